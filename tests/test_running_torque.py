"""Running-torque tests (friction sweeps): reading, the shared law, fit, checks and the CLI.

Data here come from closed forms written in this file (plateaus of constant speed with
the law's terms) or from the library's own law where the test is of the fit's machinery
(exact recovery); discovery on independent data is `tests/test_running_torque_battery.py`.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import hdsim

from hdsim.errors import InputError
from hdsim.identification.running_diagnosis import diagnose_running
from hdsim.identification.running_fit import fit_running
from hdsim.identification.workflow import examine
from hdsim.io.data_checks import DriveScale
from hdsim.io.measurement import load_measurement, make_measurement, save_measurement
from hdsim.io.running_checks import sweep_kinematics
from hdsim.model.catalog import load_unit
from hdsim.model.input_friction import InputFriction, for_unit
from hdsim.model.running_terms import parse_running_effects, parse_running_forms

RATIO = 100.0


def sweep_profile(speeds=(3.0, 30.0, 150.0), fs=1000.0, dwell_turns=3.0, ramp=0.1, signs=(1.0, -1.0)):
    """Time, WG angle, speed and acceleration of a sweep: each speed forward and back, linear ramps."""
    knots_t, knots_w = [0.0], [0.0]
    for w in speeds:
        for sign in signs:
            cruise = dwell_turns * 2 * math.pi / w
            t = knots_t[-1]
            knots_t += [t + ramp, t + ramp + cruise, t + 2 * ramp + cruise]
            knots_w += [sign * w, sign * w, 0.0]
    t = np.arange(0.0, knots_t[-1], 1.0 / fs)
    w = np.interp(t, knots_t, knots_w)
    a = np.gradient(w, t)
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
    return t, theta, w, a


def law_record(law: InputFriction, inertia=2e-5, noise=0.0, seed=0, side="input", **profile):
    """A running-torque measurement made with the library's own law (fit machinery tests)."""
    t, theta, w, a = sweep_profile(**profile)
    torque = law.torque(w, theta) + inertia * a
    torque = torque + np.random.default_rng(seed).normal(0.0, noise, t.size) if noise else torque
    factor = RATIO if side == "output" else 1.0
    return make_measurement("running_torque", t, factor * torque, None, wg_angle=theta, ratio=RATIO,
                            meta={"torque_side": side})


FULL = InputFriction(starting_torque=0.09, coulomb_torque=0.05, viscous=2e-4, stribeck_speed=8.0,
                     velocity_scale=0.05, ripple_orders=(1.0, 2.0), ripple_amplitudes=(0.05, 0.12),
                     ripple_phases=(0.3, -1.0), coulomb_asymmetry=0.006)
#: FULL with its ripple a torque of the position alone (the same both ways), of order 2
POSITION_ONLY = FULL.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=(), position_orders=(2.0,),
                                  position_amplitudes=(0.008,), position_phases=(0.4,))


# --------------------------------------------------------------------------- the law


def test_ripple_averages_out_over_a_turn_and_the_law_is_dissipative():
    theta = np.linspace(0.0, 2 * math.pi, 4001)[:-1]
    for w in (0.5, 10.0, 200.0):
        assert np.mean(FULL.torque(w, theta)) == pytest.approx(FULL.running_torque(w), rel=1e-12)
        # the running torque by its closed form: F_c + Δ + (F_s − F_c) e^{−(ω/ω_s)²} + b ω (tanh ≈ 1 here)
        closed = 0.05 + 0.006 + 0.04 * math.exp(-(w / 8.0) ** 2) + 2e-4 * w
        assert FULL.running_torque(w) == pytest.approx(closed, rel=1e-7)
        assert np.all(FULL.torque(w, theta) * w > 0)  # opposes the motion at every angle
    assert FULL.dissipative
    assert not FULL.with_updates(coulomb_asymmetry=0.05).dissipative


