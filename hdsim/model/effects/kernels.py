"""Compiled scalar forms of the built-in laws, for the compiled quasi-static evaluator.

Optional: this module needs numba (``pip install "hdsim[fast]"``); the effects import it
only when asked for their compiled form (`Effect.compiled`), and the evaluator falls back
to its numpy form when numba is missing or a law has none (a law defined outside the
package). Each function is the scalar twin of the numpy
law it names, for one parameter set (one row of a batch); the evaluator's tests check
each pair against each other.

Every kernel has one of four fixed signatures (one per family) and is compiled with it, so the evaluator
takes them as first-class functions (`numba.types.FunctionType`) and is compiled once for
all combinations of laws and cached on disk (``cache=True``): a new process loads it in
well under a second instead of compiling it for each combination.

Parameters travel as one float row per parameter set (``p``), laid out by the effect's
`compiled` method next to its numpy law.
"""

from __future__ import annotations

import math

from numba import njit, types

_F8 = types.float64
_ROW = types.float64[::1]

#: spring law of the hardening family: (torque [N·m], tangent [N·m/rad]) at body twist e
SPRING = types.UniTuple(_F8, 2)(_F8, _ROW)
_SPRING_FUNCTION = types.FunctionType(SPRING)
#: the body after its twist moves monotonically from e0 to e in direction d, through the
#: spring law (its function and row): the friction states written to ``out``, and (body
#: torque [N·m], its slope along the path [N·m/rad], spring torque [N·m], spring tangent
#: [N·m/rad]). One call per Newton iteration (each call through a function pointer costs);
#: a law beside the spring adds its torque to the spring's, a law in series with it
#: solves for the spring's share of the twist
FRICTION_STEP = types.UniTuple(_F8, 4)(_SPRING_FUNCTION, _ROW, _ROW, _F8, _F8, _F8, _ROW, _ROW)
#: viscous coefficient [N·m·s/rad] where the tangent stiffness is ratio·K₀
DAMPING = _F8(_F8, _ROW)
#: angle of the dead zone [rad] that carries the contact twist v = T/K₀
GAP_TWIST = _F8(_F8, _ROW)

FUNCTION_TYPES = {"spring": _SPRING_FUNCTION, "friction_step": types.FunctionType(FRICTION_STEP),
                  "damping": types.FunctionType(DAMPING), "gap_twist": types.FunctionType(GAP_TWIST)}


# --------------------------------------------------------------------------- hardening


@njit(SPRING, cache=True, error_model="numpy")
def linear_spring(e, p):
    """``T = K₀ e``; p = (K₀,)."""
    return p[0] * e, p[0]


@njit(_F8(_F8, _F8), cache=True, error_model="numpy")
def _softplus(x, width):
    z = x / width
    return width * (max(z, 0.0) + math.log1p(math.exp(-abs(z))))


@njit(SPRING, cache=True, error_model="numpy")
def smooth_three_segment_spring(e, p):
    """`hdsim.physics.stiffness.smooth_three_segment_torque` and its tangent;
    p = (T1, T2, K1, K2, K3, width)."""
    T1, T2, K1, K2, K3, width = p[0], p[1], p[2], p[3], p[4], p[5]
    a = abs(e)
    phi1 = T1 / K1
    phi2 = phi1 + (T2 - T1) / K2
    torque = K1 * a + (K2 - K1) * _softplus(a - phi1, width) + (K3 - K2) * _softplus(a - phi2, width)
    tangent = (K1 + (K2 - K1) * 0.5 * (1.0 + math.tanh(0.5 * (a - phi1) / width))
               + (K3 - K2) * 0.5 * (1.0 + math.tanh(0.5 * (a - phi2) / width)))
    return math.copysign(1.0, e) * torque if e != 0.0 else 0.0, tangent


