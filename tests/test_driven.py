"""Driven wave generator: scenarios, input checks, measured profiles, batches, metrics, CLI.

The physics checks (rigid limit, energy, order spectrum, Bode, friction, the contract
scenario) are in ``test_driven_physics.py``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hdsim.scenarios import ke_metrics
from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import catalog_entry
from hdsim.physics.stiffness import three_segment_twist
from hdsim.scenarios.driven import SETUP, bench_from_scenario
from hdsim.scenarios.profile_csv import read_profile_csv
from hdsim.errors import InputError
from hdsim.scenarios.run import read_run, run_scenario
from hdsim.scenarios.scenario import Scenario, load_scenario
from hdsim.units import arcsec_to_rad, rad_to_arcsec

ROOT = Path(__file__).resolve().parents[1]
DRIVEN = ["kinematic_error", "constant_speed", "reversal", "point_to_point", "sine_oscillation", "load_step",
          "frequency_sweep"]


def scenario(**tables) -> Scenario:
    data = {"name": "t", "setup": SETUP, "metrics": tables.pop("metrics", [])}
    data.update(tables)
    return Scenario(data, "<dict>")


# --------------------------------------------------------------------------- shipped scenarios
@pytest.mark.parametrize("name", DRIVEN)
def test_shipped_scenario_is_a_symlink_and_builds(name):
    link = ROOT / "scenarios" / f"{name}.toml"
    assert link.is_symlink() and link.resolve() == (ROOT / "hdsim/data/scenarios" / f"{name}.toml").resolve()
    sc = load_scenario(link)
    assert sc.setup == SETUP and sc.name == name
    bench = bench_from_scenario(load_unit(), sc)
    assert bench.t_end > 0 and bench.sample_times()[-1] == pytest.approx(bench.t_end)


def test_kinematic_error_scenario_reports_the_contract_metrics():
    sc = load_scenario(ROOT / "scenarios/kinematic_error.toml")
    assert {"transmission_accuracy", "lost_motion_on_reversal"} <= set(sc.metrics)


@pytest.mark.parametrize("tables, message", [
    ({"input": {"mode": "servo", "profile": "hold"}}, "input.mode"),
    ({"input": {"mode": "prescribed", "profile": "zigzag"}}, "input.profile"),
    ({"input": {"mode": "prescribed", "profile": "constant"}}, "speed_rpm"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "load": {"profile": "opposing", "torque": 0.1}},
     "moving input"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "load": {"profile": "constant", "torque": 9.0}},
     "within ±5"),
    ({"input": {"mode": "prescribed", "profile": "csv"}}, "input.csv"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "controller": {"bandwidth_Hz": 10.0}}, "pi"),
    ({"input": {"mode": "pi", "profile": "hold"}, "controller": {"feedforward": "maybe"}}, "yes"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "metrics": ["wobble"]}, "metric"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "input_friction": {"model": "magic"}}, "catalog"),
    ({"input": {"mode": "prescribed", "profile": "sine", "frequency_Hz": -1.0}}, "frequency_Hz"),
    # found by a tester: each of these went on to the solver or a formula and failed there (exit 1),
    # or ran something else than the keys say
    ({"input": {"mode": "prescribed", "profile": "constant", "speed_rpm": float("nan")}},
     "input.speed_rpm must be a finite"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "load": {"profile": "constant", "torque": float("nan")}},
     "load.torque must be a finite"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "analysis": {"orders": ["x"]}}, "list of numbers"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "output": {"samples_per_wg_rev": 0}}, "1 or more"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "efficiency": {"speed_rpm": 0.0}}, "speed_rpm must be > 0"),
    ({"input": {"mode": "prescribed", "profile": "reversal", "speed_rpm": 2000.0, "output_revolutions": 0.05,
                "settle_revolutions": 0.05}}, "would share no angle"),
    ({"input": {"mode": "pi", "profile": "hold"}, "controller": {"position_gain_per_s": 50.0}}, "position_loop is"),
    ({"input": {"mode": "pi", "profile": "hold"}, "controller": {"position_loop": "yes", "position_gain_per_s": 0.0}},
     "is no loop"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "input_friction": {"load_coefficient": 1.5}}, "<= 0.9"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "linearise": {"load": 50.0}}, "within ±5"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "linearise": {"f_min_Hz": -5.0}}, "f_min_Hz must be > 0"),
    ({"input": {"mode": "prescribed", "profile": "hold"}, "linearise": {"compare_below": 5.0}}, "in (0, 1]"),
    ({"input": {"mode": "prescribed", "profile": "constant", "speed_rpm": 100.0},
      "load": {"profile": "opposing", "torque": -0.25}}, "its sign follows the motion"),
    # a measured load (the 2 s of the contract KE file) shorter than the input profile was held at its
    # last value for the rest of the run, unsaid
    ({"input": {"mode": "prescribed", "profile": "constant", "speed_rpm": 100.0, "output_revolutions": 1.0,
                "csv": str(Path(__file__).parent / "data" / "ke_example.csv")}, "load": {"profile": "csv"}},
     "a measured load is not extrapolated"),
])
def test_bad_scenarios_are_refused_in_one_line(tables, message):
    with pytest.raises(InputError) as info:
        bench_from_scenario(load_unit(), scenario(**tables))
    text = str(info.value)
    assert message in text and "\n" not in text


def test_the_quasi_static_evaluator_refuses_a_motor_loop():
    """Forced on a pi-mode scenario it held the motor on its reference: a load step's peak of
    243 arcsec against the loop's 1039, with exit 0."""
    from hdsim.scenarios.run import run_scenario

    with pytest.raises(InputError, match="needs the dynamic model"):
        run_scenario(load_unit(), load_scenario(ROOT / "scenarios/load_step.toml"), evaluator="quasistatic")
    # forced on metrics it has no signals for it had crashed in the linearisation (exit 1)
    with pytest.raises(InputError, match="does not compute the metric groups frequency_response"):
        run_scenario(load_unit(), load_scenario(ROOT / "scenarios/frequency_sweep.toml"), evaluator="quasistatic")


