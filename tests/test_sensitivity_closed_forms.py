"""Estimator checks against closed forms with analytic Sobol' indices."""

import numpy as np
import pytest

from hdsim.sensitivity import GFunction, Ishigami, Linear, run_study
from hdsim.sensitivity.analysis import estimates, salib_indices
from hdsim.sensitivity.design import block_size, replicate_seed, sample_replicate


def test_analytic_values_match_reference():
    ish, g = Ishigami().analytic(), GFunction().analytic()
    np.testing.assert_allclose(ish["S1"], [0.3139, 0.4424, 0.0], atol=1e-4)
    np.testing.assert_allclose(ish["ST"], [0.5576, 0.4424, 0.2437], atol=1e-4)
    np.testing.assert_allclose(g["S1"][:4], [0.7162, 0.1790, 0.0237, 0.0072], atol=1e-4)
    np.testing.assert_allclose(g["ST"][:4], [0.7871, 0.2422, 0.0343, 0.0105], atol=1e-4)


@pytest.mark.parametrize("func", [Ishigami(), GFunction()], ids=["ishigami", "gfunction"])
def test_indices_within_002_at_n4096(func):
    res = run_study(func, func.problem(), 4096, seed=0, workers=1, progress=False)
    exact = func.analytic()
    assert res.evaluations == 4096 * (func.problem().num_vars + 2)
    assert np.abs(res.analysis["S1"] - exact["S1"]).max() <= 0.02
    assert np.abs(res.analysis["ST"] - exact["ST"]).max() <= 0.02
    assert res.checks["ok"], res.checks


def test_ishigami_second_order_s13():
    f = Ishigami()
    res = run_study(f, f.problem(), 4096, seed=0, second_order=True, workers=1, progress=False)
    assert res.evaluations == 4096 * (2 * 3 + 2)
    assert abs(res.analysis["S2"][0, 2] - f.analytic()["S2"][0, 2]) <= 0.03
    assert abs(res.analysis["S2"][0, 1]) <= 0.03 and abs(res.analysis["S2"][1, 2]) <= 0.03


def test_linear_model_is_additive_within_intervals():
    f = Linear()  # uniform, log-uniform and normal inputs
    res = run_study(f, f.problem(), 1024, seed=0, workers=1, progress=False)
    a, exact = res.analysis, f.analytic()["S1"]
    # S_i = ST_i = b_i² σ_i² / Σ b_j² σ_j²
    gap = np.abs(a["S1"] - a["ST"])
    assert np.all(gap <= a["S1_conf_replicates"] + a["ST_conf_replicates"])
    assert np.abs(a["S1"] - exact).max() <= 0.01
    assert np.abs(a["ST"] - exact).max() <= 0.01
    assert abs(a["S1"].sum() - 1) <= 0.01 and res.checks["ok"]


@pytest.mark.parametrize("second_order", [False, True])
def test_own_estimator_reproduces_salib(second_order):
    f = Ishigami()
    p = f.problem()
    X = sample_replicate(p, 256, replicate_seed(3, 0), second_order)
    Y = f(X)
    ours = estimates(Y.reshape(-1, block_size(3, second_order)), 3, second_order)
    theirs = salib_indices(p, Y, second_order, 0.95, 10, 0)
    for key in ("S1", "ST") + (("S2",) if second_order else ()):
        np.testing.assert_allclose(ours[key], theirs[key], atol=1e-12)


def test_replicate_intervals_narrower_than_bootstrap_on_smooth_model():
    # Reference §4: the iid bootstrap ignores QMC variance reduction.
    f = Linear()
    a = run_study(f, f.problem(), 1024, workers=1, progress=False).analysis
    assert np.median(a["S1_conf_replicates"]) < np.median(a["S1_conf"])