@njit(SPRING, cache=True, error_model="numpy")
def tanh_spring(e, p):
    """`hdsim.physics.stiffness.tanh_hardening_torque` and its tangent; p = (K₀, K∞, φ_s)."""
    K0, K_inf, scale = p[0], p[1], p[2]
    th = math.tanh(e / scale)
    # 1/cosh² = 1 − tanh²: one transcendental instead of two (far out both are 0)
    return K_inf * e - (K_inf - K0) * scale * th, K_inf - (K_inf - K0) * (1.0 - th * th)


# --------------------------------------------------------------------------- friction


@njit(FRICTION_STEP, cache=True, error_model="numpy")
def no_friction(spring, ph, s0, e0, e, d, p, out):
    """The spring alone."""
    u, k = spring(e, ph)
    return u, k, u, k


@njit(FRICTION_STEP, cache=True, error_model="numpy")
def dahl_step(spring, ph, s0, e0, e, d, p, out):
    """Exact Dahl state over a monotone twist step, added to the spring's torque, and the
    slope ``σ max(1 − z d/F, 0)`` added to its tangent; p = (σ/F or 0, F, σ)."""
    step = e - e0
    target = math.copysign(p[1], step)
    z = target - (target - s0[0]) * math.exp(-p[0] * abs(step))
    out[0] = z
    u, k = spring(e, ph)
    return u + z, k + p[2] * max(1.0 - z / p[1] * d, 0.0), u, k


@njit(FRICTION_STEP, cache=True, error_model="numpy")
def maxwell_slip_step(spring, ph, s0, e0, e, d, p, out):
    """Elasto-plastic elements stopped at their reach, ``Σ k_i z_i`` added to the spring's
    torque and the stiffness of the elements not sliding in direction d to its tangent;
    p = (k_1…k_n, f_1…f_n, reach_1…reach_n)."""
    n = s0.size
    torque = 0.0
    slope = 0.0
    for i in range(n):
        k, f, reach = p[i], p[n + i], p[2 * n + i]
        z = min(max(s0[i] + (e - e0), -reach), reach)
        out[i] = z
        torque += k * z
        if not d * z * k >= f * (1.0 - 1e-9):
            slope += k
    u, k = spring(e, ph)
    return u + torque, k + slope, u, k


@njit(types.UniTuple(_F8, 2)(_ROW, _F8, _F8, _F8, _ROW, _ROW), cache=True, error_model="numpy")
def _relays_on_branch(s0, torque, d, nudge, p, out):
    """`hdsim.physics.friction.relay_slips_on_branch` for one parameter set: the slips
    written to ``out``, returns (total slip [rad], its slope in the torque [rad/(N·m)]).
    A relay within ``nudge`` of its range behind its curve counts as on it (the slope of
    a step of zero length, as in `DistributedSlip.path_tangent`)."""
    n = s0.size
    total = 0.0
    slope = 0.0
    for i in range(n):
        c, w, a = p[i], p[n + i], p[2 * n + i]
        x = min(max((torque - d * c) / w, -1.0), 1.0)
        curve = a * 0.5 * x * (3.0 - x * x)
        if d * (curve - s0[i]) > -nudge * a:
            out[i] = curve
            slope += a * 1.5 * (1.0 - x * x) / w
        else:
            out[i] = s0[i]
        total += out[i]
    return total, slope


@njit(_F8(_F8, _F8, _F8, _F8, _ROW), cache=True, error_model="numpy")
def _slider_share(s, u, k, d, p):
    """dslip/dtwist of a Dahl slider with rounded stops in series with a spring of tangent
    k carrying u, the body moving in direction d: the scalar `hdsim.physics.friction.dahl_slip_rates`
    for one slider (its tanh sign is exactly ±1 at a unit rate); p = (F, s_max, σ, width)."""
    F, reach, sigma, width = p[0], p[1], p[2], p[3]
    stop = sigma * (_softplus(s - reach, width) - _softplus(-s - reach, width))
    stick = sigma * max(1.0 - (u - stop) / F * d, 0.0)
    contact = 1.0 + 0.5 * (math.tanh(0.5 * (s - reach) / width) + math.tanh(0.5 * (-s - reach) / width))
    slider = 1.0 / max(stick + sigma * contact, 1e-9 * sigma)
    return slider / (1.0 / max(k, 1e-300) + slider)


