"""The driven bench's quasi-static evaluator against solve_ivp, and the criterion that allows it.

The reference is the dynamic contract kinematic-error run (solve_ivp at the scenario's
tolerance, the session's ``ke_run``); the bar is the same transmission accuracy
within 0.1 arcsec. The criterion is checked on the cases that must fail it: a motor loop,
a metric read outside constant-speed windows, a law not shown to agree, a presliding
stiffer than the bound, a path without losses.
"""

from __future__ import annotations

import numpy as np
import pytest

from hdsim.model import effects as fx
from hdsim.model.catalog import load_unit
from hdsim.scenarios.driven import bench_from_scenario, quasistatic_criterion
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import load_scenario
from hdsim.simulation.driven_quasistatic import MAX_STICKING_RATIO, _rigid_pass, step_grid
from hdsim.units import rad_to_arcsec


@pytest.fixture(scope="module")
def unit():
    return load_unit("CSG-25-100")


@pytest.fixture(scope="module")
def contract():
    return load_scenario("kinematic_error")


def test_the_contract_run_agrees_with_solve_ivp_within_a_tenth_of_an_arcsec(ke_run, unit, contract):
    quasi = run_scenario(unit, contract, evaluator="quasistatic")
    assert quasi.result.metadata["evaluator"]["chosen"] == "quasistatic"
    for name in ("transmission_accuracy_arcsec", "transmission_accuracy_forward_arcsec",
                 "transmission_accuracy_reverse_arcsec", "lost_motion_on_reversal_arcsec", "windup_arcsec",
                 "ke_order_2_arcsec", "ke_output_order_1_arcsec"):
        assert quasi.metric(name) == pytest.approx(ke_run.metric(name), abs=0.1), name
    # the signals too, not only the metrics read off them: the deviation sample by sample
    # in the measuring windows (outside them the brake's relaxation is dropped)
    t = ke_run.result.t
    assert np.array_equal(t, quasi.result.t)
    for a, b in ke_run.result.metadata["windows"].values():
        inside = (t >= a) & (t <= b)
        gap = quasi.result.signals["deviation_rad"][0, inside] - ke_run.result.signals["deviation_rad"][0, inside]
        assert rad_to_arcsec(np.max(np.abs(gap))) < 0.1
    # the windup is large against that bar: the agreement is not a comparison of zeros
    assert ke_run.metric("windup_arcsec") > 100.0


def test_auto_takes_the_quasistatic_evaluator_on_the_contract_run_and_says_why(unit, contract):
    holds, reason, figures = quasistatic_criterion(unit, contract)
    assert holds, reason
    assert figures["ripple_ratio"] < 1e-3 and figures["sticking_ratio"] < MAX_STICKING_RATIO
    assert figures["settle_before_window_s"] > 20 * figures["brake_relaxation_s"]


def test_the_criterion_refuses_a_motor_loop_and_metrics_outside_the_windows(unit, contract):
    from hdsim.scenarios.scenario import Scenario

    looped = contract.with_updates({"input.mode": "pi", "controller.bandwidth_Hz": 20.0})
    holds, reason, _ = quasistatic_criterion(unit, looped)
    assert not holds and "motor loop" in reason
    tracked = Scenario(dict(contract.data, metrics=["transmission_accuracy", "tracking"]), contract.source)
    holds, reason, _ = quasistatic_criterion(unit, tracked)
    assert not holds and "constant-speed windows" in reason


def test_the_criterion_refuses_laws_it_has_not_been_shown_to_reproduce(unit, contract):
    from hdsim.identification.fit import build_model

    maxwell = build_model(unit, {"friction": "maxwell_slip", "kinematic_error": "fourier"})
    holds, reason, _ = quasistatic_criterion(maxwell, contract)
    assert not holds and "maxwell_slip" in reason
    # a Coulomb law whose presliding is 43x stiffer than the spring
    coulomb = build_model(unit, {"friction": "coulomb", "kinematic_error": "fourier"})
    holds, reason, figures = quasistatic_criterion(coulomb, contract)
    assert not holds and figures["sticking_ratio"] > MAX_STICKING_RATIO and "sticks" in reason
    lossless = unit.with_effects(friction=fx.NO_EFFECT["friction"], damping=fx.NO_EFFECT["damping"])
    holds, reason, _ = quasistatic_criterion(lossless, contract)
    assert not holds and "never decays" in reason