def test_mesh_torque_adds_mu_times_the_transmitted_torque():
    law = FULL.with_updates(load_coefficient=0.1, ripple_orders=(), ripple_amplitudes=(), ripple_phases=())
    assert law.torque(100.0, 0.0, mesh_torque=0.87) - law.torque(100.0, 0.0) == pytest.approx(0.087, rel=1e-9)
    assert law.torque(-100.0, 0.0, mesh_torque=-0.87) - law.torque(-100.0, 0.0) == pytest.approx(-0.087, rel=1e-9)


def test_a_scenario_refuses_a_law_that_would_deliver_power():
    with pytest.raises(InputError, match="delivers power"):
        for_unit(load_unit(), {"ripple_amplitudes": [0.6, 0.6]})


# --------------------------------------------------------------------------- reading


def test_one_angle_and_the_ratio_give_the_other(tmp_path):
    path = tmp_path / "sweep.csv"
    path.write_text("# test: running_torque\n# ratio: 50\n# torque_side: output\n"
                    "time_s,output_angle_deg,torque_Nm,temperature_C\n"
                    + "".join(f"{0.01 * i},{0.1 * i},2.0,{20 + 0.01 * i}\n" for i in range(30)))
    meas = load_measurement(path)
    assert meas.torque_side == "output"
    assert np.allclose(meas.wg_angle, np.radians(0.1 * np.arange(30)) * 50)
    assert meas.temperature[-1] == pytest.approx(20.29)
    back = load_measurement(save_measurement(meas, tmp_path / "again.csv"))
    assert np.array_equal(back.wg_angle, meas.wg_angle) and back.torque_side == "output"


@pytest.mark.parametrize("head, match", [
    ("# test: running_torque\n# ratio: 100\ntime_s,wg_angle_rad,torque_Nm\n", None),
    ("# test: running_torque\ntime_s,wg_angle_rad,torque_Nm\n", "needs the transmission ratio"),
    ("# test: running_torque\ntime_s,output_angle_rad,torque_Nm\n", "needs the transmission ratio"),
    ("# test: running_torque\n# ratio: 100\ntime_s,torque_Nm\n", "at least one of them"),
    ("# test: running_torque\n# ratio: 100\n# torque_side: motor\ntime_s,wg_angle_rad,torque_Nm\n", "input or output"),
    # both angles but the torque on the output: without the ratio it would be fitted as the
    # input's, a hundred times too large (it was, silently)
    ("# test: running_torque\n# torque_side: output\ntime_s,wg_angle_rad,output_angle_rad,torque_Nm\n",
     "with '# torque_side: output' needs the transmission ratio to refer the torque to the input"),
    # a breakaway's starting torques are given on both shafts (it had failed as an internal error)
    ("# test: breakaway\ntime_s,wg_angle_rad,output_angle_rad,torque_Nm\n",
     "a breakaway file needs the transmission ratio to give its starting torques on both shafts"),
])
def test_running_torque_files_are_refused_in_one_line(tmp_path, head, match):
    path = tmp_path / "bad.csv"
    cols = head.strip().splitlines()[-1].count(",") + 1
    path.write_text(head + "".join(",".join([str(0.01 * i)] * cols) + "\n" for i in range(20)))
    if match is None:
        assert load_measurement(path).test == "running_torque"
        return
    with pytest.raises(InputError, match=match) as err:
        load_measurement(path)
    assert "\n" not in str(err.value)