@njit(FRICTION_STEP, cache=True, error_model="numpy")
def dahl_slip_step(spring, ph, s0, e0, e, d, p, out):
    """The Dahl micro-slip slider in series with the spring (`hdsim.model.effects.friction.DahlSlip`):
    the generic `Friction.advance` (8 midpoint sub-steps of dslip/dtwist) and path tangent
    ``k (1 − dslip/dtwist)`` at the end; p = (F, s_max, σ, stop width)."""
    direction = 1.0 if e >= e0 else -1.0
    h = (e - e0) / 8.0
    s, x = s0[0], e0
    for _ in range(8):
        u, k = spring(x - s, ph)
        k1 = _slider_share(s, u, k, direction, p)
        u, k = spring(x + 0.5 * h - (s + 0.5 * h * k1), ph)
        s += h * _slider_share(s + 0.5 * h * k1, u, k, direction, p)
        x += h
    out[0] = s
    u, k = spring(e - s, ph)
    return u, k * (1.0 - _slider_share(s, u, k, d, p)), u, k


@njit(FRICTION_STEP, cache=True, error_model="numpy")
def distributed_slip_step(spring, ph, s0, e0, e, d, p, out):
    """Relays in series with the spring (`hdsim.model.effects.distributed_slip`): the
    spring's twist x solving ``x + slip(u(x)) = e`` by Newton's method in the bracket
    ``e ∓ Σ a_i``, the body torque u(x) and its slope ``k/(1 + k·dslip/dT)``;
    p = (c_1…c_n, w_1…w_n, a_1…a_n)."""
    n = s0.size
    reach = 0.0
    held = 0.0
    for i in range(n):
        reach += p[2 * n + i]
        held += s0[i]
    lo, hi = e - reach, e + reach
    x = e - held
    for _ in range(60):
        u, k = spring(x, ph)
        total, slope = _relays_on_branch(s0, u, d, 0.0, p, out)
        h = x + total - e
        if h == 0.0:  # most steps: no relay moves, the start is the root
            break
        if h < 0.0:
            lo = max(lo, x)
        else:
            hi = min(hi, x)
        xn = x - h / (1.0 + k * slope)
        if xn < lo or xn > hi:  # the root may sit on the bracket's edge (a relay at its stop)
            xn = 0.5 * (lo + hi)
        done = abs(xn - x) <= 1e-15 + 1e-13 * abs(x)
        x = xn
        if done:
            break
    u, k = spring(x, ph)
    _, slope = _relays_on_branch(s0, u, d, 1e-4 if e == e0 else 0.0, p, out)
    return u, k / (1.0 + k * slope), u, k


# --------------------------------------------------------------------------- damping


@njit(DAMPING, cache=True, error_model="numpy")
def no_damping(ratio, p):
    return 0.0


@njit(DAMPING, cache=True, error_model="numpy")
def viscous_damping(ratio, p):
    """`hdsim.physics.damping.load_dependent_coefficient`; p = (c₀, share)."""
    return p[0] * (1.0 - p[1] + p[1] * ratio)


# --------------------------------------------------------------------------- backlash


@njit(GAP_TWIST, cache=True, error_model="numpy")
def no_gap_twist(v, p):
    return 0.0


@njit(GAP_TWIST, cache=True, error_model="numpy")
def dead_zone_gap_twist(v, p):
    """`hdsim.physics.backlash.inverse_smooth_dead_zone` minus v; p = (half gap h, rounding
    width w, e^(−h/w))."""
    h, w, c = p[0], p[1], p[2]
    if abs(v) >= 40.0 * w:
        return math.copysign(h, v) if v != 0.0 else 0.0
    d = math.exp(abs(v) / w)
    a = ((d - 1.0) + math.sqrt((d - 1.0) ** 2 + 4.0 * c * c * d)) / (2.0 * c)
    y = w * math.log(a)
    return (y if v > 0.0 else -y if v < 0.0 else 0.0) - v