def test_schema_rejects_unknown_keys_and_wrong_types():
    with pytest.raises(InputError, match="unknown key"):
        scenario(input={"mode": "prescribed", "profile": "hold", "sped_rpm": 3.0})
    with pytest.raises(InputError, match="must be float"):
        scenario(input={"mode": "prescribed", "profile": "constant", "speed_rpm": "fast"})
    with pytest.raises(InputError, match="missing input.profile"):
        scenario(input={"mode": "prescribed"})


def test_set_overrides_reach_the_bench():
    sc = load_scenario(ROOT / "scenarios/constant_speed.toml").with_updates({"input.speed_rpm": "1000"})
    bench = bench_from_scenario(load_unit(), sc)
    assert bench.motion.max_speed == pytest.approx(1000 * 2 * np.pi / 60)


# --------------------------------------------------------------------------- measured profile
def test_measured_profile_from_a_contract_kinematic_error_file():
    path = ROOT / "tests/data/ke_example.csv"
    profile = read_profile_csv(path)
    assert {"time", "angle", "torque"} <= set(profile)
    sc = Scenario({"name": "measured", "setup": SETUP, "metrics": ["tracking"],
                   "input": {"mode": "prescribed", "profile": "csv", "csv": str(path)},
                   "load": {"profile": "csv"}, "solver": {"rtol": 1e-5, "atol_scale": 1e-3}}, "<dict>")
    run = run_scenario(load_unit(), sc)
    s, t = run.result.signals, run.result.t
    # the WG follows the file (zeroed at its first sample), the load is the file's torque
    t_file, angle_file = profile["time"] - profile["time"][0], profile["angle"] - profile["angle"][0]
    bench = bench_from_scenario(load_unit(), sc)
    assert np.max(np.abs(bench.motion.angle(t_file) - angle_file)) < 1e-12  # the spline interpolates
    assert np.max(np.abs(s["wg_angle_rad"][0] - np.interp(t, t_file, angle_file))) < 1e-4  # ~ 1/N of a step
    torque = np.interp(t, profile["time"] - profile["time"][0], profile["torque"])
    assert np.max(np.abs(s["load_torque_Nm"][0] - torque)) < 0.1
    # a constant load of −25 N·m (beyond T1 and beyond the micro-slip torque): the twist is
    # the catalog three-segment law plus half the backlash plus the slip range (1 %: the
    # slider's rounded stops, 2 % of s_max)
    unit, cat = load_unit(), catalog_entry("CSG-25-100")
    load = np.median(torque)
    assert abs(load) > cat["T1"]
    expected = (three_segment_twist(load, cat["T1"], cat["T2"], cat["K1"], cat["K2"], cat["K3"])
                + np.sign(load) * (float(unit.backlash.gap) / 2 + float(unit.friction.slip_max)))
    assert np.median(s["twist_rad"][0]) == pytest.approx(expected, rel=0.01)


