"""A battery of logs with the habits of real bench software, each with its expected end.

Every file starts from an independent truth record (tests/truth.py, which shares no code
with hdsim) and is written the way drive software and DAQ programs write: no ``#`` keys,
torque from motor current with 5-20 % noise, the output angle in revolutions or from the
rotor encoder, NaN cells, runs whose clock restarts, step tests without a clock, one
loading rate, stick-slip jumps, a saturated current, a friction sweep labelled as a
stiffness test, torque in amperes. Each must end in exit 0 or 2 (never a traceback or
exit 1): refused with the sentence that says what to do, or accepted with the warning
that says what is odd, or the outcome that says what it is.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import truth

K_T = 5.11  # N·m per A at the output (torque constant × ratio)
RATIO = 100.0


@pytest.fixture(scope="module")
def record():
    """A ±T_N locked test of a CSG-25-100-like drive, two loading rates, 1200 rows."""
    cols, _ = truth.make_stiffness_data({"friction", "hardening"}, set(), seed=11, n_rows=1200)
    return cols


def _write(path, header, columns, every=1):
    rows = zip(*[np.asarray(c)[::every] for c in columns])
    text = ",".join(header) + "\n" + "".join(",".join("nan" if not np.isfinite(v) else repr(float(v)) for v in row)
                                             + "\n" for row in rows)
    path.write_text(text)
    return path


def _current(torque, share, seed=0):
    """Motor current [A] for a torque, with noise of ``share`` of the torque swing."""
    noise = np.random.default_rng(seed).normal(0.0, share * np.ptp(torque), np.size(torque))
    return (torque + noise) / K_T


def _run(cli, cwd, *args):
    code, out, err = cli(*map(str, args), cwd=cwd)  # the fitted file (--out) lands in cwd
    assert code in (0, 2), err  # never a traceback, never the program's own failure
    if code == 2:
        assert len(err.strip().splitlines()) == 1 and out == "", err
    return code, (json.loads(out) if code == 0 and out else None), err


def _checks(summary):
    return {c["check"]: c for c in summary["checks"]}


FIT = ("--json", "--out", "f.toml")
MAP = "time_s=t,torque_Nm={k}*iq_A,angle_rev=pos_rev"


def test_current_torque_and_revolutions_with_the_options(record, tmp_path, cli):
    path = _write(tmp_path / "drive.csv", ["t", "iq_A", "pos_rev"],
                  [record["time_s"], _current(record["torque_Nm"], 0.05), record["angle_rad"] / (2 * math.pi)])
    code, _, err = _run(cli, tmp_path, "fit", path, *FIT)
    assert code == 2 and "--test" in err  # no keys: told which option gives the key
    code, summary, err = _run(cli, tmp_path, "fit", path, "--test", "stiffness", "--columns", MAP.format(k=K_T), *FIT)
    assert code == 0
    assert all(c["status"] != "fail" for c in summary["checks"])
    assert _checks(summary)["torque_noise"]["status"] in ("ok", "warn")
    # the stiffness of a linear fit is the truth's K1 within the hardening's spread, not 5× off
    assert 0.5 < summary["derived"]["K0_Nm_per_rad"] / truth.K1_NM_PER_RAD < 2.0


def test_torque_in_amperes_is_named_implausible(record, tmp_path, cli):
    path = _write(tmp_path / "amps.csv", ["time_s", "torque_Nm", "angle_rad"],
                  [record["time_s"], record["torque_Nm"] / K_T / 2.0, record["angle_rad"]])
    code, summary, _ = _run(cli, tmp_path, "fit", path, "--test", "stiffness", *FIT)
    assert code == 0 and _checks(summary)["stiffness"]["status"] == "warn"


def test_rotor_encoder_not_divided_by_the_ratio_is_a_wrong_test(record, tmp_path, cli):
    path = _write(tmp_path / "rotor.csv", ["time_s", "torque_Nm", "angle_rad"],
                  [record["time_s"], record["torque_Nm"], record["angle_rad"] * RATIO * 20])
    code, _, err = _run(cli, tmp_path, "fit", path, "--test", "stiffness", *FIT)
    assert code == 2 and "rotor side" in err
    code, summary, _ = _run(cli, tmp_path, "diagnose", path, "--test", "stiffness", "--json")
    assert code == 0 and summary["outcome"] == "wrong_test" and summary["added"] == []


def test_nan_cells_are_refused_then_dropped_and_counted(record, tmp_path, cli):
    torque = np.array(record["torque_Nm"], dtype=float)
    torque[[40, 41, 300]] = np.nan
    path = _write(tmp_path / "nan.csv", ["time_s", "torque_Nm", "angle_rad"],
                  [record["time_s"], torque, record["angle_rad"]])
    code, _, err = _run(cli, tmp_path, "fit", path, "--test", "stiffness", *FIT)
    assert code == 2 and "--drop-nan" in err
    code, summary, _ = _run(cli, tmp_path, "fit", path, "--test", "stiffness", "--drop-nan", *FIT)
    assert code == 0 and summary["data"]["dropped_rows"] == 3 and summary["data"]["rows"] == 1197


def test_concatenated_runs_and_a_log_without_a_clock(record, tmp_path, cli):
    n = len(record["time_s"]) // 3
    t = np.concatenate([record["time_s"][:n]] * 3)
    path = _write(tmp_path / "runs.csv", ["time_s", "torque_Nm", "angle_rad"],
                  [t, record["torque_Nm"][:3 * n], record["angle_rad"][:3 * n]])
    code, _, err = _run(cli, tmp_path, "fit", path, "--test", "stiffness", *FIT)
    assert code == 2 and "--concatenated" in err
    code, summary, _ = _run(cli, tmp_path, "fit", path, "--test", "stiffness", "--concatenated", *FIT)
    assert code == 0 and _checks(summary)["concatenated_runs"]["message"].startswith("3 runs")
    steps = _write(tmp_path / "steps.csv", ["torque_Nm", "angle_arcsec"],
                   [record["torque_Nm"], np.degrees(record["angle_rad"]) * 3600.0], every=20)
    code, _, err = _run(cli, tmp_path, "fit", steps, "--test", "stiffness", *FIT)
    assert code == 2 and "--sample-rate" in err
    code, summary, _ = _run(cli, tmp_path, "fit", steps, "--test", "stiffness", "--sample-rate", "1", *FIT)
    assert code == 0 and _checks(summary)["time_axis"]["status"] == "warn"


def test_one_loading_rate_and_a_saturated_current_are_warned(tmp_path, cli):
    cols, _ = truth.make_stiffness_data({"friction"}, set(), seed=12, n_rows=800, quarter_s=(1.0,))
    current = np.clip(_current(cols["torque_Nm"], 0.0), -12.0, 12.0)  # the amplifier's limit, 61 N·m
    path = _write(tmp_path / "limit.csv", ["t", "iq_A", "pos_rev"],
                  [cols["time_s"], current, cols["angle_rad"] / (2 * math.pi)])
    code, summary, _ = _run(cli, tmp_path, "fit", path, "--test", "stiffness", "--columns", MAP.format(k=K_T), *FIT)
    assert code == 0
    checks = _checks(summary)
    assert checks["loading_rates"]["status"] == "warn" and checks["saturation"]["status"] == "warn"


def test_a_friction_sweep_labelled_stiffness_is_not_found_or_improved(tmp_path, cli):
    t = np.linspace(0.0, 40.0, 1600)
    angle = np.radians(80.0) * np.abs((t / 10.0) % 2.0 - 1.0)  # output turning at constant speed each way
    torque = 1.2 * np.sign(np.gradient(angle, t)) + 0.3 * np.sin(angle * 2 * RATIO)
    path = _write(tmp_path / "sweep.csv", ["t", "iq_A", "pos_rev"],
                  [t, _current(torque, 0.2), angle / (2 * math.pi)])
    code, summary, _ = _run(cli, tmp_path, "diagnose", path, "--test", "stiffness", "--columns", MAP.format(k=K_T), "--json")
    assert code == 0 and summary["outcome"] == "wrong_test"


def test_stick_slip_jumps_are_analysed_not_refused(record, tmp_path, cli):
    angle = np.array(record["angle_rad"], dtype=float)
    jumps = np.zeros_like(angle)
    jumps[::97] = 5e-6 * np.random.default_rng(3).standard_normal(jumps[::97].size)  # slips that stay
    path = _write(tmp_path / "slip.csv", ["time_s", "torque_Nm", "angle_rad"],
                  [record["time_s"], record["torque_Nm"], angle + np.cumsum(jumps)])
    code, summary, _ = _run(cli, tmp_path, "fit", path, "--test", "stiffness", *FIT)
    assert code == 0 and all(c["status"] != "fail" for c in summary["checks"])


def test_the_answer_does_not_depend_on_the_unit_named(record):
    """The fit starts from what the record says (loading slope, loop width, step), not from
    the unit: the smallest and the largest built-in unit give the same friction and stiffness."""
    from hdsim.identification.fit import fit
    from hdsim.io.measurement import make_measurement

    every = slice(None, None, 3)  # 400 rows are enough to tell
    meas = make_measurement("stiffness", record["time_s"][every], record["torque_Nm"][every],
                            record["angle_rad"][every])
    small, large = (fit(meas, ["friction", "hardening"], unit=u) for u in ("CSG-14-100", "CSG-32-100"))
    for name, value in small.internal.items():
        assert large.internal[name] == pytest.approx(value, rel=1e-3), name


def test_the_whole_workflow_from_python_is_what_the_command_prints(record, tmp_path, cli, monkeypatch):
    """Contracts §6 from Python on a log with a current-derived torque and the output in
    revolutions: the import options as keywords, then `hdsim.diagnose` with the outcome,
    the checks, the next measurement, the JSON of ``--json`` and the report page.

    The command reads the file with its own options and asks for the same diagnosis; it
    gets the Python one (after checking it read the same samples and asked with the same
    arguments) instead of running the deterministic procedure a second time."""
    import hdsim
    from hdsim.identification import workflow
    from hdsim.identification.fit import parse_effects

    path = _write(tmp_path / "drive.csv", ["t", "iq_A", "pos_rev"],
                  [record["time_s"], _current(record["torque_Nm"], 0.05), record["angle_rad"] / (2 * math.pi)])
    columns = {"time_s": "t", "torque_Nm": f"{K_T}*iq_A", "angle_rev": "pos_rev"}
    meas = hdsim.load_measurement(path, columns=columns, test="stiffness")
    result = hdsim.diagnose(meas, effects="friction")
    assert result.outcome in ("found", "improved", "nothing_missing", "cannot_decide")
    assert "hardening" in result.added and result.ranking[0].family == "hardening"
    assert {c["check"] for c in result.checks} >= {"torque_noise", "plausibility"} or any(
        c["check"] == "stiffness" for c in result.checks)
    assert isinstance(result.next_measurement, str)
    page = result.report(tmp_path / "report")
    assert page.name == "index.html" and page.exists()
    j = result.to_json()
    assert j["outcome"] == result.outcome and j["checks"] == result.checks and j["report"] == str(page)
    asked = []

    def shared_diagnose(measurement, effects=None, *, unit=None, families=None, candidates=None,
                        max_rounds=None, max_steps=None, log=None):
        assert measurement.test == meas.test and effects == parse_effects("friction")  # --effects friction, parsed
        assert (unit, families, candidates, max_rounds, max_steps) == (None,) * 5  # hdsim.diagnose's defaults
        for name in ("time", "torque", "angle"):  # the command read the file as Python did
            np.testing.assert_array_equal(getattr(measurement, name), getattr(meas, name), err_msg=name)
        assert measurement.rated_torque == meas.rated_torque and measurement.ratio == meas.ratio
        asked.append(measurement.source)
        return result

    monkeypatch.setattr(workflow, "diagnose", shared_diagnose)
    code, printed, err = _run(cli, tmp_path, "diagnose", path, "--test", "stiffness", "--columns",
                              MAP.format(k=K_T), "--effects", "friction", "--json")
    assert code == 0
    assert len(asked) == 1
    for key in ("test", "outcome", "next_measurement", "added", "ambiguous", "checks", "data"):
        assert printed[key] == j[key], key
    assert [c["family"] for c in printed["ranking"]] == [c["family"] for c in j["ranking"]]
    assert printed["final"]["effects"] == j["final"]["effects"]
    assert printed["final"]["rmse_rad"] == pytest.approx(j["final"]["rmse_rad"], rel=1e-9)