def test_plateau_speed_is_the_slope_of_the_angle_despite_encoder_steps():
    t, theta, w, _ = sweep_profile(speeds=(2.0, 40.0))
    step = 2 * math.pi / 2**14  # a 14-bit encoder
    speed, accel, segments = sweep_kinematics(t, np.round(theta / step) * step)
    assert len(segments) == 4
    for seg in segments:
        assert abs(seg.speed) == pytest.approx(abs(w[(seg.start + seg.stop) // 2]), rel=2e-3)
        assert np.all(accel[seg.start:seg.stop] == 0.0)


# --------------------------------------------------------------------------- fit


def test_the_fit_recovers_the_law_that_made_the_data():
    fit = fit_running(law_record(FULL), ["friction", "damping", "ripple"])
    law = fit.law
    # 1 % of the level: the Stribeck grid's nearest speed, and the speed and acceleration
    # derivatives smoothing the kinks of the linear ramps
    assert fit.rmse_Nm < 1e-3
    assert law.coulomb_torque == pytest.approx(0.05, rel=0.02)
    assert law.viscous == pytest.approx(2e-4, rel=0.02)
    assert law.coulomb_asymmetry == pytest.approx(0.006, rel=0.02)
    assert fit.inertia == pytest.approx(2e-5, rel=0.05)
    amplitudes = dict(zip(law.ripple_orders, law.ripple_amplitudes))
    assert amplitudes[2.0] == pytest.approx(0.12, rel=0.03) and amplitudes[1.0] == pytest.approx(0.05, rel=0.05)
    # the contract's metrics: the running torque of each direction over whole WG turns, where the
    # ripple averages out: in closed form the plateaus' ripple-free law, each weighted by its whole turns
    rec = fit.record
    x = rec.measurement.wg_angle
    for name, direction in (("running_torque_forward_Nm", 1), ("running_torque_reverse_Nm", -1)):
        own = [s for s in rec.segments if np.sign(s.speed) == direction]
        turns = [math.floor(abs(x[s.stop - 1] - x[s.start]) / (2 * math.pi)) for s in own]
        levels = [direction * FULL.running_torque(s.speed) for s in own]
        assert fit.metrics()[name] == pytest.approx(np.average(levels, weights=turns), rel=0.01)


def test_an_output_side_record_gives_the_same_law_and_torques_times_the_ratio():
    law = FULL.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=())
    on_input = fit_running(law_record(law, noise=1e-3), ["friction", "damping"])
    on_output = fit_running(law_record(law, noise=1e-3, side="output"), ["friction", "damping"])
    assert on_output.law.coulomb_torque == pytest.approx(on_input.law.coulomb_torque, rel=1e-9)
    assert on_output.rmse_Nm == pytest.approx(RATIO * on_input.rmse_Nm, rel=1e-9)
    assert on_output.metrics()["running_torque_forward_Nm"] == pytest.approx(
        RATIO * on_input.metrics()["running_torque_forward_Nm"], rel=1e-9)


def test_an_output_torque_of_a_drive_turning_the_other_way_is_read_with_its_own_shafts_sign():
    # ratio −100: the output turns against the WG, and its torque is signed with the output's
    # motion; the fit read it so, but the checks and the measured levels took the WG's sign
    # (a warning on every plateau and running torques of −8.5 N·m)
    law = FULL.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=())
    t, theta, w, a = sweep_profile()
    torque = -RATIO * (law.torque(w, theta) + 2e-5 * a)  # on the output, with the output's motion
    meas = make_measurement("running_torque", t, torque, None, wg_angle=theta, ratio=-RATIO,
                            meta={"torque_side": "output"})
    checks, data = examine(meas, DriveScale.of(load_unit("CSG-25-100")))[:2]
    assert {c.check: c.status for c in checks}["torque_opposes_motion"] == "ok"
    fitted = fit_running(meas, ["friction", "damping"])
    for way in ("forward", "reverse"):
        assert data[f"running_torque_{way}_Nm"] > 0
        assert fitted.metrics()[f"running_torque_{way}_Nm"] == pytest.approx(data[f"running_torque_{way}_Nm"])
    assert fitted.law.coulomb_torque == pytest.approx(law.coulomb_torque, rel=2e-3)


def test_columns_a_record_cannot_tell_apart_do_not_stop_the_fit_as_an_internal_error():
    # the shipped kinematic-error record read as a sweep: one speed, a level, its direction
    # asymmetry and the Stribeck rise are one column there; the solver split them into
    # ±3e11 N·m that cancel, the law lost their digits and the fit stopped (exit 1)
    from pathlib import Path

    meas = load_measurement(Path(__file__).parent / "data" / "ke_example.csv", test="running_torque")
    law = fit_running(meas, ["friction", "damping", "ripple"]).law
    assert max(abs(law.coulomb_torque), abs(law.coulomb_asymmetry), abs(law.starting_torque)) < 1e3


def test_both_angles_that_contradict_the_ratio_are_said_to():
    # the output angle is wg/100 but the file says 50: the law on the input came out doubled, unsaid
    law = FULL.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=())
    t, theta, w, a = sweep_profile()
    meas = make_measurement("running_torque", t, RATIO * law.torque(w, theta), theta / RATIO, wg_angle=theta,
                            ratio=RATIO / 2, meta={"torque_side": "output"})
    checks = {c.check: c for c in examine(meas, DriveScale.of(load_unit("CSG-25-100")))[0]}
    assert checks["ratio_consistent"].status == "warn"
    assert checks["ratio_consistent"].message.startswith("the output turns 0.5 times the wave-generator angle")