def test_measured_profile_relative_path_and_speed_column(tmp_path):
    t = np.linspace(0.0, 0.5, 60)
    rows = "\n".join(f"{a},{b}" for a, b in zip(t, 300.0 * np.sin(np.pi * t / 0.5) ** 2))
    (tmp_path / "motor.csv").write_text("# from the motor drive\ntime_s,wg_speed_rpm\n" + rows + "\n")
    (tmp_path / "sc.toml").write_text(
        f'name = "m"\nsetup = "{SETUP}"\n[input]\nmode = "prescribed"\nprofile = "csv"\ncsv = "motor.csv"\n')
    bench = bench_from_scenario(load_unit(), load_scenario(tmp_path / "sc.toml"))
    # angle = integral of the speed: 300 rpm * 0.25 s = 1.25 turns
    assert bench.motion.angle(0.5) == pytest.approx(2 * np.pi * 300 / 60 * 0.25, rel=1e-3)


@pytest.mark.parametrize("text, message", [
    ("time_s,wg_angle_rad\n0,0\n1,1\n", "at least 4 rows"),
    ("time,wg_angle_rad\n" + "".join(f"{i},{i}\n" for i in range(5)), "missing column time_s"),
    ("time_s,angle\n" + "".join(f"{i},{i}\n" for i in range(5)), "wg_angle_rad"),
    ("time_s,wg_angle_rad\n0,0\n1,1\n1,2\n3,3\n4,4\n", "strictly increasing"),
    ("time_s,wg_angle_rad\n0,0\n1,x\n2,2\n3,3\n4,4\n", "not a number"),
])
def test_bad_profile_files_are_refused(tmp_path, text, message):
    path = tmp_path / "p.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        read_profile_csv(path)


# --------------------------------------------------------------------------- batch
def test_batch_metrics_have_one_value_per_sample_and_match_single_runs():
    unit = load_unit()
    a2 = float(unit.kinematic_error.a2)
    sc = load_scenario(ROOT / "scenarios/constant_speed.toml").with_updates(
        {"input.speed_rpm": 300.0, "input.output_revolutions": 0.02, "input.settle_revolutions": 0.0,
         "input.ramp_s": 0.05, "input_friction.model": "none"})
    sc = Scenario({**sc.data, "metrics": ["transmission_accuracy", "order_spectrum"]}, sc.source)
    batch = run_scenario(unit.with_updates({"kinematic_error.a2": np.array([a2, 2 * a2])}), sc)
    single = run_scenario(unit.with_updates({"kinematic_error.a2": 2 * a2}), sc)
    for name, value in batch.metrics.items():
        assert np.shape(value) == (2,), name
        assert value[1] == pytest.approx(single.metrics[name][0], rel=1e-3, abs=1e-3), name
    assert batch.metrics["ke_order_2_arcsec"][1] / batch.metrics["ke_order_2_arcsec"][0] == pytest.approx(2, rel=0.02)


# --------------------------------------------------------------------------- metric functions
def test_metric_functions_on_synthetic_signals():
    N = 50
    wg = np.linspace(0.0, 2 * 2 * np.pi * N, 40001)  # two output revolutions of WG travel
    t = wg / 100.0
    a = arcsec_to_rad(np.array([3.0, 7.0, 1.0, 11.0]))
    q = (a[0] * np.sin(wg) + a[1] * np.sin(2 * wg + 0.3) + a[2] * np.cos(4 * wg)
         + a[3] * np.sin(wg / N + 1.0) + 1e-4)[None, :]
    window = (t[0], t[-1])
    amps = ke_metrics.order_amplitudes(t, wg, q, window, N, [1, 2, 4, 1 / N])
    assert rad_to_arcsec(np.array(amps)).ravel() == pytest.approx([3.0, 7.0, 1.0, 11.0], rel=1e-3)
    ta = ke_metrics.transmission_accuracy(t, wg, q, window, N)[0]
    assert ta == pytest.approx(np.max(q[0, t >= t[-1] / 2]) - np.min(q[0, t >= t[-1] / 2]), rel=1e-12)
    # a reverse pass over the same WG angles, offset by 20 arcsec: lost motion = 20 arcsec
    half = wg.size // 2
    fwd, rev = (t[0], t[half]), (t[half + 1], t[-1])
    wg2 = np.concatenate([wg[: half + 1], wg[half:0:-1]])
    q2 = np.concatenate([q[0, : half + 1], q[0, half:0:-1] + arcsec_to_rad(20.0)])[None, :]
    t2 = np.linspace(t[0], t[-1], wg2.size)
    fwd, rev = (t2[0], t2[half]), (t2[half + 1], t2[-1])
    lm = ke_metrics.lost_motion_on_reversal(t2, wg2, q2, fwd, rev)[0]
    assert rad_to_arcsec(lm) == pytest.approx(20.0, rel=1e-3)
    orders, spectrum = ke_metrics.order_spectrum(t, wg, q, window, N, max_order=5)
    assert rad_to_arcsec(spectrum[np.argmin(np.abs(orders - 2))]) == pytest.approx(7.0, rel=1e-3)


