"""The input friction is part of the drive: parameters, scenario overrides, a fitted sweep's drive, a study.

`HarmonicDrive.input_friction` is the running-torque law of the wave-generator shaft; its
scalar fields are the parameters ``input_friction.<field>``; a driven scenario runs it with
its ``[input_friction]`` table on top; `RunningFit.drive` carries a fitted law; and
``hdsim.sobol`` studies it like any other parameter.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from truth_running import RATIO, make_running_data

import hdsim
from hdsim.errors import InputError
from hdsim.identification.running_fit import fit_running
from hdsim.io.measurement import make_measurement
from hdsim.model.input_friction import NO_INPUT_FRICTION, InputFriction, catalog_friction, for_unit
from hdsim.scenarios.driven import bench_from_scenario

RPM = math.pi / 30.0  # [rad/s per rpm]
#: a short friction sweep (two speeds, one measured WG turn each way): ~0.5 s a run
SHORT_SWEEP = {"metrics": ["running_torque_sweep"], "input.speeds_rpm": [500.0, 2000.0],
               "input.revolutions": 1.0, "input.settle_revolutions": 0.25}
#: a law without ripple, so the mean torque over one WG turn is the closed form
PLAIN = InputFriction(starting_torque=0.08, coulomb_torque=0.05, viscous=1.5e-4, stribeck_speed=3.0,
                      load_coefficient=0.1)
FIELDS = ("starting_torque", "coulomb_torque", "viscous", "stribeck_speed", "velocity_scale",
          "coulomb_asymmetry", "load_coefficient")


def short_sweep(**updates):
    return hdsim.load_scenario("running_torque").with_updates({**SHORT_SWEEP, **updates})


# --------------------------------------------------------------------------- parameters


def test_the_drive_carries_the_catalog_law_and_lists_its_fields_as_parameters():
    drive = hdsim.load_unit("CSG-20-100")
    law = drive.input_friction
    assert law.starting_torque == catalog_friction(drive).starting_torque == 0.037  # the catalog row
    assert law.ripple_amplitudes == catalog_friction(drive).ripple_amplitudes
    params = drive.params()
    assert {f"input_friction.{f}" for f in FIELDS} <= set(params)
    assert params["input_friction.load_coefficient"] == law.load_coefficient
    info = drive.param_info("input_friction.viscous")
    assert info["unit"] == "N·m·s/rad" and info["bounds"] == (0.0, math.inf)


def test_with_updates_sets_input_friction_parameters_as_numbers_or_a_batch():
    drive = hdsim.load_unit()
    changed = drive.with_updates({"input_friction.coulomb_torque": 0.06, "flexspline.h_c": 0.6e-3})
    assert changed.input_friction.coulomb_torque == 0.06
    assert changed.input_friction.viscous == drive.input_friction.viscous  # the rest of the law stays
    assert changed.input_friction.ripple_orders == drive.input_friction.ripple_orders
    assert drive.input_friction.coulomb_torque != 0.06  # a new drive, the old one unchanged
    batch = drive.with_updates({"input_friction.viscous": [1e-4, 2e-4, 3e-4]})
    assert batch.batch_size == 3 and batch.input_friction.batch_size == 3
    assert batch.input_friction.sample(1).viscous == 2e-4
    assert batch.with_updates({"input_friction.viscous": 1e-4}).batch_size == 1


@pytest.mark.parametrize("updates, needle", [
    ({"input_friction.nope": 1.0}, "unknown parameter 'input_friction.nope'"),
    ({"input_friction.viscous": -1e-4}, "input_friction.viscous must be a finite number >= 0, got -0.0001"),
    ({"input_friction.stribeck_speed": 0.0}, "input_friction.stribeck_speed must be a finite number > 0, got 0"),
    ({"input_friction.coulomb_torque": "lots"}, "input_friction.coulomb_torque must be a number"),
    ({"input_friction.coulomb_asymmetry": math.inf},
     "input_friction.coulomb_asymmetry must be a finite number, got inf"),
    ({"input_friction.viscous": [1e-4, math.nan]}, "input_friction.viscous must be a finite number >= 0, got nan"),
])
def test_a_bad_input_friction_parameter_is_one_input_error(updates, needle):
    with pytest.raises(InputError, match=needle.replace(".", r"\.")) as err:
        hdsim.load_unit().with_updates(updates)
    assert "\n" not in str(err.value)


def test_an_unknown_input_friction_parameter_exits_2_from_the_cli(cli, tmp_path):
    code, out, err = cli("simulate", "running_torque", "--set", "input_friction.nope=1", "--out", tmp_path / "o")
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "unknown parameter 'input_friction.nope'" in lines[0]
    assert not (tmp_path / "o").exists()


# --------------------------------------------------------------------------- the scenario's table


def test_a_scenario_table_is_applied_on_top_of_the_drive_law():
    drive = hdsim.load_unit().with_input_friction(PLAIN)
    assert for_unit(drive) is PLAIN  # no table: the drive's law itself
    viscous = for_unit(drive, {"viscous_Nms": 4e-4, "ripple_orders": [2.0], "ripple_amplitudes": [0.1],
                               "ripple_phases": [0.0]})
    assert viscous.viscous == 4e-4 and viscous.ripple_amplitudes == (0.1,)
    assert (viscous.coulomb_torque, viscous.starting_torque, viscous.load_coefficient) == (0.05, 0.08, 0.1)
    # a catalog key re-derives F_s, F_c, b; what the table leaves out is the drive's (share, running torque)
    start = for_unit(drive, {"starting_torque_Nm": 0.1})
    running = PLAIN.coulomb_torque + PLAIN.viscous * 2000.0 * RPM
    assert start.starting_torque == 0.1
    assert start.coulomb_torque == pytest.approx(0.1 * 0.05 / 0.08, rel=1e-12)
    assert start.coulomb_torque + start.viscous * 2000.0 * RPM == pytest.approx(running, rel=1e-12)
    assert for_unit(drive, {"model": "catalog"}).starting_torque == catalog_friction(drive).starting_torque
    assert for_unit(drive, {"model": "none", "viscous_Nms": 1.0}) is NO_INPUT_FRICTION
    with pytest.raises(InputError, match="'drive', 'catalog' or 'none'"):
        for_unit(drive, {"model": "fitted"})
    with pytest.raises(InputError, match="unknown input_friction key 'viscous'"):
        for_unit(drive, {"viscous": 1e-4})
    with pytest.raises(InputError, match="delivers power"):
        for_unit(drive, {"coulomb_asymmetry_Nm": 0.2})


def test_the_running_torque_scenario_runs_the_drive_law_and_its_override(tmp_path):
    """A table's key and the same drive parameter run the same friction; the run file keeps the law."""
    base = hdsim.load_unit().without("friction", "backlash").with_input_friction(PLAIN)
    assert bench_from_scenario(base, short_sweep()).input_friction is PLAIN
    by_table = hdsim.run_scenario(base, short_sweep(**{"input_friction.viscous_Nms": 3e-4}))
    by_drive = hdsim.run_scenario(base.with_updates({"input_friction.viscous": 3e-4}), short_sweep())
    for name in ("running_torque_forward_Nm", "running_torque_500rpm_mNm", "running_torque_2000rpm_mNm"):
        assert by_table.metric(name) == pytest.approx(by_drive.metric(name), rel=1e-9), name
    closed = np.mean([0.05 + 3e-4 * rpm * RPM for rpm in (500.0, 2000.0)])  # F_c + b ω, Stribeck died out
    assert by_drive.metric("running_torque_forward_Nm") == pytest.approx(closed, rel=1e-3)
    back = hdsim.read_run(by_drive.save(tmp_path / "sweep.h5")).model.input_friction
    assert back.viscous == 3e-4 and back.ripple_orders == () and back.coulomb_torque == 0.05