def test_a_misspelt_family_is_named_in_the_words_of_the_test_the_options_name(cli, tmp_path):
    """``--effects stribeck,hardening`` with ``--test running_torque`` had been refused in the
    stiffness test's words, naming the valid ``stribeck`` and not ``hardening``."""
    code, _, stderr = cli("fit", "missing.csv", "--test", "running_torque", "--ratio", "100",
                          "--effects", "stribeck,hardening", cwd=tmp_path)
    assert code == 2 and "the hardening family acts in the elastic path" in stderr and "'stribeck'" not in stderr


def test_effects_of_the_elastic_path_are_refused_for_a_sweep():
    assert parse_running_effects("stribeck,ripple") == ["friction", "ripple"]
    with pytest.raises(InputError, match="elastic path"):
        parse_running_effects("hardening")


def test_a_ripple_form_named_with_its_family_is_the_form_fitted():
    # {"ripple": "position_torque"} and "ripple=position_torque" had fitted the default ripple form
    assert parse_running_forms({"ripple": "position_torque"}) == {"ripple": "position_torque"}
    assert parse_running_forms("friction,ripple=position_torque") == {"friction": "stribeck",
                                                                      "ripple": "position_torque"}
    with pytest.raises(InputError, match="unknown ripple form 'positon_torque'; did you mean position_torque"):
        parse_running_forms("ripple=positon_torque")
    with pytest.raises(InputError, match="two ripple forms"):
        parse_running_forms("ripple,position_torque")


def test_a_misspelt_ripple_form_is_named_in_the_sweeps_words(cli, tmp_path):
    code, _, stderr = cli("fit", "missing.csv", "--effects", "ripple=positon_torque", cwd=tmp_path)
    assert code == 2 and "did you mean position_torque" in stderr


def test_diagnosis_adds_what_the_law_made_and_nothing_more():
    law = FULL.with_updates(starting_torque=0.05, coulomb_asymmetry=0.0, ripple_orders=(), ripple_amplitudes=(),
                            ripple_phases=())  # Coulomb + viscous only
    d = diagnose_running(law_record(law, noise=2e-3, seed=3), [])
    assert d.added == ["damping"]
    assert d.success
    nothing = diagnose_running(law_record(law.with_updates(viscous=0.0), noise=2e-3, seed=4), [])
    assert nothing.added == [] and nothing.success


# --------------------------------------------------------------------------- checks


def test_a_record_that_never_turns_steadily_is_the_wrong_test():
    t = np.linspace(0.0, 4.0, 2000)
    meas = make_measurement("running_torque", t, np.sin(t), None, wg_angle=1e-3 * np.sin(3 * t), ratio=RATIO)
    checks, _, wrong = examine(meas, DriveScale.of(load_unit()))
    assert "never turns at a steady speed" in wrong


def test_a_torque_channel_that_never_changes_is_the_wrong_test_and_its_json_holds_no_infinity():
    """A current channel never logged (0 on every row) had been fitted with a law of level 0
    and no noise floor: the verdict said "rms inf× the noise floor" and --json stopped with an
    internal error (JSON has no infinity)."""
    record = law_record(FULL)
    meas = make_measurement("running_torque", record.time, np.zeros(len(record)), None, wg_angle=record.wg_angle,
                            ratio=RATIO)
    checks, _, wrong = examine(meas, DriveScale.of(load_unit()))
    assert "0 N·m on every row" in wrong and any(c.check == "torque_varies" and c.status == "fail" for c in checks)
    d = diagnose_running(law_record(FULL, fs=200.0), [], max_rounds=0)
    d.whiteness["rms_over_noise"] = math.inf  # as a residual over a zero floor gives it
    assert json.loads(json.dumps(d.to_json(), allow_nan=False))["whiteness"]["rms_over_noise"] is None