def test_driven_figures(short_ke_run):
    """The deviation figure draws each measured pass (deviation in arcsec against output
    angle in degrees) and the time figure draws the signals of the run.

    The figures, not the contract numbers, are checked here, so the session's shortened
    contract run (``short_ke_run``: the same profile and metrics, 0.02 output revolutions a
    pass) is drawn; the full run's numbers are checked in ``test_driven_physics.py``."""
    from hdsim.plotting.driven import plot_deviation, plot_driven_time

    run = short_ke_run
    s, t = run.result.signals, run.result.t
    windows = run.result.metadata["windows"]
    travel = float(run.scenario.data["input"]["output_revolutions"])  # output revolutions a pass
    fig = plot_deviation(run)
    lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
    assert set(lines) == {"forward", "reverse"}
    for name, line in lines.items():
        a, b = windows[name]
        m = (t >= a) & (t <= b)
        np.testing.assert_allclose(line.get_xdata(), np.rad2deg(s["wg_angle_rad"][0, m] / 100.0))
        np.testing.assert_allclose(line.get_ydata(), rad_to_arcsec(s["deviation_rad"][0, m]))
        # the drawn pass is the measured window: its peak-to-peak is the pass's accuracy
        # and it spans the pass's output travel
        assert np.ptp(line.get_ydata()) == pytest.approx(
            run.metric(f"transmission_accuracy_{name}_arcsec"), rel=1e-9)
        assert np.ptp(line.get_xdata()) == pytest.approx(360.0 * travel, rel=0.01)
    fig = plot_driven_time(run)
    top, middle, bottom = fig.axes
    drawn = {line.get_label(): line.get_ydata() for line in bottom.get_lines()}
    np.testing.assert_allclose(drawn["load torque"], s["load_torque_Nm"][0])
    np.testing.assert_allclose(drawn["drive torque"], s["drive_torque_Nm"][0])
    drawn = {line.get_label(): line.get_ydata() for line in middle.get_lines()}
    np.testing.assert_allclose(drawn["output − WG/N"], rad_to_arcsec(s["deviation_rad"][0]))


# --------------------------------------------------------------------------- command line
def test_cli_simulate_driven_json(tmp_path, cli, monkeypatch, png_image, short_ke_run):
    """``hdsim simulate`` on a driven scenario: its JSON, run file and figures. The run it
    asks for (the contract scenario shortened by --set) is the session's ``short_ke_run``
    (conftest.py; the brake check of test_driven_physics.py uses it too): the verb gets that
    run, after checking it asked for exactly that drive and scenario, instead of making it
    a second time."""
    from hdsim.cli import simulate

    asked = []

    def shared_run(model, scenario, evaluator="dynamic"):
        assert evaluator == "dynamic"  # the default of simulate: the time series is the product
        unit = load_unit("CSG-25-100")
        assert model.name == unit.name and model.params() == unit.params()
        assert {k: e.id for k, e in model.effects().items()} == {k: e.id for k, e in unit.effects().items()}
        assert scenario.data == short_ke_run.scenario.data  # --set reached the scenario
        asked.append(scenario.name)
        return short_ke_run

    monkeypatch.setattr(simulate, "run_scenario", shared_run)
    code, stdout, err = cli("simulate", ROOT / "scenarios/kinematic_error.toml", "--unit", "CSG-25-100",
                            "--set", "scenario.input.output_revolutions=0.02",
                            "--set", "scenario.input.settle_revolutions=0.01", "--out", tmp_path, "--json")
    assert code == 0, err
    assert asked == ["kinematic_error"]
    payload = json.loads(stdout)
    assert payload["scenario"] == "kinematic_error" and payload["unit"] == "CSG-25-100"
    assert set(payload["metrics"]) >= {"transmission_accuracy_arcsec", "lost_motion_on_reversal_arcsec",
                                       "windup_arcsec", "ke_order_2_arcsec"}
    stored = read_run(payload["result"])
    for name, value in payload["metrics"].items():
        assert stored.metrics[name][0] == pytest.approx(value), name
    assert stored.result.setup == SETUP
    assert stored.scenario.data["input"]["output_revolutions"] == 0.02  # --set reached it
    png_image(tmp_path / "kinematic_error_deviation.png")
    png_image(tmp_path / "kinematic_error_time.png")


def test_cli_bad_driven_scenario_exits_2(tmp_path, cli):
    bad = tmp_path / "bad.toml"
    bad.write_text(f'name = "b"\nsetup = "{SETUP}"\n[input]\nmode = "prescribed"\nprofile = "warp"\n')
    code, stdout, err = cli("simulate", bad, "--out", tmp_path / "out", "--json")
    assert code == 2 and "input.profile" in err and len(err.strip().splitlines()) == 1
    assert stdout == "" and not (tmp_path / "out").exists()