# --------------------------------------------------------------------------- a fitted sweep's drive


@pytest.fixture(scope="module")
def output_side_fit():
    """A viscous sweep logged on the output shaft (torque = N × input torque), fitted with damping."""
    cols, meta, truth = make_running_data(("damping",), seed=3, damping_form="viscous", noise=False,
                                          cogging=False, temperature=False, layout="output",
                                          speeds_rpm=[300.0, 1000.0, 3000.0])
    assert meta["torque_side"] == "output"
    meas = make_measurement("running_torque", cols["time_s"], cols["torque_Nm"], cols["output_angle_rad"],
                            ratio=float(meta["ratio"]), rated_torque=float(meta["rated_torque_Nm"]),
                            meta={"torque_side": "output"})
    return fit_running(meas, ["damping"]), truth


def test_a_fitted_drive_carries_the_law_on_the_input_shaft(output_side_fit):
    fit, truth = output_side_fit
    drive = fit.drive
    law, unit = drive.input_friction, hdsim.load_unit()
    assert drive.name == unit.name and float(drive.drive.ratio) == RATIO
    # the law is the input side's (the file's torque / N), the truth's F_c and c within 1 %
    assert law.coulomb_torque == pytest.approx(truth["params"]["base"]["F_c"], rel=0.01)
    assert law.viscous == pytest.approx(truth["params"]["damping"]["c"], rel=0.01)
    assert (law.coulomb_torque, law.viscous) == (fit.law.coulomb_torque, fit.law.viscous)
    # what a no-load sweep cannot see stays the drive's
    assert law.load_coefficient == unit.input_friction.load_coefficient
    assert law.velocity_scale == unit.input_friction.velocity_scale
    # the fit reports on the file's side: the measured running torque over whole WG turns is N times
    # the drive's input-side law at the plateau speeds, each weighted by its whole turns (within the
    # noise and the cogging left over a handful of turns)
    x = fit.record.measurement.wg_angle
    own = [seg for seg in fit.record.segments if seg.speed > 0]
    turns = [np.floor(abs(x[seg.stop - 1] - x[seg.start]) / (2 * np.pi)) for seg in own]
    on_input = np.average([law.coulomb_torque + law.viscous * seg.speed for seg in own], weights=turns)
    assert fit.metrics()["running_torque_forward_Nm"] == pytest.approx(RATIO * on_input, rel=0.01)
    assert fit.drive_for("CSG-20-100").name == "CSG-20-100"