def test_one_speed_and_a_torque_on_the_other_shaft_are_warned():
    law = FULL.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=())
    t, theta, w, a = sweep_profile(speeds=(100.0,))
    meas = make_measurement("running_torque", t, RATIO * law.torque(w, theta), None, wg_angle=theta, ratio=RATIO)
    checks, data, wrong = examine(meas, DriveScale.of(load_unit()))
    status = {c.check: c.status for c in checks}
    assert not wrong and status["speeds"] == "warn" and status["torque_side"] == "warn"
    assert "torque_side=output" in next(c.message for c in checks if c.check == "torque_side")
    assert data["speeds_rpm"] == [pytest.approx(100.0 * 30 / math.pi, rel=1e-3)]


# --------------------------------------------------------------------------- command line


def test_fit_and_diagnose_on_the_command_line(cli, tmp_path, capsys):
    from hdsim.cli.diagnose import _print as _print_diagnosis

    save_measurement(law_record(FULL, noise=2e-3, fs=300.0), tmp_path / "sweep.csv")
    code, stdout, stderr = cli("fit", "sweep.csv", "--effects", "friction,damping,ripple", "--json", cwd=tmp_path)
    assert code == 0, stderr
    out = fitted = json.loads(stdout)
    assert set(out["metrics"]) == {"running_torque_forward_Nm", "running_torque_reverse_Nm"}
    assert out["rmse_Nm"] == pytest.approx(2e-3, rel=0.15) and out["noise_floor_Nm"] == pytest.approx(2e-3, rel=0.15)
    assert all((tmp_path / f).exists() for f in ("sweep.fit.toml", "sweep.fit.torque_vs_speed.png",
                                                 "sweep.fit.ripple.png"))
    code, stdout, stderr = cli("diagnose", "sweep.csv", "--json", "--report", "rep", cwd=tmp_path)
    assert code == 0, stderr
    out = json.loads(stdout)
    assert out["test"] == "running_torque" and out["outcome"] == "found"
    assert set(out["added"]) == {"friction", "damping", "ripple"}
    assert {"family", "effect", "rmse_Nm", "score"} <= set(out["ranking"][0])
    assert (tmp_path / "rep" / "index.html").exists()
    # the same model's starting torque, each way, as the fit gives it (the diagnosis had the mean level only)
    starting = {k: v for k, v in fitted["derived"].items() if k.startswith("starting_torque")}
    assert {"starting_torque_forward_Nm", "starting_torque_reverse_Nm"} <= set(starting)
    assert {k: out["final"]["derived"][k] for k in starting} == pytest.approx(starting)
    _print_diagnosis(out)
    assert f"{starting['starting_torque_forward_Nm']:.4g}" in capsys.readouterr().out
    code, _, stderr = cli("fit", "sweep.csv", "--effects", "backlash", cwd=tmp_path)
    assert code == 2 and "elastic path" in stderr


