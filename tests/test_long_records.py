"""Long records: a log is thinned to every k-th row where the noise of every signal allows,
so the diagnosis's answer and its rms at the noise do not depend on the sampling rate.

The record is one ±T_N cycle of a plain linear spring plus white angle noise (nothing is
missing from a linear model), logged at several rates; `benchmarks/bench_long_record.py`
runs the same at 1,000,000 and 10,000,000 rows.
"""

from __future__ import annotations

import numpy as np
import pytest

import hdsim
from hdsim.io.decimation import MAX_ROWS, thinning_factor
from hdsim.io.measurement import make_measurement
from hdsim.signals import noise_level

K, RATED, NOISE, DURATION = 31_000.0, 87.0, 2e-6, 40.0


def _spring(rows, seed=0):
    t = np.linspace(0.0, DURATION, rows)
    torque = RATED * np.sin(2 * np.pi * t / 20.0) * np.minimum(1.0, t / 5.0)
    angle = torque / K + np.random.default_rng(seed).normal(0.0, NOISE, rows)
    return t, torque, angle


def test_a_record_short_enough_is_kept_whole():
    t, torque, angle = _spring(MAX_ROWS)
    assert thinning_factor([torque, angle]) == 1


def test_a_long_log_is_thinned_to_about_max_rows_and_keeps_its_noise():
    t, torque, angle = _spring(16 * MAX_ROWS)
    k = thinning_factor([torque, angle])
    assert k == 16
    assert noise_level(angle[::k]) == pytest.approx(noise_level(angle), rel=0.1)


def test_a_ripple_the_thinned_rows_cannot_follow_keeps_the_rows_it_needs():
    # a 10 Hz ripple of 20 µrad on the angle, logged at 4 kHz: every 160th row (25 Hz) would
    # alias it; the factor stops where the thinned angle still follows it
    t, torque, angle = _spring(160_000)
    rippled = angle + 2e-5 * np.sin(2 * np.pi * 10.0 * t)
    assert thinning_factor([torque, angle]) == 8
    k = thinning_factor([torque, rippled], max_rows=1_000)
    assert 1 < k < 160
    assert noise_level(rippled[::k]) == pytest.approx(noise_level(rippled), rel=0.1)


@pytest.mark.parametrize("rows", [MAX_ROWS, 16 * MAX_ROWS])
def test_the_same_test_at_two_sampling_rates_gives_one_answer_at_the_noise(rows):
    t, torque, angle = _spring(rows)
    meas = make_measurement("stiffness", t, torque, angle)
    result = hdsim.diagnose(meas)
    assert result.outcome == "nothing_missing" and result.added == []
    rms = result.to_json()["final"]["rmse_rad"]
    assert rms == pytest.approx(NOISE, rel=0.05)
    assert result.data["rows"] <= 2 * MAX_ROWS
    thinned = [c for c in result.checks if c["check"] == "thinned"]
    assert bool(thinned) == (rows > MAX_ROWS)
    if thinned:
        assert result.data["logged_rows"] == rows and "one row in 16 is used" in thinned[0]["message"]


# --------------------------------------------------------------------------- reading long CSV logs


def _csv(path, t, torque, angle, extra_lines=()):
    rows = [f"{float(a)!r},{float(b)!r},{float(c)!r}" for a, b, c in zip(t, torque, angle)]
    for at, line in extra_lines:
        rows.insert(at, line)
    path.write_text("# test: stiffness\n# note: bench 3 at 20 °C\ntime_s,torque_Nm,angle_rad\n" + "\n".join(rows) + "\n")
    return path


@pytest.fixture
def numeric_parser(monkeypatch):
    """The numeric parser for every body (it starts at a million characters otherwise)."""
    from hdsim.io import measurement_readers

    monkeypatch.setattr(measurement_readers, "FAST_BODY", 0)
    return measurement_readers


def test_the_numeric_parser_reads_what_the_cell_parser_reads(tmp_path, numeric_parser, monkeypatch):
    t, torque, angle = _spring(2_000)
    path = _csv(tmp_path / "log.csv", t, torque, angle)
    parsed = numeric_parser.read_measurement_file(path, None)
    raw = path.read_bytes()
    offset = raw.index(b"angle_rad\n") + len(b"angle_rad\n")  # after a head with a non-ASCII note
    fast = numeric_parser._numeric_body(raw, offset, 3)
    np.testing.assert_array_equal(fast[:, 2], angle)
    monkeypatch.setattr(numeric_parser, "FAST_BODY", 10**12)  # the cell parser only
    again = numeric_parser.read_measurement_file(path, None)
    for name in ("time_s", "torque_Nm", "angle_rad"):
        np.testing.assert_array_equal(parsed.data[name], again.data[name])
    np.testing.assert_array_equal(parsed.data["angle_rad"], angle)


@pytest.mark.parametrize("bad, message", [
    ((1500, "1.0,2.0"), "line 1504: 2 cells; expected 3"),  # 3 head lines, then row 1501 is line 1504
    ((1500, "1.0,x,2.0"), "line 1504, column 'torque_Nm': 'x' is not a number"),
    ((1500, "#late"), "line 1504: '#' line after the header"),
])
def test_a_long_log_with_a_bad_line_is_refused_naming_that_line(tmp_path, numeric_parser, bad, message):
    from hdsim.errors import InputError

    t, torque, angle = _spring(2_000)
    path = _csv(tmp_path / "log.csv", t, torque, angle, extra_lines=[bad])
    with pytest.raises(InputError, match=message):
        numeric_parser.read_measurement_file(path, None)


def test_a_nan_and_a_blank_line_in_a_long_log_keep_their_line_numbers(tmp_path, numeric_parser):
    from hdsim.errors import InputError

    t, torque, angle = _spring(2_000)
    time_back = t.copy()
    time_back[1200] = time_back[1198]  # time stands still at row 1201 (line 1204)
    path = _csv(tmp_path / "log.csv", time_back, torque, angle, extra_lines=[(10, "")])  # a blank line 14
    with pytest.raises(InputError, match="line 1205"):  # one line further down after the blank
        numeric_parser.read_measurement_file(path, None)
    nan = angle.copy()
    nan[700] = np.nan
    path = _csv(tmp_path / "nan.csv", t, torque, nan)
    with pytest.raises(InputError, match="line 704"):
        numeric_parser.read_measurement_file(path, None)


def test_a_breakaway_log_is_fitted_whole():
    """A start from rest is a transient of a few rows; the noise check, a median, would not
    see it thinned away, so a breakaway record keeps every row."""
    import truth_breakaway

    from hdsim.identification.breakaway import BreakawayTest
    from hdsim.identification.workflow import prepare_record
    from hdsim.io.measurement import make_measurement as make

    assert not BreakawayTest.thinnable
    cols, meta, _ = truth_breakaway.make_breakaway_data(seed=207)  # logged at 1 kHz
    rows = len(cols["time_s"])
    assert rows > 2 * MAX_ROWS  # long enough that a twist or sweep record would be thinned
    meas = make("breakaway", cols["time_s"], cols["torque_Nm"], None, wg_angle=cols["wg_angle_rad"],
                ratio=float(meta["ratio"]))
    prepared, checks, data, _, _ = prepare_record(meas)
    assert len(prepared) == rows and "logged_rows" not in data
    assert not [c for c in checks if c["check"] == "thinned"]
