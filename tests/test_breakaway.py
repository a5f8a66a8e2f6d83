"""The breakaway (starting-torque) test kind: the starting torque of each direction, the
families a breakaway can show, and records that are not breakaways (or are, under
another name).

Truth: ``tests/truth_breakaway.py`` (its own integrator and stick/slip logic, a decay
after breakaway that is not hdsim's; imports nothing from hdsim). The battery over many
seeds is ``validation/breakaway_battery.py``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import truth
import truth_breakaway as tb
from hdsim import diagnose, fit
from hdsim.io.measurement import make_measurement
from hdsim.signals import breakaway_episodes


def _measurement(cols, meta, test="breakaway"):
    return make_measurement(test, cols["time_s"], cols["torque_Nm"], cols.get("output_angle_rad"),
                            wg_angle=cols.get("wg_angle_rad"), ratio=meta["ratio"],
                            meta={"torque_side": meta["torque_side"]})


def test_the_onset_of_a_hand_built_start_is_where_the_angle_left_its_rest():
    # the torque rises at 0.1 N·m/s from 0; the shaft leaves its rest at t = 3 s (0.3 N·m) and
    # turns at 2 rad/s; an encoder of 1e-3 rad: the torque at the onset is 0.3 N·m within a step
    t = np.arange(0.0, 5.0, 1e-3)
    torque = 0.1 * np.minimum(t, 3.0)
    angle = np.round(np.where(t > 3.0, 2.0 * (t - 3.0), 0.0) / 1e-3) * 1e-3
    (start,) = breakaway_episodes(t, angle, torque)
    assert start.direction == 1
    assert t[start.onset] == pytest.approx(3.0, abs=2e-3)
    # the mean of the last 20 ms at rest: 0.3 minus half their rise (0.001 N·m), within its uncertainty
    assert start.torque == pytest.approx(0.3 - 0.001, abs=2e-4)
    assert start.uncertainty < 2e-3
    assert start.held_torque == pytest.approx(0.3, rel=0.02)


@pytest.mark.parametrize("seed, overrides", [(1, {"shape": "ramp"}), (4, {"shape": "steps"}),
                                             (2, {"torque_side": "output"}), (5, {"directions": ("forward",)})])
def test_the_starting_torque_of_each_direction_is_within_ten_percent_of_the_truth(seed, overrides):
    cols, meta, tr = tb.make_breakaway_data(("friction", "asymmetry"), seed=seed, **overrides)
    metrics = fit(_measurement(cols, meta)).metrics()
    for way in ("forward", "reverse"):
        want, got = tr[f"starting_torque_{way}_Nm"], metrics[f"starting_torque_{way}_Nm"]
        if want is None:  # a direction never started: null, not a number
            assert got is None and metrics[f"starting_torque_{way}_uncertainty_Nm"] is None
            continue
        assert got == pytest.approx(want, rel=0.10)
        # the stated uncertainty covers the error at about three standard uncertainties
        assert abs(got - want) < 4 * metrics[f"starting_torque_{way}_uncertainty_Nm"] + 0.01 * want


@pytest.mark.parametrize("hidden, seed", [((), 3), (("asymmetry",), 3), (("friction",), 1),
                                          (("asymmetry", "friction"), 1)])
def test_the_hidden_family_is_found_and_nothing_else(hidden, seed):
    cols, meta, _ = tb.make_breakaway_data(hidden, seed=seed)
    result = diagnose(_measurement(cols, meta))
    assert set(result.added) == set(hidden)
    assert result.outcome == ("found" if hidden else "nothing_missing")


def test_a_one_direction_record_says_what_it_cannot_tell():
    cols, meta, _ = tb.make_breakaway_data(("friction",), seed=0, directions=("forward",))
    result = diagnose(_measurement(cols, meta))
    checks = {c["check"]: c for c in result.checks}
    assert checks["both_directions"]["status"] == "warn"
    assert "asymmetry" not in result.added


def test_a_breakaway_labelled_stiffness_is_the_wrong_test_and_a_locked_record_is_no_breakaway():
    cols, meta, _ = tb.make_breakaway_data(("friction",), seed=0, torque_side="output")
    as_stiffness = diagnose(make_measurement("stiffness", cols["time_s"], cols["torque_Nm"],
                                             cols["output_angle_rad"], ratio=100))
    assert as_stiffness.outcome == "wrong_test" and "breakaway" in as_stiffness.to_json()["verdict"]
    locked, _ = truth.make_stiffness_data({"friction"}, set(), seed=3, n_rows=600)
    as_breakaway = diagnose(make_measurement("breakaway", locked["time_s"], locked["torque_Nm"],
                                             locked["angle_rad"], ratio=100))
    assert as_breakaway.outcome == "wrong_test" and "never started from rest" in as_breakaway.to_json()["verdict"]
    assert as_breakaway.to_json()["verdict"].count("not a breakaway test") == 1  # it was said twice
    # and a real locked record is not taken for a breakaway (its checks find no slip)
    from hdsim.identification.workflow import examine_record

    held = make_measurement("stiffness", locked["time_s"], locked["torque_Nm"], locked["angle_rad"], rated_torque=87.0)
    assert examine_record(held)[2] == ""


def test_cli_fit_json_gives_the_contract_metrics_beside_the_catalog(tmp_path, cli):
    cols, meta, tr = tb.make_breakaway_data(("asymmetry",), seed=2, torque_side="output")
    tb.write_csv(tmp_path / "ramp.csv", cols, meta)
    code, out, err = cli("fit", "ramp.csv", "--json", "--report", "fitrep", cwd=tmp_path)
    assert code == 0, err
    metrics = json.loads(out)["metrics"]
    # the page gives each direction's measured starting torque with its uncertainty (it gave
    # only the fitted level, which is neither direction)
    page = (tmp_path / "fitrep" / "index.md").read_text()
    for way in ("forward", "reverse"):  # read back from the page, not formatted by the page's own rounding
        row = next(line for line in page.splitlines() if line.startswith(f"| {way} | "))
        value, sigma = (float(x) for x in row.split("|")[2].split("±"))
        assert value == pytest.approx(metrics[f"starting_torque_{way}_Nm"], rel=0.02)
        assert sigma == pytest.approx(metrics[f"starting_torque_{way}_uncertainty_Nm"], rel=0.1)
    assert "## Starting torque, measured (the file's shaft)" in page
    for way in ("forward", "reverse"):
        assert metrics[f"starting_torque_{way}_Nm"] == pytest.approx(tr[f"starting_torque_{way}_Nm"], rel=0.1)
    # the catalog's starting torque of the default unit, referred to the output shaft of the file
    assert metrics["catalog_starting_torque_Nm"] == pytest.approx(100 * 0.069, rel=0.2)
    code, out, err = cli("diagnose", "ramp.csv", "--json", "--report", "rep")
    assert code == 0, err
    assert json.loads(out)["added"] == ["asymmetry"]
    assert (tmp_path / "rep" / "index.html").read_text().count("data:image/png;base64,") >= 2


def test_the_fitted_drive_breaks_away_at_the_measured_level(tmp_path):
    cols, meta, tr = tb.make_breakaway_data(("friction",), seed=1)
    result = fit(_measurement(cols, meta), "friction")
    saved = result.save(str(tmp_path / "b.fit.toml"))  # a Path, as every fit's save returns
    assert saved == tmp_path / "b.fit.toml" and saved.read_text().startswith("# hdsim breakaway fit")
    law = result.drive.input_friction
    assert law.starting_torque == pytest.approx(tr["T_s"]["forward"], rel=0.05)
    assert law.coulomb_torque == pytest.approx(tr["T_c"]["forward"], rel=0.15)


def test_a_breakaway_labelled_a_friction_sweep_is_the_wrong_test():
    # its short runs after breakaway can look like plateaus; the torque raised over seconds at
    # rest before every start cannot (a sweep's speed loop breaks free in a blink)
    cols, meta, _ = tb.make_breakaway_data(("friction",), seed=1)
    result = diagnose(make_measurement("running_torque", cols["time_s"], cols["torque_Nm"], None,
                                       wg_angle=cols["wg_angle_rad"], ratio=100))
    assert result.outcome == "wrong_test" and "breakaway" in result.to_json()["verdict"]