def test_the_running_torque_scenario_on_a_fitted_drive_gives_the_fitted_level(output_side_fit):
    """Closed form: on plateaus the law is F_c + b ω on the input shaft (no Stribeck, no ripple);
    the bench's motor torque is that within 0.1 % (the elastic path and the mesh term add ~1e-4)."""
    fit, _ = output_side_fit
    law = fit.drive.input_friction
    run = hdsim.run_scenario(fit.drive, short_sweep())
    for rpm in (500.0, 2000.0):
        level = law.coulomb_torque + law.viscous * rpm * RPM
        assert run.metric(f"running_torque_{rpm:g}rpm_mNm") == pytest.approx(1e3 * level, rel=1e-3), rpm
    expected = np.mean([law.coulomb_torque + law.viscous * rpm * RPM for rpm in (500.0, 2000.0)])
    for direction in ("forward", "reverse"):
        assert run.metric(f"running_torque_{direction}_Nm") == pytest.approx(expected, rel=1e-3)


def test_sobol_studies_the_fitted_input_friction(output_side_fit):
    """The running torque depends on F_c and not on F_s (its Stribeck excess has died out by
    2000 rpm): S1 of F_c ≈ 1, ST of F_s = 0. N = 128: N = 8, the least the design takes, gives
    S1 anywhere in 0.4-1.3 by seed for a one-parameter function, at about the same cost here."""
    fit, _ = output_side_fit
    # the elastic path's friction and backlash do not touch the running torque; they cost solver time
    drive = fit.drive.without("friction", "backlash")
    level = drive.input_friction.coulomb_torque
    scenario = short_sweep(**{"input.speeds_rpm": [2000.0], "output.samples_per_wg_rev": 8})
    result = hdsim.sobol(drive, {"input_friction.coulomb_torque": (0.5 * level, 1.5 * level),
                                 "input_friction.starting_torque": (0.01, 0.1)},
                         output="running_torque_forward_Nm", scenario=scenario, n=128, replicates=2,
                         workers=1, progress=False, log=lambda line: None)
    assert not result.failures
    indices = result.to_json()
    assert indices["S1"]["input_friction.coulomb_torque"] == pytest.approx(1.0, abs=0.03)
    assert indices["ST"]["input_friction.coulomb_torque"] == pytest.approx(1.0, abs=0.03)
    assert abs(indices["ST"]["input_friction.starting_torque"]) < 1e-9


def test_a_batch_of_input_friction_laws_breaks_away_law_by_law():
    """The starting torque of a study's batch (each row its own F_s) is each row's own."""
    drive = hdsim.load_unit().without("friction", "backlash")
    # the breakaway metrics come from their own torque ramps, not from the sweep's signals:
    # one cruise speed instead of two (the same values, 40 % less time)
    scenario = short_sweep(metrics=["starting_torque", "backdriving_torque"], **{"input.speeds_rpm": [2000.0]})
    batch = hdsim.run_scenario(drive.with_updates({"input_friction.starting_torque": [0.05, 0.09]}), scenario)
    single = hdsim.run_scenario(drive.with_updates({"input_friction.starting_torque": 0.09}), scenario)
    assert batch.metrics["starting_torque_mNm"][1] == single.metric("starting_torque_mNm")
    assert batch.metrics["starting_torque_mNm"][0] < single.metric("starting_torque_mNm")
    assert batch.metrics["backdriving_torque_Nm"][1] == single.metric("backdriving_torque_Nm")