def test_a_fitted_law_pasted_into_a_scenario_runs_the_measured_friction():
    """The fit's `law` table is a scenario's [input_friction]: the simulated bench then needs the
    fitted law's running torque at every speed (one law, no second copy)."""
    from hdsim import run_scenario
    from hdsim.scenarios.scenario import load_scenario
    from pathlib import Path

    law = FULL.with_updates(load_coefficient=0.0)
    fit = fit_running(law_record(law, noise=1e-3), ["friction", "damping", "ripple"])
    sc = load_scenario(Path(__file__).resolve().parents[1] / "scenarios" / "running_torque.toml").with_updates(
        {"input.speeds_rpm": [60.0, 900.0], "input.revolutions": 1.0, "input.settle_revolutions": 0.25,
         "metrics": ["running_torque_sweep"],
         **{f"input_friction.{k}": v for k, v in {**fit.law_table(), "load_coefficient": 0.0}.items()}})
    run = run_scenario(load_unit(), sc)
    from types import SimpleNamespace

    from hdsim.plotting.driven import plot_running_torque

    assert plot_running_torque(run) is not None  # the sweep's figure, beside the catalog point
    assert plot_running_torque(SimpleNamespace(metrics={"running_torque_mNm": 1.0}, model=run.model)) is None
    for rpm in (60.0, 900.0):
        w = rpm * math.pi / 30
        both_ways = 0.5 * (fit.law.running_torque(w) - fit.law.running_torque(-w))  # the asymmetry cancels
        assert run.metric(f"running_torque_{rpm:g}rpm_mNm") == pytest.approx(1e3 * both_ways, rel=2e-3)



def test_halves_too_short_to_fit_add_nothing_unvalidated():
    from hdsim.identification.engine import Step
    from hdsim.identification.running_diagnosis import RunningSession

    session = RunningSession(law_record(FULL), {})
    empty = np.zeros(session.record.speed.size, dtype=bool)
    session.folds = ([empty, empty], [empty, empty])  # nothing to fit a half on
    assert session._holdout_rss([]) is None
    step = Step([], fit_running(session.record, []), None)
    cand = session._try(step, "friction", "stribeck", ["stribeck"], at_floor=False)
    assert not cand.accepted and "too short" in cand.reason


def test_a_list_key_takes_a_toml_array_on_the_command_line():
    from pathlib import Path

    from hdsim.scenarios.scenario import load_scenario

    sc = load_scenario(Path(__file__).resolve().parents[1] / "scenarios" / "running_torque.toml")
    assert sc.with_updates({"input.speeds_rpm": "[500, 2000.5]"}).data["input"]["speeds_rpm"] == [500, 2000.5]
    with pytest.raises(InputError, match="must be list"):
        sc.with_updates({"input.speeds_rpm": "500 rpm"})


def test_a_running_fit_file_is_not_taken_for_a_drive(tmp_path):
    from hdsim.identification.fit import load_fitted

    path = fit_running(law_record(FULL, fs=300.0), ["friction"]).save(tmp_path / "sweep.fit.toml")
    with pytest.raises(InputError, match="paste its \\[input_friction\\] table"):
        load_fitted(path)


def test_ripple_and_starting_torque_are_torques_on_the_files_shaft_with_uncertainty():
    # the law's amplitudes are fractions of F_c = 0.05 N·m on the input; the file logs the output (× N)
    fit = fit_running(law_record(FULL, side="output", noise=1e-4 * RATIO), ["friction", "damping", "ripple"])
    summary = fit.summary()
    ripple = {r["order"]: r["amplitude_Nm"] for r in summary["ripple_Nm"]}
    assert ripple[2.0] == pytest.approx(RATIO * 0.05 * 0.12, rel=0.05)
    assert ripple[1.0] == pytest.approx(RATIO * 0.05 * 0.05, rel=0.1)
    # F_s = 0.09 N·m on the input, on the file's side; the slowest plateau (3 rad/s) is not
    # below half of ω_s = 8 rad/s twice over, so the record does not determine it
    # (tests/test_sweep_starting_torque.py): no uncertainty
    derived = summary["derived"]
    assert derived["starting_torque_Nm"] == pytest.approx(RATIO * 0.09, rel=0.05)
    assert derived["starting_torque_uncertainty_Nm"] is None
    # the scenario table keeps fractions of the level, and its key says so; the old key is still read
    table = summary["law"]
    assert table["ripple_amplitudes_of_level"][:2] == pytest.approx([0.05, 0.12], rel=0.1)  # orders 1, 2 (and 4: ~0)
    old = for_unit(load_unit(), {"ripple_orders": [2.0], "ripple_amplitudes": [0.1], "ripple_phases": [0.0]})
    new = for_unit(load_unit(), {"ripple_orders": [2.0], "ripple_amplitudes_of_level": [0.1], "ripple_phases": [0.0]})
    assert old.ripple_amplitudes == new.ripple_amplitudes == (0.1,)


