"""Import options for real bench logs (docs/measurements.md, "Bringing your own bench log"):
the ``#`` keys a log lacks, ``FACTOR*column``, revolutions, NaN rows, a time window, runs
whose clock restarts and logs without a clock. Expected values are written from the
file each test builds, not from the reader."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hdsim.errors import InputError
from hdsim.io.import_options import ImportOptions, parse_meta, parse_window, split_factor


def test_window_and_meta_strings():
    assert parse_window("2.5:40") == (2.5, 40.0)
    assert parse_window("5:") == (5.0, math.inf) and parse_window(":20") == (-math.inf, 20.0)
    for bad in ("5", "a:b", "9:3", "nan:1"):
        with pytest.raises(InputError, match="--window"):
            parse_window(bad)
    assert parse_meta(["torque_side=output", "operator = J. Doe"]) == {"torque_side": "output",
                                                                       "operator": "J. Doe"}
    for bad in ("novalue", "=x", "a:b=c"):
        with pytest.raises(InputError, match="--meta"):
            parse_meta([bad])


def test_factor_sources():
    assert split_factor("5.11*iq_A") == ("iq_A", 5.11)
    assert split_factor("-1e-3 * pos counts") == ("pos counts", -1e-3)
    assert split_factor("iq_A") == ("iq_A", 1.0)
    assert split_factor("a*b") == ("a*b", 1.0)  # not a number in front: a plain name
    with pytest.raises(InputError, match="factor"):
        split_factor("0*iq_A")
    for factor in ("inf", "-Infinity", "NaN"):  # refused as factors, not looked for as a column 'inf*iq_A'
        with pytest.raises(InputError, match="the factor must be a finite non-zero number"):
            split_factor(f"{factor}*iq_A")
    assert split_factor("Info*2") == ("Info*2", 1.0)


def test_options_refuse_nonsense():
    with pytest.raises(InputError, match="ratio"):
        ImportOptions(ratio=0.0)
    with pytest.raises(InputError, match="rated_torque"):
        ImportOptions(rated_torque=-3.0)
    with pytest.raises(InputError, match="window"):
        ImportOptions(window=(3.0, 1.0))
    keys = ImportOptions(test="stiffness", ratio=-50, rated_torque=16, meta={"torque_side": "output"}).overrides()
    assert keys == {"torque_side": "output", "test": "stiffness", "ratio": "-50.0", "rated_torque_Nm": "16.0"}


def test_a_window_side_may_be_open_and_every_bad_keyword_is_named(tmp_path):
    """window=(None, T1) is the API's '--window :T1'; a bad value is one InputError naming its
    keyword, never a TypeError or ValueError from inside (or an unknown option it is not)."""
    from hdsim.io.measurement import load_measurement

    assert ImportOptions(window=(None, 5)).window == (-math.inf, 5.0)
    assert ImportOptions(window=[2.5, None]).window == (2.5, math.inf)
    t, torque, twist = _twist_rows()
    path = _log(tmp_path, ["time_s", "torque_Nm", "angle_rad"], [[_num(a), _num(b), _num(c)]
                                                                 for a, b, c in zip(t, torque, twist)])
    meas = load_measurement(path, test="stiffness", window=(None, 0.3))
    assert meas.time[-1] <= 0.3 and meas.rows.windowed_rows == int(np.sum(t > 0.3))
    bad = {"window": [(1.0,), "1:5", (1.0, "5"), (5.0, 1.0)], "meta": [["torque_side=output"]],
           "drop_nan": ["yes"], "ratio": [True], "test": [3]}
    for keyword, values in bad.items():
        for value in values:
            with pytest.raises(InputError, match=f"^{keyword}: "):
                load_measurement(path, **{"test": "stiffness", keyword: value})
    with pytest.raises(InputError, match="unknown import option 'windw'; known: .*window"):
        load_measurement(path, test="stiffness", windw=(0, 1))


def _num(x) -> str:
    return repr(float(x))


def _log(tmp_path, header, rows, name="log.csv"):
    path = tmp_path / name
    path.write_text(",".join(header) + "\n" + "".join(",".join(r) + "\n" for r in rows))
    return path


def _twist_rows(n=40, restart_every=None):
    """A stiffness log as drive software writes it: time, motor current [A] (5.11 N·m/A at
    the output), output position in revolutions; the clock may restart."""
    t = np.arange(n) * 0.01
    if restart_every:
        t = t % (restart_every * 0.01)
    torque = 20.0 * np.sin(np.linspace(0, 2 * np.pi, n))
    twist = torque / 3.0e4 + 0.25  # rad, with an encoder offset
    return t, torque, twist


def test_a_drive_log_is_read_without_editing(tmp_path):
    from hdsim.io.measurement import load_measurement

    t, torque, twist = _twist_rows()
    rows = [[_num(a), _num(b / 5.11), _num(c / (2 * np.pi))] for a, b, c in zip(t, torque, twist)]
    rows[7][1] = "nan"      # a failed current read
    rows[12][2] = ""        # a failed encoder read
    path = _log(tmp_path, ["t", "iq_A", "pos"], rows)
    with pytest.raises(InputError, match="test"):  # no '# test' key and no option: refused
        load_measurement(path, {"time_s": "t", "torque_Nm": "5.11*iq_A", "angle_rev": "pos"})
    meas = load_measurement(path, {"time_s": "t", "torque_Nm": "5.11*iq_A", "angle_rev": "pos"},
                            test="stiffness", rated_torque=67.0, drop_nan=True, window=(0.05, 0.3))
    keep = [i for i in range(len(t)) if 0.05 <= t[i] <= 0.3 and i not in (7, 12)]
    np.testing.assert_allclose(meas.time, t[keep])
    np.testing.assert_allclose(meas.torque, torque[keep], rtol=1e-12)
    np.testing.assert_allclose(meas.angle, twist[keep], rtol=1e-12)
    assert meas.rows.dropped_rows == 2 and meas.rows.windowed_rows == len(t) - 26
    assert meas.test == "stiffness" and meas.rated_torque == 67.0 and meas.meta["test"] == "stiffness"


def test_concatenated_runs_and_logs_without_a_clock(tmp_path):
    from hdsim.io.measurement import load_measurement

    t, torque, twist = _twist_rows(n=30, restart_every=10)  # three runs of 10 rows, clock 0 … 0.09 s each
    rows = [[_num(a), _num(b), _num(c)] for a, b, c in zip(t, torque, twist)]
    path = _log(tmp_path, ["time_s", "torque_Nm", "angle_rad"], rows)
    with pytest.raises(InputError, match="concatenated=True joins them"):
        load_measurement(path, test="stiffness")
    meas = load_measurement(path, test="stiffness", concatenated=True)
    np.testing.assert_allclose(meas.time, np.arange(30) * 0.01, atol=1e-12)  # each run one step after the last
    assert meas.rows.runs == 3
    steps = _log(tmp_path, ["torque_Nm", "angle_deg"], [[_num(b), _num(np.degrees(c))] for b, c in
                                                         zip(torque, twist)], "steps.csv")
    with pytest.raises(InputError, match="sample_rate=HZ"):
        load_measurement(steps, test="stiffness")
    meas = load_measurement(steps, test="stiffness", sample_rate=2.0)
    np.testing.assert_allclose(meas.time, np.arange(30) / 2.0)
    np.testing.assert_allclose(meas.angle, twist, rtol=1e-12)
    assert meas.rows.time_from_rows


def test_the_cli_reads_a_log_with_the_import_options(tmp_path, cli):
    import json

    t, torque, twist = _twist_rows(n=60)
    rows = [[_num(a), _num(b / 5.11), _num(c / (2 * np.pi))] for a, b, c in zip(t, torque, twist)]
    rows[3][1] = "NaN"
    path = _log(tmp_path, ["t", "iq_A", "pos"], rows)
    code, out, err = cli("fit", path, "--columns", "time_s=t,torque_Nm=5.11*iq_A,angle_rev=pos", "--test",
                         "stiffness", "--rated-torque", "87", "--drop-nan", "--meta", "operator=bench 2",
                         "--out", tmp_path / "f.toml", "--json")
    assert code == 0, err
    summary = json.loads(out)
    assert summary["data"]["rows"] == 59 and summary["data"]["dropped_rows"] == 1
    # the linear fit of an elastic record gives its stiffness back
    assert summary["fitted"]["stiffness.K0"] == pytest.approx(3.0e4, rel=1e-3)
    code, out, err = cli("fit", path, "--columns", "time_s=t,torque_Nm=5.11*iq_A,angle_rev=pos", "--test",
                         "stiffness", "--json")
    assert code == 2 and "nan" in err.lower() and "--drop-nan" in err
    assert len(err.strip().splitlines()) == 1


_TEXT = st.text(alphabet=st.characters(codec="utf-8"), max_size=20)
_NUMBER_TEXT = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr), st.integers().map(str), _TEXT)


# 200 generated cases (was 300): the four parsers are small, and every kind of text (window,
# meta, factor, numbers) is still drawn many times over
@settings(max_examples=200, deadline=None, derandomize=True, database=None)
@given(window=st.one_of(_TEXT, st.tuples(_NUMBER_TEXT, _NUMBER_TEXT).map(":".join)),
       meta=st.lists(st.one_of(_TEXT, st.tuples(_TEXT, _TEXT).map("=".join)), max_size=3),
       source=st.one_of(_TEXT, st.tuples(_NUMBER_TEXT, _TEXT).map("*".join)),
       numbers=st.tuples(*[st.one_of(st.none(), st.floats(allow_nan=True, allow_infinity=True))] * 3))
def test_import_option_strings_end_in_a_value_or_one_clear_line(window, meta, source, numbers):
    """Generated --window, --meta, FACTOR*column and option values: a value or an InputError."""
    for parse, text in ((parse_window, window), (parse_meta, meta), (split_factor, source)):
        try:
            parse(text)
        except InputError as exc:
            assert str(exc) and "\n" not in str(exc)
    try:
        ImportOptions(ratio=numbers[0], rated_torque=numbers[1], sample_rate=numbers[2])
    except InputError as exc:
        assert str(exc)


def test_the_library_names_keywords_and_the_cli_its_flags():
    """A Python caller is told the keyword (drop_nan=True), arrays are mended by the caller, and
    the command line says the flag (--drop-nan) of the same message."""
    from hdsim.cli._import_arguments import cli_words
    from hdsim.io.measurement import make_measurement

    t = np.arange(20.0)
    torque = np.sin(t)
    torque[3] = np.nan
    with pytest.raises(InputError, match=r"\(1 such rows; drop those rows from the arrays\)$") as arrays:
        make_measurement("stiffness", t, torque, 1e-4 * torque)
    assert "--" not in str(arrays.value) and "drop_nan" not in str(arrays.value)
    assert cli_words("run.csv: x (1 such rows; a log's failed reads are dropped with drop_nan=True)") == \
        "run.csv: x (1 such rows; a log's failed reads are dropped with --drop-nan)"
    assert cli_words("no time column; give its name with columns={'time_s': NAME}, or ... sample_rate=HZ") == \
        "no time column; give its name with --columns time_s=NAME, or ... --sample-rate HZ"
    assert cli_words("rated_torque: must be positive") == "--rated-torque: must be positive"