def test_bootstrap_reproduces_salib_analyze_exactly():
    from SALib.analyze import sobol

    from hdsim.sensitivity.analysis import bootstrap_seed

    f = Ishigami()
    p = f.problem()
    Y = f(sample_replicate(p, 512, 9, True))
    ours = salib_indices(p, Y, True, 0.95, 100, 4)
    ref = sobol.analyze({"num_vars": 3, "names": list(p.names), "bounds": list(p.bounds)}, Y,
                        calc_second_order=True, num_resamples=100, seed=bootstrap_seed(4))
    for key in ("S1", "S1_conf", "ST", "ST_conf", "S2", "S2_conf"):
        want = np.asarray(ref[key])
        if key.startswith("S2"):
            want = np.triu(np.nan_to_num(want), 1)
        np.testing.assert_allclose(ours[key], want, rtol=0, atol=1e-14)


def test_batched_bootstrap_is_the_same_statistic(monkeypatch):
    import hdsim.sensitivity.analysis as analyse_mod

    f = GFunction()
    p = f.problem()
    Y = f(sample_replicate(p, 1024, 2, False))
    whole = salib_indices(p, Y, False, 0.95, 200, 0)
    monkeypatch.setattr(analyse_mod, "BOOT_ELEMENTS", 1024 * 16)  # 13 batches
    batched = salib_indices(p, Y, False, 0.95, 200, 0)
    np.testing.assert_array_equal(whole["S1"], batched["S1"])
    # Different resamples, same statistic: agree to bootstrap noise (~1/sqrt(2B)).
    np.testing.assert_allclose(batched["S1_conf"][:4], whole["S1_conf"][:4], rtol=0.25)


class _NearlyConstant:
    """An output that varies across the design by 1e-6 of its value, from a simulator that
    resolves 1e-4 of it: what the indices of such a study show is the simulator's error."""

    def __call__(self, X):
        X = np.atleast_2d(X)
        return 42.5 + 1e-6 * 42.5 * X[:, 0]

    def resolution(self, y):
        return 1e-4 * float(np.mean(np.abs(y)))


def test_a_study_of_an_output_below_the_simulators_resolution_is_flagged():
    from hdsim.sensitivity.checks import RESOLVED_SPREAD, resolution_flags
    from hdsim.sensitivity.problem import build_problem

    assert resolution_flags([1.0, 2.0, 3.0], 0.01) == []
    assert resolution_flags([1.0, 1.0 + 1e-9], 0.01) and resolution_flags([1.0, 2.0], None) == []
    problem = build_problem(["a", "b"], {}, None, {"a": (0.0, 1.0), "b": (0.0, 1.0)}, None)
    result = run_study(_NearlyConstant(), problem, 64, workers=1, progress=False, log=lambda *a: None)
    assert not result.checks["ok"]
    assert any("the simulator's resolution" in flag and f"{RESOLVED_SPREAD:g}x" in flag
               for flag in result.checks["flags"])
    # the scenario outputs say how finely they resolve: the solver's tolerance of their value
    from hdsim.sensitivity.scenario_outputs import STUDY_SOLVER, ScenarioMetric

    metric = ScenarioMetric("CSG-25-100", ("flexspline.h_pz",), "transmission_accuracy_arcsec", "kinematic_error")
    assert metric.resolution(np.array([42.0, 43.0])) == pytest.approx(STUDY_SOLVER.rtol * 42.5)


def test_a_quasistatic_outputs_resolution_is_at_least_its_distance_from_the_dynamic_model():
    from hdsim.sensitivity.scenario_outputs import ScenarioMetric

    metric = ScenarioMetric("CSG-25-100", ("flexspline.h_pz",), "transmission_accuracy_arcsec", "kinematic_error",
                            evaluator="quasistatic", choice={"figures": {"quasistatic_gap": 0.007}})
    assert metric.resolution(np.array([42.49, 42.50])) == pytest.approx(0.007)  # not 1e-6 × 42.5
    assert metric.resolution(np.array([4e4, 4.2e4])) == pytest.approx(1e-6 * 4.1e4)