def test_auto_keeps_the_dynamic_model_where_the_criterion_fails_and_forcing_says_so(unit, contract):
    from hdsim.identification.fit import build_model

    maxwell = build_model(unit, {"friction": "maxwell_slip", "kinematic_error": "fourier"})
    short = contract.with_updates({"input.output_revolutions": 0.002, "input.settle_revolutions": 0.001,
                                   "input.ramp_s": 0.02, "input.dwell_s": 0.01})
    run = run_scenario(maxwell, short, evaluator="auto")
    assert run.result.metadata["evaluator"]["chosen"] == "dynamic"
    forced = run_scenario(maxwell, short, evaluator="quasistatic")
    assert forced.result.metadata["evaluator"]["chosen"] == "quasistatic"
    assert "maxwell_slip" in forced.result.metadata["evaluator"]["reason"]


def test_a_maxwell_slip_law_runs_on_the_driven_bench_alone_as_in_a_batch(unit, contract):
    """The single-model path hands the law Python floats; its elements must stay per element."""
    from hdsim.identification.fit import build_model

    maxwell = build_model(unit, {"friction": "maxwell_slip", "kinematic_error": "fourier"})
    short = contract.with_updates({"input.output_revolutions": 0.002, "input.settle_revolutions": 0.001,
                                   "input.speed_rpm": 2000.0, "input.ramp_s": 0.02, "input.dwell_s": 0.01})
    alone = run_scenario(maxwell, short)
    pair = run_scenario(maxwell.with_updates({"drive.J_in": np.full(2, maxwell.drive.J_in)}), short)
    for name in ("windup_arcsec", "transmission_accuracy_arcsec"):
        np.testing.assert_allclose(pair.metrics[name], alone.metric(name), rtol=1e-4, atol=1e-3)


def test_the_step_grid_follows_the_torque_and_keeps_its_gap():
    torque = np.concatenate([np.zeros(500), np.linspace(0.0, 10.0, 101), np.full(500, 10.0)])
    grid = step_grid(torque, 0.5, 64)
    assert grid[0] == 0 and grid[-1] == torque.size - 1
    assert np.max(np.diff(grid)) <= 64
    on_ramp = grid[(grid >= 500) & (grid <= 600)]
    assert on_ramp.size >= 20 - 1  # 10 N·m in steps of 0.5
    assert np.all(np.diff(np.floor(np.interp(grid, np.arange(torque.size), torque) / 0.5)) <= 1 + 1e-12)


def test_the_inertial_load_of_the_kinematic_error_is_what_its_acceleration_asks(unit, contract):
    """τ = (T_L − J (α_w/N + ë)) / (1 − e_o): the ripple on the path is J ë, the closed form
    of the Fourier law's second derivative along the cruise."""
    bench = bench_from_scenario(unit, contract)
    t = bench.sample_times()
    rigid = _rigid_pass(unit, bench, t)
    a, b = bench.motion.windows["forward"]
    inside = (t > a + 0.05) & (t < b - 0.05)
    ke = unit.kinematic_error
    w = bench.motion.speed(t[inside])
    assert np.ptp(w) < 1e-9 * abs(w[0])  # cruise
    # the WG-order terms a_k sin(k θ_w + p_k): ë = −Σ a_k (k ω_w)² sin(k θ_w + p_k) (load constant)
    theta = bench.motion.angle(t[inside])
    expected = sum(-getattr(ke, f"a{k}") * (k * w[0]) ** 2 * np.sin(k * theta + getattr(ke, f"p{k}"))
                   for k in (1, 2, 4))
    measured = rigid["e_accel"][inside, 0]
    # the output-order term is 1/N slower and 1/N² weaker in acceleration: below 1e-3 of it;
    # the derivative by central differences of the sampled rate errs by (k ω h)²/6, 0.7 % of
    # the 4x term at 1 kHz, 0.4 % of the peak
    np.testing.assert_allclose(measured, expected * (1.0 + ke.load_gain * np.abs(rigid["frac"][inside, 0])),
                               rtol=0.02, atol=6e-3 * np.max(np.abs(expected)))


def test_a_transmission_accuracy_study_from_the_command_line_runs_quasi_statically_and_says_why(cli, tmp_path):
    import json

    code, out, err = cli("sobol", "--unit", "CSG-25-100", "--params", "h_pz", "--range", "10%",
                         "--output", "transmission_accuracy_arcsec", "--n", "16", "--workers", "1", "--json",
                         cwd=tmp_path)
    assert code == 0, err
    summary = json.loads(out)
    choice = summary["evaluator"]
    assert choice["requested"] == "auto" and choice["chosen"] == "quasistatic"
    assert choice["figures"]["ripple_ratio"] < 0.01 and "prescribed" in choice["reason"]
    assert summary["evaluations"] == 16 * (1 + 2) and not summary["failures"]
    # the evaluator's distance from solve_ivp (~0.007 arcsec) is more than the output moves: flagged
    assert 1e-3 < choice["figures"]["quasistatic_gap"] < 0.05
    assert any("the simulator's resolution" in flag for flag in summary["checks"]["flags"])
