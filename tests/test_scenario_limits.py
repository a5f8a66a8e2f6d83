"""Scenario files that would exhaust memory or run for hours are refused before anything
is allocated, with the estimate and the limit in one line."""

from __future__ import annotations

import pytest

from hdsim.errors import InputError
from hdsim.scenarios.scenario import Scenario


def _locked(**load):
    base = {"amplitude": 0.04, "cycles": 2, "rate": 0.04}
    base.update(load)
    return {"name": "x", "setup": "locked_wave_generator", "metrics": ["lost_motion"], "load": base}


@pytest.mark.parametrize("data, match", [
    (_locked(cycles=10**7), "load.cycles"),
    (_locked(rate=1e-9), "bench time"),
    (dict(_locked(), output={"samples_per_segment": 10**8}), "output samples"),
    (dict(_locked(), output={"samples_per_segment": 1}), "at least 2"),
])
def test_absurd_sizes_are_refused_with_the_estimate(data, match, monkeypatch):
    import hdsim.simulation.solver as solver

    def no_solver(*args, **kwargs):  # the refusal must come before any integration
        raise AssertionError("the solver was called")

    monkeypatch.setattr(solver, "solve_ivp", no_solver)
    with pytest.raises(InputError, match=match) as info:
        Scenario(data, "big.toml")
    assert "limit" in str(info.value) or "at least" in str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("rate", [float("inf"), float("nan"), 0.0])
def test_a_rate_that_is_not_a_finite_positive_number_is_refused(rate):
    with pytest.raises(InputError, match="load.rate a finite number"):
        Scenario(_locked(rate=rate), "rate.toml")


def test_a_catalog_test_is_far_inside_the_limits():
    Scenario(_locked(cycles=3, rate=0.04), "ok.toml")


@pytest.fixture
def no_solver(monkeypatch):
    """The refusal must come before any integration: the solver raises if it is reached."""
    import hdsim.simulation.solver as solver

    def refuse(*args, **kwargs):
        raise AssertionError("the solver was called")

    monkeypatch.setattr(solver, "solve_ivp", refuse)


@pytest.mark.parametrize("updates, match", [
    ({"input.output_revolutions": 1e5}, "bench time"),            # a typo in the travel: days of bench time
    ({"output.sample_rate_Hz": 1e8}, "output samples"),            # 26 s at 100 MHz
    ({"solver.max_step": 1e-9}, "solver steps"),                   # a step bound of a nanosecond
])
def test_absurd_driven_runs_are_refused_with_the_estimate(updates, match, no_solver):
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.run import run_scenario
    from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

    scenario = load_scenario(builtin_scenario_path("kinematic_error")).with_updates(updates)
    with pytest.raises(InputError, match=match) as info:
        run_scenario(load_unit(), scenario)
    assert "limit" in str(info.value) and "\n" not in str(info.value)


def test_a_batch_too_large_for_memory_is_refused_before_it_runs(no_solver):
    """Each sample alone is within the limits; 2,000 of them at once are not."""
    import numpy as np

    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.run import run_scenario

    scenario = Scenario(dict(_locked(cycles=5), output={"samples_per_segment": 1000}), "big.toml")
    batch = load_unit().with_updates({"flexspline.h_c": np.full(2000, 0.6e-3)})
    with pytest.raises(InputError, match="parameter sets"):
        run_scenario(batch, scenario)


def test_the_shipped_scenarios_are_far_inside_the_limits():
    """Every shipped scenario asks for under a tenth of each limit."""
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios import limits
    from hdsim.scenarios.driven import bench_from_scenario
    from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario
    from hdsim.simulation.solver import SolverOptions, step_schedule

    for name in ("kinematic_error", "constant_speed", "frequency_sweep", "point_to_point", "reversal"):
        bench = bench_from_scenario(load_unit(), load_scenario(builtin_scenario_path(name)))
        steps = sum((b - a) / o.max_step for a, b, o in step_schedule(bench, SolverOptions()))
        assert bench.t_end * bench.sample_rate < limits.MAX_SAMPLES / 10
        assert steps < limits.MAX_SOLVER_STEPS / 10


@pytest.mark.parametrize("evaluator", ["dynamic", "quasistatic"])
def test_a_torque_cycle_too_fast_to_be_static_is_refused_before_it_runs(evaluator, monkeypatch):
    """A ramp shorter than ten periods of the first mode: the loop would read the vibration (a
    rate of 1e3 T_N/s gave a negative lost motion); the limit is the first mode's, computed
    here with the same formula, 2π √(J / K_max)."""
    import numpy as np

    import hdsim.simulation.solver as solver
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.run import run_scenario

    monkeypatch.setattr(solver, "solve_ivp", lambda *a, **k: (_ for _ in ()).throw(AssertionError("solver called")))
    unit = load_unit("CSG-25-100")
    c_struct, c_mesh = unit.split()
    reach = np.linspace(0.0, 2.0 * 0.04 * unit.drive.rated_torque * (c_struct + c_mesh), 33)
    period = 2 * np.pi * np.sqrt(unit.drive.J_out / np.max(unit.hardening.tangent(reach[:, None], c_struct, c_mesh)))
    limit = 0.04 / (10.0 * period)  # a ramp of the ±4 % cycle lasts amplitude / rate
    with pytest.raises(InputError, match=rf"load.rate <= {limit:.3g}$"):
        run_scenario(unit, Scenario(_locked(rate=1.01 * limit), "fast.toml"), evaluator=evaluator)
    if evaluator == "quasistatic":  # just inside the limit it runs
        run = run_scenario(unit, Scenario(_locked(rate=0.99 * limit), "fast.toml"), evaluator=evaluator)
        assert run.metric("lost_motion_arcmin") > 0


@pytest.mark.parametrize("updates, match", [
    ({"flexspline.module": 1.0}, "module × teeth / 2 = .* must be the pitch radius"),
    ({"flexspline.teeth": 3.0}, "module × teeth / 2 = .* must be the pitch radius"),
    ({"flexspline.teeth": 200.5}, "must be a whole number of teeth"),
])
def test_teeth_that_do_not_fit_the_rim_are_refused(updates, match):
    """The module and tooth count set the pitch radius, m z / 2, which the rim sets too (one
    dedendum beyond the tooth root): a module changed alone (1 m instead of 0.3 mm moved the
    mesh compliance a thousandfold) or a tooth count that fits no rim is refused."""
    from hdsim.model.catalog import load_unit

    unit = load_unit("CSG-25-100")
    g = unit.geometry
    assert 0.5 * g.module * g.teeth == pytest.approx(float(g.pitch_radius), rel=1e-12)  # the catalog's own
    with pytest.raises(InputError, match=match):
        unit.with_updates(updates)
    unit.with_updates({"flexspline.h_pz": 1.1 * g.h_pz})  # a design study's ±10 % stays inside