def test_a_position_torque_is_the_same_both_ways_and_averages_out_over_a_turn():
    law = FULL.with_updates(position_orders=(2.0,), position_amplitudes=(0.01,), position_phases=(0.5,))
    theta = np.linspace(0.0, 2 * math.pi, 73)
    for w in (30.0, -30.0):  # added as it is in both directions: not signed by the motion
        added = law.torque(np.full(theta.size, w), theta) - FULL.torque(np.full(theta.size, w), theta)
        assert added == pytest.approx(0.01 * np.cos(2.0 * theta + 0.5), abs=1e-15)
    assert law.running_torque(30.0) == FULL.running_torque(30.0)
    table = for_unit(load_unit(), {"position_torque_orders": [2.0], "position_torque_amplitudes_Nm": [0.01],
                                   "position_torque_phases": [0.5]})
    assert (table.position_orders, table.position_amplitudes, table.position_phases) == ((2.0,), (0.01,), (0.5,))


def test_the_fit_recovers_a_position_torque_in_its_own_form():
    law = FULL.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=(), position_orders=(1.0, 2.0),
                            position_amplitudes=(0.004, 0.009), position_phases=(0.3, -1.0))
    fit = fit_running(law_record(law), ["friction", "damping", "position_torque"])
    assert fit.forms["ripple"] == "position_torque" and fit.rmse_Nm < 1e-3
    amplitudes = dict(zip(fit.law.position_orders, fit.law.position_amplitudes))
    assert amplitudes[2.0] == pytest.approx(0.009, rel=0.03) and amplitudes[1.0] == pytest.approx(0.004, rel=0.05)
    # the modulated form cannot take it: it reverses with the motion
    other = fit_running(law_record(law), ["friction", "damping", "ripple"])
    assert other.rmse_Nm > 3 * fit.rmse_Nm


def test_a_diagnosis_tells_the_ripple_forms_apart_with_both_directions():
    law = POSITION_ONLY
    result = diagnose_running(law_record(law, noise=5e-4), ["friction", "damping"])
    assert result.added == ["ripple"]
    chosen = next(c for c in result.steps[0].candidates if c.family == "ripple")
    assert chosen.effect == "position_torque"
    modulated = diagnose_running(law_record(FULL, noise=5e-4), ["friction", "damping"])
    assert next(c for c in modulated.steps[0].candidates if c.family == "ripple").effect == "ripple"
    assert not [a for a in result.ambiguous + modulated.ambiguous if a["families"] == ["ripple", "ripple"]]


def test_a_sweep_in_one_direction_says_it_cannot_tell_the_ripple_forms_apart():
    # it had added the modulated form silently: 'ambiguous' empty and no next measurement
    law = POSITION_ONLY
    result = hdsim.diagnose(law_record(law, noise=5e-4, signs=(1.0,)), effects=["friction", "damping"])
    assert result.added == ["ripple"]
    entry = next(a for a in result.to_json()["ambiguous"] if a["families"] == ["ripple", "ripple"])
    assert entry["other_form"] == {"ripple": "position_torque"} and "other direction" in entry["measurement"]
    assert entry["scores"][1] == pytest.approx(entry["scores"][0], abs=1.0)  # the same torque one way
    assert "other direction" in result.next_measurement and "position torque" in result.next_measurement


def test_a_ripple_given_in_the_baseline_of_a_one_way_sweep_is_not_called_added():
    # the entry had said "added" (and the page "ripple was added") of a ripple the user gave
    law = POSITION_ONLY
    result = hdsim.diagnose(law_record(law, noise=5e-4, signs=(1.0,)), effects=["friction", "damping", "ripple"])
    entry = next(a for a in result.to_json()["ambiguous"] if a["families"] == ["ripple", "ripple"])
    assert entry["added"] is False and entry["scores"] == [None, None]
    assert "other direction" in result.next_measurement
