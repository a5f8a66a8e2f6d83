"""The smooth hardening's fit coordinates: the curvature at small load and the transition
torque map onto the law as physics.md §5.3 states."""

import numpy as np
import pytest

from hdsim.identification.fit import build_model
from hdsim.identification.problem import Evaluator, make_problem
from hdsim.io.measurement import make_measurement

PEAK = 87.0  # N·m


def _problem():
    t = np.linspace(0.0, 4.0, 401)  # holds the peak at t = 1 s
    torque = PEAK * np.sin(2.0 * np.pi * t / 4.0)
    meas = make_measurement("stiffness", t, torque, torque / 3.0e4, rated_torque=87.0)
    model = build_model(None, {"hardening": "tanh"}, meas)
    return make_problem(model, meas, Evaluator(meas))


def _fitted_law(prob, **values):
    """The model a fit at ``values`` (fit coordinates by local name) stands for."""
    phys = {n: float(tr.to_phys(u)) for n, tr, u in zip(prob.names, prob.transforms, prob.u)}
    phys.update({f"hardening.{k}": v for k, v in values.items()})
    U = np.array([[tr.to_internal(phys[n]) for n, tr in zip(prob.names, prob.transforms)]])
    updates = {k: np.asarray(v).reshape(-1)[0] for k, v in prob.updates(U).items()}
    model = prob.model.with_updates(updates)
    c_struct, c_mesh = model.split()
    return model, c_struct, c_mesh


def test_the_curvature_is_the_small_load_stiffening():
    """Taylor expansion of the tanh law: ``k(T) = K0 (1 + (K∞/K0 − 1)(T/T_s)²)`` to second
    order, i.e. ``K0 (1 + curvature·T²)`` with ``T ≈ K0 φ``."""
    curvature, T_s = 2.0e-4, 40.0  # ratio 1.32
    model, cs, cm = _fitted_law(_problem(), curvature=curvature, T_s=T_s)
    h = model.hardening
    K0 = 1.0 / (cs + cm)
    assert h.T_s == pytest.approx(T_s, rel=1e-12)
    for T in (1.0, 3.0):
        phi = T / K0
        assert h.tangent(phi, cs, cm) == pytest.approx(K0 * (1.0 + curvature * T**2), rel=1e-4)


def test_the_stiffness_ratio_is_one_plus_curvature_times_T_s_squared_capped_at_40():
    prob = _problem()
    for curvature, T_s, ratio in ((2.0e-4, 40.0, 1.32), (0.1, 40.0, 40.0)):
        model, cs, cm = _fitted_law(prob, curvature=curvature, T_s=T_s)
        K0, K_inf = 1.0 / (cs + cm), 1.0 / (cs + cm / model.hardening.e_inf)
        assert K_inf / K0 == pytest.approx(ratio, rel=1e-9)


def test_a_fit_cannot_put_the_transition_near_zero_torque():
    """The bound of physics.md §5.3: T_s at least 5 % of the record's peak torque."""
    prob = _problem()
    i = prob.names.index("hardening.T_s")
    low = prob.transforms[i].to_phys(np.array([-50.0, 0.0, 50.0]))
    assert np.all(low >= 0.05 * PEAK * (1.0 - 1e-12))
    assert low[0] == pytest.approx(0.05 * PEAK, rel=1e-9)
