"""The compiled quasi-static engine against the numpy one, law by law and end to end.

The numpy laws are the reference (they are the ones checked against closed forms and the
dynamic model in ``test_fit.py`` and ``test_effects.py``); every compiled twin must give
the same numbers, and the two engines the same twist to the Newton tolerance.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

pytest.importorskip("numba")

from hdsim.errors import InputError  # noqa: E402
from hdsim.model import effects as fx  # noqa: E402
from hdsim.model.catalog import load_unit  # noqa: E402
from hdsim.simulation.profiles import cosine_ramps  # noqa: E402
from hdsim.simulation.quasistatic import UnsupportedEffect, locked_twist, stack_models  # noqa: E402

UNIT = load_unit()
K = float(UNIT.base_stiffness)
C_STRUCT, C_MESH = (float(np.asarray(c)) for c in UNIT.split())
RNG = np.random.default_rng(7)


def _profile(n=2500, until=6.0):
    """±T_N cycles with a small ripple: reversals at several amplitudes (the first
    ``until`` seconds of 6, at the density of n samples over 6 s)."""
    f = cosine_ramps(np.array([0, 1, 3, 5, 6.0]), np.array([0, 87, -87, 87, 0.0]))
    t = np.linspace(0, until, int(round(n * until / 6.0)))
    return t, f(t) + 4.0 * np.sin(40 * t)


def _model(**effects):
    base = dict(hardening=fx.NO_EFFECT["hardening"], backlash=fx.NO_EFFECT["backlash"],
                friction=fx.NO_EFFECT["friction"], damping=fx.NO_EFFECT["damping"])
    base.update(effects)
    return UNIT.with_effects(**base)


HARDENING = [fx.NO_EFFECT["hardening"], fx.TanhHardening(e_inf=2.5, T_s=30.0),
             fx.ThreeSegmentHardening(T1=10.0, T2=40.0, e2=1.5, e3=2.5)]
FRICTION = [fx.NO_EFFECT["friction"], fx.DahlFriction(torque_max=4.0, sigma=2 * K), fx.CoulombFriction(torque=3.0),
            fx.MaxwellSlip(k_total=K, slip_torque_max=6.0, velocity_scale=1e-6),
            fx.DistributedSlip(slip_torque=8.0, slip_max=2e-4, spread=0.5),
            fx.DahlSlip(slip_torque=20.0, slip_max=1e-4)]
DAMPING = [fx.NO_EFFECT["damping"], fx.ViscousDamping(coefficient=300.0, stiffness_share=0.5)]
BACKLASH = [fx.NO_EFFECT["backlash"], fx.DeadZoneBacklash(gap=1.5e-4), fx.GradualDeadZone(gap=1e-4, contact_rounding=2.0)]


def _kernel(effect, size=1):
    functions, rows = effect.compiled(size, C_STRUCT, C_MESH)
    return functions, rows


# --------------------------------------------------------------------------- law by law


@pytest.mark.parametrize("law", HARDENING, ids=lambda e: e.id)
def test_each_spring_law_equals_its_numpy_law(law):
    (spring,), rows = _kernel(law)
    numpy_law = law.spring_law(C_STRUCT, C_MESH)
    for e in np.concatenate([RNG.normal(0, 3e-3, 200), [0.0, 1e-12, -1e-12, 0.5]]):
        with np.errstate(over="ignore"):  # cosh overflows far out on the tanh law, as it should
            u, k = numpy_law(e)
        cu, ck = spring(float(e), rows[0])
        assert cu == pytest.approx(float(u), rel=1e-12, abs=1e-12)
        assert ck == pytest.approx(float(k), rel=1e-12)


@pytest.mark.parametrize("law", FRICTION, ids=lambda e: e.id)
def test_each_friction_law_advances_and_bends_as_its_numpy_law(law):
    (friction_step,), rows = _kernel(law)
    hardening = HARDENING[1]  # a law beside or in series with a hardening spring
    (spring_c,), spring_rows = _kernel(hardening)
    spring = hardening.spring_law(C_STRUCT, C_MESH)
    n = len(law.state_names)
    states = np.zeros((n, 1))
    e0 = 0.0
    for e in np.cumsum(RNG.normal(0, 2e-4, 300)):  # a random walk: reversals of every size
        out = np.zeros(n)
        direction = 1.0 if e >= e0 else -1.0
        body, slope, u, k = friction_step(spring_c, spring_rows[0], states[:, 0].copy(), e0, float(e), direction,
                                          rows[0], out)
        B, D, reference, u_ref, k_ref = law.quasistatic(states, np.array([e0]), np.array([e]), spring)
        reference = np.asarray(reference, dtype=float).reshape(n, 1)
        np.testing.assert_allclose(out, reference[:, 0], rtol=1e-10, atol=1e-14)
        assert body == pytest.approx(float(np.asarray(B).reshape(-1)[0]), rel=1e-10, abs=1e-10)
        # a sliding slider's slope k (1 - share) is far below k, and the numpy path tangent
        # takes the share through a difference quotient: it agrees to round-off of k
        assert slope == pytest.approx(float(np.asarray(D).reshape(-1)[0]), rel=1e-10, abs=1e-13 * abs(k))
        assert (u, k) == pytest.approx((float(np.asarray(u_ref).reshape(-1)[0]),
                                        float(np.asarray(k_ref).reshape(-1)[0])), rel=1e-10, abs=1e-10)
        states, e0 = reference, float(e)


def test_the_series_law_counts_the_relays_on_their_curve_in_a_step_of_zero_length():
    # the slope the damping's rate uses: a step of zero twist must see the relays that
    # slip on as the load goes on, in both engines
    law = FRICTION[4]
    (friction_step,), rows = _kernel(law)
    (spring_c,), spring_rows = _kernel(HARDENING[0])
    spring = HARDENING[0].spring_law(C_STRUCT, C_MESH)
    e = 12.0 / K  # past the median threshold: relays on their curve
    _, _, states, u, k = law.quasistatic(np.zeros((6, 1)), np.array([0.0]), np.array([e]), spring)
    states = np.asarray(states, dtype=float)
    tangent = float(np.asarray(law.path_tangent(states, 1.0, u, k)).reshape(-1)[0])
    _, slope, _, _ = friction_step(spring_c, spring_rows[0], states[:, 0].copy(), e, e, 1.0, rows[0], np.zeros(6))
    assert tangent < 0.9 * float(np.asarray(k).reshape(-1)[0])  # the slip softens the body
    assert slope == pytest.approx(tangent, rel=1e-9)


@pytest.mark.parametrize("law", DAMPING, ids=lambda e: e.id)
def test_each_damping_law_equals_its_numpy_law(law):
    (damping,), rows = _kernel(law)
    for ratio in (1.0, 0.4, 3.0):
        assert damping(ratio, rows[0]) == pytest.approx(float(np.asarray(law.coefficient_at(ratio))), rel=1e-14)


@pytest.mark.parametrize("law", BACKLASH, ids=lambda e: e.id)
def test_each_dead_zone_equals_its_numpy_law(law):
    (gap_twist,), rows = _kernel(law)
    torque = np.concatenate([np.linspace(-90, 90, 2001), [0.0]])
    reference = np.asarray(law.twist_at_torque(torque, K), dtype=float) * np.ones_like(torque)
    compiled = np.array([gap_twist(T / K, rows[0]) for T in torque])
    np.testing.assert_allclose(compiled, reference, rtol=1e-12, atol=1e-15)


# --------------------------------------------------------------------------- end to end


COMBINATIONS = [dict(hardening=h, friction=f, damping=d, backlash=b)
                for h, f, d, b in [(HARDENING[1], FRICTION[1], DAMPING[1], BACKLASH[1]),
                                   (HARDENING[2], FRICTION[3], DAMPING[1], BACKLASH[2]),
                                   (HARDENING[0], FRICTION[2], DAMPING[0], BACKLASH[0]),
                                   (HARDENING[2], FRICTION[4], DAMPING[1], BACKLASH[1]),
                                   (HARDENING[0], FRICTION[0], DAMPING[0], BACKLASH[0]),
                                   (HARDENING[2], FRICTION[5], DAMPING[1], BACKLASH[1])]]


@pytest.mark.parametrize("effects", COMBINATIONS, ids=["tanh-dahl-viscous-gap", "3seg-maxwell-viscous-gradual",
                                                       "coulomb", "3seg-distributed-viscous-gap", "bare",
                                                       "3seg-dahl_slip-viscous-gap"])
def test_the_engines_give_one_twist(effects):
    # the numpy loop of the sub-stepped Dahl slider costs ~3 ms a step: its comparison
    # stops after the first reversal, at the same step size
    t, T = _profile(until=1.8 if isinstance(effects["friction"], fx.DahlSlip) else 6.0)
    model = _model(**effects)
    x_np, s_np = locked_twist(model, t, T, engine="numpy", return_states=True)
    x_c, s_c = locked_twist(model, t, T, engine="compiled", return_states=True)
    assert np.ptp(x_np) > 1.5e-3  # a real loop: to T_N and back past its reversal
    np.testing.assert_allclose(x_c, x_np, rtol=0, atol=3e-9)  # Newton stop x_tol = 1e-8 rad
    if np.size(s_np):
        np.testing.assert_allclose(np.asarray(s_c), np.asarray(s_np), rtol=0, atol=1e-6 * max(np.ptp(s_np), 1.0))


def test_a_mixed_batch_on_a_sub_grid_agrees_row_by_row():
    # a diagnosis pass: rows of different damping and friction, a long record stepped on a grid
    t, T = _profile(12000)
    model = _model(hardening=HARDENING[1], friction=FRICTION[1], damping=DAMPING[1], backlash=BACKLASH[2])
    batch = model.with_updates({"damping.coefficient": np.linspace(0.0, 2000.0, 12),
                                "friction.torque_max": np.linspace(0.5, 8.0, 12)})
    x_np = locked_twist(batch, t, T, grid=2000, engine="numpy", x_tol=1e-12)
    x_c = locked_twist(batch, t, T, grid=2000, engine="compiled", x_tol=1e-12)
    np.testing.assert_allclose(x_c, x_np, rtol=0, atol=1e-12)


def test_unsolvable_rows_are_nan_in_both_engines():
    t, T = _profile(400)
    model = _model(hardening=HARDENING[1], friction=FRICTION[1])
    batch = model.with_updates({"friction.torque_max": np.array([4.0, 4.0])})
    for engine in ("numpy", "compiled"):
        x = locked_twist(batch, t, T, engine=engine, max_iter=1, on_failure="nan")
        assert np.all(np.isnan(x))  # one Newton step cannot meet x_tol on a hardening spring
        with pytest.raises(Exception, match="not solved at sample"):
            locked_twist(batch, t, T, engine=engine, max_iter=1)


# --------------------------------------------------------------------------- which engine runs


class _RedefinedSlip(fx.DahlSlip):
    """A law as a user might write one: its rates are its own (here the parent's), so no
    compiled twin can stand for it."""

    def rates(self, states, body_rate, spring_torque, spring_tangent):
        return super().rates(states, body_rate, spring_torque, spring_tangent)


def test_a_law_without_a_compiled_twin_runs_in_numpy():
    t, T = _profile(100)  # twice in numpy: the fallback is what is checked, not the loop
    slip = _model(friction=_RedefinedSlip(slip_torque=20.0, slip_max=1e-4))  # in series with the spring
    assert slip.friction.compiled(1, C_STRUCT, C_MESH) is None
    np.testing.assert_array_equal(locked_twist(slip, t, T), locked_twist(slip, t, T, engine="numpy"))
    with pytest.raises(UnsupportedEffect, match="no compiled form"):
        locked_twist(slip, t, T, engine="compiled")


def test_a_subclass_that_changes_the_law_loses_the_compiled_twin():
    class Softer(fx.TanhHardening):
        def spring_law(self, c_struct, c_mesh):
            law = super().spring_law(c_struct, c_mesh)
            return lambda twist: tuple(0.5 * v for v in law(twist))

    law = Softer(e_inf=2.5, T_s=30.0)
    assert law.compiled(1, C_STRUCT, C_MESH) is None
    assert fx.TanhHardening(e_inf=2.5, T_s=30.0).compiled(1, C_STRUCT, C_MESH) is not None


def test_engine_by_argument_and_environment(monkeypatch):
    t, T = _profile(200)
    model = _model(hardening=HARDENING[1])
    with pytest.raises(InputError, match="engine must be one of"):
        locked_twist(model, t, T, engine="fortran")
    monkeypatch.setenv("HDSIM_ENGINE", "fortran")
    with pytest.raises(InputError, match="engine must be one of"):
        locked_twist(model, t, T)


def test_without_numba_auto_falls_back_and_compiled_says_how_to_install(monkeypatch):
    t, T = _profile(200)
    model = _model(hardening=HARDENING[1], friction=FRICTION[1])
    reference = locked_twist(model, t, T, engine="numpy")
    import hdsim.simulation

    monkeypatch.delattr(hdsim.simulation, "quasistatic_compiled", raising=False)
    monkeypatch.setitem(sys.modules, "hdsim.simulation.quasistatic_compiled", None)  # import fails
    np.testing.assert_array_equal(locked_twist(model, t, T), reference)
    with pytest.raises(InputError, match=r"pip install 'hdsim\[fast\]'"):
        locked_twist(model, t, T, engine="compiled")


def test_stacking_keeps_every_slot_compilable():
    # a diagnosis stacks candidates that lack a family: the neutral stand-ins have twins too
    models = [_model(hardening=HARDENING[1]), _model(friction=FRICTION[1], damping=DAMPING[1])]
    plan = stack_models(models)
    for effect in (plan.hardening, plan.friction, plan.damping, plan.backlash):
        functions, rows = effect.compiled(plan.size, plan.c_struct, plan.c_mesh)
        assert rows.shape[0] == plan.size and rows.flags.c_contiguous


def test_every_row_of_the_seed_box_solves_the_stiffness_test(default_stiffness_run):
    """Row 44 of a 64-row draw of the seed study's box (±10 % of the five dimensions): on the
    Dahl-slip path near the slider's stop the analytic slope is the path's, not the
    sub-stepped step's, and Newton steps landed on alternate sides of the root inside their
    bracket, 60 of them without converging; the step is now bisected on its bracket. Both
    engines solve every sample, give one twist, and follow the dynamic model as closely as
    the nominal unit's quasi-static twist follows its own."""
    from hdsim.scenarios.run import run_scenario
    from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

    nominal = load_unit("CSG-25-100")
    row = nominal.with_updates({
        "flexspline.h_pz": 0.0010850639250735822, "flexspline.h_c": 0.0006980099311450658,
        "flexspline.R_v": 0.0019589166776016347, "flexspline.R_k": 0.003283958147577747,
        "flexspline.h_p": 0.0003033479667643714})
    scenario = load_scenario(builtin_scenario_path("stiffness"))
    t = scenario.sample_times(40)
    T = scenario.torque_profile(87.0)(t)
    twist = {engine: locked_twist(row, t, T, engine=engine)[0] for engine in ("compiled", "numpy")}
    np.testing.assert_allclose(twist["compiled"], twist["numpy"], rtol=0, atol=1e-9)

    def off_dynamic(run, quasi_static):
        dynamic = np.interp(t, np.ravel(run.result.t), np.ravel(run.result.signals["twist_rad"]))
        return np.max(np.abs(dynamic - quasi_static)) / np.ptp(quasi_static)

    # the nominal unit's dynamic run is the session's shared one (the same unit and scenario)
    assert off_dynamic(run_scenario(row, scenario), twist["numpy"]) < 1.5 * off_dynamic(
        default_stiffness_run, locked_twist(nominal, t, T)[0])
