"""Distributed micro-slip (relays in series with the spring) against closed forms, an
independent Preisach model and the dynamic model.

The closed forms follow the law's definition in docs/physics.md ("distributed
micro-slip"): six relays at the mid-quantiles of a log-normal, each ``slip_max/6`` to a
side, switching over ``c_i ± c_i min(0.6 spread, 0.9)`` with the cubic ``x(3 − x²)/2``.
The Preisach reference is the truth zoo's (``tests/truth_zoo_forms.py``: an Everett
function tabulated on a grid, no hdsim code), with its interaction spread made small.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

import truth_zoo_forms as zf
from hdsim.model import effects as fx
from hdsim.model.catalog import load_unit
from hdsim.simulation.quasistatic import dynamic_locked_twist, locked_twist

UNIT = load_unit()
K = float(UNIT.base_stiffness)
LAW = fx.DistributedSlip(slip_torque=10.0, slip_max=1.5e-4, spread=0.4)


def bare(friction=LAW, **effects):
    base = dict(hardening=fx.NO_EFFECT["hardening"], backlash=fx.NO_EFFECT["backlash"],
                friction=friction, damping=fx.NO_EFFECT["damping"])
    base.update(effects)
    return UNIT.with_effects(**base)


def relays(law):
    c = law.slip_torque * np.exp(norm.ppf((np.arange(6) + 0.5) / 6) * law.spread)
    return c, c * min(0.6 * law.spread, 0.9), law.slip_max / 6


def smoothstep(x):
    x = np.clip(x, -1.0, 1.0)
    return 0.5 * x * (3.0 - x * x)


def path(*corners, n=600):
    """Straight torque ramps through ``corners`` [N·m], ``n`` samples each, 1 s each."""
    T = np.concatenate([np.linspace(a, b, n, endpoint=False) for a, b in zip(corners[:-1], corners[1:])]
                       + [[corners[-1]]])
    return np.linspace(0.0, len(corners) - 1.0, T.size), T


def zero_torque_twists(T, x):
    """Twist where the torque crosses zero downwards and upwards (linear between samples)."""
    out = []
    for falling in (True, False):
        s = np.sign(T)
        i = np.flatnonzero((s[:-1] > 0) & (s[1:] <= 0)) if falling else np.flatnonzero((s[:-1] < 0) & (s[1:] >= 0))
        i = i[-1]
        w = T[i] / (T[i] - T[i + 1])
        out.append(x[i] + w * (x[i + 1] - x[i]))
    return out


def test_the_first_loading_follows_the_relays_closed_form():
    t, T = path(0.0, 40.0)
    twist = locked_twist(bare(), t, T)[0]
    c, w, a = relays(LAW)
    # from the demagnetised state (every relay at zero) relay i moves once its curve rises past zero
    expected = T / K + np.sum(a * np.maximum(smoothstep((T[:, None] - c) / w), 0.0), axis=1)
    np.testing.assert_allclose(twist, expected, rtol=0, atol=1e-10)


def test_a_saturating_cycle_opens_a_loop_twice_the_slip_range_wide():
    t, T = path(0.0, 60.0, -60.0, 60.0, 0.0)
    twist = locked_twist(bare(), t, T)[0]
    down, up = zero_torque_twists(T, twist)
    assert down - up == pytest.approx(2 * LAW.slip_max, rel=1e-9)
    # beyond the largest threshold the body is as stiff as its spring again
    far = (T > 50.0) & (np.gradient(T) > 0)
    np.testing.assert_allclose(np.gradient(twist[far], T[far]), 1.0 / K, rtol=1e-6)


def test_a_cycle_below_the_lowest_switching_band_stays_elastic():
    c, w, _ = relays(LAW)
    top = 0.95 * (c[0] - w[0])
    t, T = path(0.0, top, -top, top, 0.0)
    twist = locked_twist(bare(), t, T)[0]
    np.testing.assert_allclose(twist, T / K, rtol=0, atol=1e-12)


def test_return_point_memory_and_wiping_out():
    # a minor loop inside a branch returns to the branch where it left it, and a larger
    # excursion wipes it out
    t, T = path(0.0, 60.0, -12.0, 5.0, -12.0, -30.0)
    twist = locked_twist(bare(), t, T)[0]
    t_ref, T_ref = path(0.0, 60.0, -12.0, -30.0)
    reference = locked_twist(bare(), t_ref, T_ref)[0]
    # the last sample of each record is at -30 N·m, reached through -12 N·m on one branch
    assert twist[-1] == pytest.approx(reference[-1], abs=1e-12)
    # back at -12 N·m after the minor loop, the twist is where the branch left it
    back = np.flatnonzero(np.isclose(T, -12.0))
    assert twist[back[-1]] == pytest.approx(twist[back[0]], abs=1e-12)


@pytest.mark.parametrize("s_c", [0.3, 0.5])
def test_the_loop_matches_an_independent_preisach_model_without_interaction(s_c):
    width, c_med = 3e-4, 10.0
    reference = zf.Preisach(width, 1e-3 * c_med, c_med, s_c, grid=481)
    law = fx.DistributedSlip(slip_torque=c_med, slip_max=0.5 * width, spread=s_c)
    t, T = path(0.0, 80.0, -80.0, 80.0, -80.0, 25.0, -10.0)
    slip = locked_twist(bare(law), t, T)[0] - T / K
    truth = reference.series(T)
    # the Preisach model starts demagnetised from a decaying alternating history, the law
    # from every relay at zero: compare after the first saturation
    after = np.arange(T.size) >= 600
    error = np.abs(slip - truth)[after]
    assert np.max(error) < 0.06 * width  # six smoothed relays stand for a continuous density
    assert np.sqrt(np.mean(error**2)) < 0.02 * width


def test_the_ode_form_follows_the_quasi_static_branches():
    # the relays' rate law in the dynamic model (inertia, Radau) against the quasi-static
    # closed-form branches, on a slow ±T_N cycle with a minor loop
    model = bare(damping=fx.ViscousDamping(coefficient=50.0))
    t, T = path(0.0, 60.0, -20.0, 5.0, -60.0, n=150)
    quasi = locked_twist(model, t, T)[0]
    dyn = dynamic_locked_twist(model, t, T)[0]
    # 1.8 % measured: the gate of a relay reaching its curve opens over 1e-3 of its range
    # and the direction over 1e-6 rad/s; a relay missing or stuck would be ~17 %
    assert np.max(np.abs(quasi - dyn)) < 0.03 * LAW.slip_max


def test_no_slip_range_is_no_effect():
    t, T = path(0.0, 60.0, -60.0, 0.0)
    neutral = fx.DistributedSlip.neutral()
    np.testing.assert_allclose(locked_twist(bare(neutral), t, T)[0],
                               locked_twist(bare(fx.NO_EFFECT["friction"]), t, T)[0], rtol=0, atol=1e-15)
