"""The evaluator choice: the quasi-static evaluator stands in for solve_ivp where the bench's
criterion says it may, and agrees with it there.

The dynamic model (solve_ivp) is the reference throughout; the agreement is measured on
rows of the seed study's box (five flexspline dimensions within ±10 %), and the criterion
against its closed form (the period of a linear spring and the output inertia).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model import effects as fx
from hdsim.model.catalog import load_unit
from hdsim.scenarios.evaluator import choose_evaluator
from hdsim.scenarios.locked import MIN_PERIODS_PER_RAMP, first_period, quasistatic_criterion
from hdsim.scenarios.registry import get_setup
from hdsim.scenarios.run import read_run, run_scenario
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario
from hdsim.sensitivity.scenario_outputs import ScenarioMetric, model_function, nominal_values

SEED_BOX = ("flexspline.h_pz", "flexspline.h_c", "flexspline.R_v", "flexspline.R_k", "flexspline.h_p")


def _seed_box_rows(n, seed=0):
    nominal = np.array(list(nominal_values("CSG-25-100", SEED_BOX).values()))
    return nominal * (1.0 + 0.1 * (2.0 * np.random.default_rng(seed).random((n, len(SEED_BOX))) - 1.0))


def test_the_lost_motion_of_256_rows_of_the_seed_box_agrees_with_solve_ivp_within_1e_3():
    X = _seed_box_rows(256)
    lost_motion = "lost_motion_arcmin"
    dynamic = ScenarioMetric("CSG-25-100", SEED_BOX, lost_motion, "lost_motion", evaluator="dynamic")(X)
    quasistatic = ScenarioMetric("CSG-25-100", SEED_BOX, lost_motion, "lost_motion", evaluator="quasistatic")(X)
    assert np.all(np.isfinite(dynamic)) and np.ptp(dynamic) > 50 * 1e-3 * np.mean(dynamic)  # 50x the tolerance
    np.testing.assert_allclose(quasistatic, dynamic, rtol=1e-3)


def test_a_study_of_the_lost_motion_test_chooses_the_quasistatic_evaluator_and_says_why():
    func = model_function("CSG-25-100", ["h_pz"], "lost_motion_arcmin")
    assert func.evaluator == "quasistatic" and func.choice["requested"] == "auto"
    figures = func.choice["figures"]
    assert figures["periods_per_ramp"] >= MIN_PERIODS_PER_RAMP
    assert figures["shortest_ramp_s"] == pytest.approx(figures["periods_per_ramp"] * figures["first_period_s"])
    assert model_function("CSG-25-100", ["h_pz"], "lost_motion_arcmin", evaluator="dynamic").evaluator == "dynamic"


def test_the_first_period_of_a_linear_drive_is_two_pi_root_j_over_k():
    unit = load_unit("CSG-25-100").with_effects(hardening=fx.NO_EFFECT["hardening"])
    expected = 2.0 * np.pi * np.sqrt(unit.drive.J_out / unit.base_stiffness)
    assert first_period(unit, 0.04) == pytest.approx(expected, rel=1e-12)
    # a hardening law stiffens: its shortest period is shorter
    assert first_period(load_unit("CSG-25-100"), 1.0) < expected


def test_auto_keeps_the_dynamic_model_where_the_criterion_fails():
    unit = load_unit("CSG-25-100")
    stiffness = load_scenario(builtin_scenario_path("stiffness"))
    holds, reason, _ = quasistatic_criterion(unit, stiffness)
    assert not holds and "zero torque" in reason  # hysteresis loss, centre line, K1 read it
    lost_motion = load_scenario(builtin_scenario_path("lost_motion"))
    period = first_period(unit, lost_motion.data["load"]["amplitude"])
    ramp = float(np.min(np.diff(lost_motion.times())))
    # a ramp 10x shorter than the criterion allows: the output inertia matters
    fast = lost_motion.with_updates({"load.rate": lost_motion.data["load"]["rate"] * ramp / (10.0 * period)})
    holds, reason, figures = quasistatic_criterion(unit, fast)
    assert not holds and "inertia" in reason and figures["periods_per_ramp"] == pytest.approx(10.0, rel=1e-9)
    choice = choose_evaluator(get_setup(fast.setup), unit, fast, "auto")
    assert choice.chosen == "dynamic" and choice.reason == reason


def test_a_bench_without_a_quasistatic_evaluator_is_refused_it():
    """Both benches bring one; a bench registered without one (a user's) keeps the dynamic
    model under "auto" and refuses "quasistatic" in one line."""
    from dataclasses import replace

    unit = load_unit("CSG-25-100")
    scenario = load_scenario(builtin_scenario_path("kinematic_error"))
    bare = replace(get_setup(scenario.setup), quasistatic_runner=None, quasistatic_criterion=None)
    with pytest.raises(InputError, match="no quasi-static evaluator"):
        choose_evaluator(bare, unit, scenario, "quasistatic")
    assert choose_evaluator(bare, unit, scenario, "auto").chosen == "dynamic"
    with pytest.raises(InputError, match="evaluator"):
        run_scenario(unit, "lost_motion", evaluator="fast")


def test_a_quasistatic_run_is_saved_and_read_back_with_its_evaluator(tmp_path):
    run = run_scenario(load_unit("CSG-25-100"), "lost_motion", samples_per_segment=10, evaluator="auto")
    assert run.result.solver["method"] == "quasistatic" and run.result.batch == 1
    assert set(run.result.signals) == {"torque_Nm", "twist_rad", "drive_torque_Nm"}
    again = read_run(run.save(tmp_path / "run.h5"))
    assert again.result.metadata["evaluator"] == "quasistatic"
    assert again.metrics["lost_motion_arcmin"] == pytest.approx(run.metrics["lost_motion_arcmin"], rel=1e-12)


def test_the_cli_study_reports_its_evaluator_and_refuses_to_resume_with_another(tmp_path, cli):
    args = ["sobol", "--unit", "CSG-25-100", "--params", "h_pz,h_c", "--range", "10%",
            "--output", "lost_motion_arcmin", "--n", "16", "--workers", "1", "--out", tmp_path / "s.h5"]
    code, out, err = cli(*args, "--json")
    assert code == 0, err
    summary = json.loads(out)
    choice = summary["evaluator"]
    assert choice["chosen"] == summary["model"]["evaluator"] == "quasistatic"
    assert "first_period_s" in choice["figures"]
    code, out, err = cli(*args, "--resume", "--evaluator", "quasistatic")  # the same evaluator
    assert code == 0, err
    code, out, err = cli(*args, "--resume", "--evaluator", "dynamic")
    assert code == 2 and "different study" in err, err


@pytest.mark.slow
def test_the_seed_study_total_indices_agree_within_0_01():
    """The seed paper's study (N = 1024, second order, 12,288 rows) through both evaluators."""
    import hdsim

    names = ["h_pz", "h_c", "R_v", "R_k", "h_p"]
    runs = {ev: hdsim.sobol("CSG-25-100", names, "lost_motion_arcmin", n=1024, second_order=True,
                            progress=False, evaluator=ev) for ev in ("quasistatic", "dynamic")}
    np.testing.assert_allclose(runs["quasistatic"].analysis["ST"], runs["dynamic"].analysis["ST"], atol=0.01)
    np.testing.assert_allclose(runs["quasistatic"].analysis["S1"], runs["dynamic"].analysis["S1"], atol=0.01)


def test_a_study_pool_starts_after_the_compiled_evaluator_ran_in_the_same_process():
    """GNU OpenMP (numba's threading layer here) aborts forked children; a local pool
    started after a compiled quasi-static run must still work (it starts from a fork server)."""
    import subprocess
    import sys

    pytest.importorskip("numba")
    script = (
        "import hdsim\n"
        "from hdsim.scenarios.run import run_scenario\n"
        "run_scenario(hdsim.load_unit('CSG-25-100'), 'lost_motion', evaluator='quasistatic')\n"
        "r = hdsim.sobol('CSG-25-100', ['h_pz', 'h_c'], 'lost_motion_arcmin', n=16, workers=2, progress=False)\n"
        "print(r.evaluations)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "64"