def test_a_metric_keeps_the_gap_it_measures_in_a_choice_of_its_own_not_in_the_dict_it_was_given(monkeypatch):
    # resolution() had written the gap into the caller's dict, which another metric then took for its own
    from hdsim.sensitivity import scenario_outputs

    monkeypatch.setattr(scenario_outputs, "_quasistatic_gap", lambda *args: 0.007)
    given = {"chosen": "quasistatic", "figures": {"first_period_s": 0.01}}
    metric = scenario_outputs.ScenarioMetric("CSG-25-100", ("flexspline.h_pz",), "transmission_accuracy_arcsec",
                                             "kinematic_error", evaluator="quasistatic", choice=given)
    assert metric.resolution(np.array([42.49, 42.50])) == pytest.approx(0.007)
    assert given == {"chosen": "quasistatic", "figures": {"first_period_s": 0.01}}
    assert metric.choice == {"chosen": "quasistatic", "figures": {"first_period_s": 0.01, "quasistatic_gap": 0.007}}


@pytest.mark.slow
def test_a_quasistatic_study_that_varies_less_than_the_evaluators_distance_from_the_dynamic_model_is_flagged():
    # the transmission accuracy moves by ~0.002 arcsec over a ±10 % box, through the
    # quasi-static evaluator by ten times the dynamic model's change and the other way: its
    # distance from the dynamic model on the nominal drive (~0.007 arcsec) is its resolution
    import hdsim

    result = hdsim.sobol("CSG-25-100", ["h_pz", "h_c"], "transmission_accuracy_arcsec", n=16, progress=False)
    gap = result.extra["evaluator"]["figures"]["quasistatic_gap"]
    assert result.extra["evaluator"]["chosen"] == "quasistatic" and 1e-3 < gap < 0.05
    assert not result.checks["ok"]
    assert any("the simulator's resolution" in flag for flag in result.checks["flags"])


def test_a_study_of_the_stiffness_test_computes_the_metric_hdsim_simulate_reports():
    # a study's stiffness run had 40 output samples a segment, and its K1 was 20 % low
    import hdsim
    from hdsim.sensitivity.scenario_outputs import model_function, nominal_values

    nominal = hdsim.run_scenario(hdsim.load_unit("CSG-25-100"), "stiffness", evaluator="quasistatic").metrics
    for output in ("K1_Nm_per_rad", "torsion_at_rated_arcmin", "lost_motion_centre_line_arcmin"):
        f = model_function("CSG-25-100", ["h_pz"], output, evaluator="quasistatic")
        h_pz = nominal_values("CSG-25-100", ["h_pz"])
        assert f(np.array([list(h_pz.values())]))[0] == pytest.approx(float(np.ravel(nominal[output])[0]), rel=1e-3)


class _RefusesACorner:
    """x1 + x2, refused (NaN) where x1 > 0.6: a range whose corner the model does not accept."""

    def __call__(self, X):
        X = np.atleast_2d(X)
        return np.where(X[:, 0] > 0.6, np.nan, X[:, 0] + X[:, 1])


def test_a_study_that_dropped_many_blocks_is_flagged_and_one_that_dropped_few_is_not():
    from hdsim.sensitivity.checks import dropped_flags
    from hdsim.sensitivity.problem import build_problem

    assert dropped_flags(95, 5) == [] and dropped_flags(60, 40)
    problem = build_problem(["a", "b"], {}, None, {"a": (0.0, 1.0), "b": (0.0, 1.0)}, None)
    result = run_study(_RefusesACorner(), problem, 64, workers=1, progress=False, log=lambda *a: None)
    assert result.analysis["blocks_dropped"] > 0.3 * 64  # 35 of 64 had passed every check
    assert not result.checks["ok"]
    assert any("blocks were dropped" in flag for flag in result.checks["flags"])
