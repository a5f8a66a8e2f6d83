"""Quasi-static evaluator of the locked-wave-generator bench: inertia dropped, torque in, twist out.

Why (the singular-perturbation argument)
----------------------------------------
On the stiffness bench the output obeys ``J_out ω̇ = T(t) − τ(θ, ω, z)``. The output mode
of a CSG-25 on its fixture sits at ``f_n = √(K/J_out)/2π ≈ 600 Hz``, while a bench cycle
lasts seconds: the ratio ``ε = (f_test/f_n)²`` is ~1e-6. Written in the slow time
``t/T_test``, the inertia multiplies the highest derivative by ``ε``; with the damping of
the drive (friction or viscous) the fast subsystem is stable, so by Tikhonov's theorem
the solution stays within ``O(ε)`` of the *slow manifold* ``τ(θ, θ̇, z) = T(t)`` except in
boundary layers of a few fast periods after a corner of the torque profile. The neglected
inertial torque ``J_out θ̈`` is ``J_out·Ṫ̇/K``: zero on a ramp, and at a corner of rate
change ``ΔṪ`` it excites a decaying ringing of amplitude ``ΔṪ/(K ω_n) ≈ 1e-6 rad`` at most
(less with damping), about the encoder noise. On the slow manifold there is no 600 Hz
mode to resolve, so one step per sample suffices: this evaluator is 100–1000 times
faster than :func:`hdsim.simulation.path.locked_wave_generator` with Radau, which is what makes
hundreds of refits affordable (``tests/test_fit.py`` checks both agree on a slow profile).

What it solves
--------------
The same elastic path as :class:`hdsim.simulation.path.ElasticPath`, with the library's effect
objects and laws (the same :class:`~hdsim.model.drive.HarmonicDrive` slots)::

    e            body twist, behind the dead zone (spring ∥ damper ∥ Dahl friction)
    u            = hardening.torque(e, C_s, C_m) spring torque, K_t = its tangent
    z            Dahl friction torque, dz/de = σ (1 − z/F · sgn ė)
    d            = c(e) · ė, c(e) = c₀ [(1 − s) + s K_t/K₀]   viscous damping torque
    u + z + d = T(t)                             the torque balance, inertia dropped
    x            = e + g(T), g(T) = dead_zone⁻¹(T/K₀) − T/K₀   output twist (= the angle θ)

The dead zone is in series with the body and carries the same torque, so its angle
``g`` is a function of the transmitted torque alone (:class:`hdsim.simulation.path.ElasticPath`).

Each step from sample ``k`` to ``k+1`` solves the balance at ``t_{k+1}`` for the new
body twist with an exponentially fitted rate for ``ė`` (the coefficient ``c(e)`` taken at
the start of the step); the Dahl state is advanced *exactly* over the twist increment
(the law is rate-independent: for a fixed sign of ``ė``,
``z(e) = s F − (s F − z₀) exp(−σ|Δe|/F)``). The scalar equation per sample is
monotone in the new body twist (the dead zone is not inside it) and is solved by Newton's
method kept inside a bracket (bisection when a Newton step leaves it), vectorised over a
batch of parameter sets; the output twist follows from the torque by one monotone
inversion of the rounded dead zone. Without damping (``c = 0``) the result does not
depend on the time step at all (rate independence).

A batch may mix *models*: several :class:`HarmonicDrive` objects (each single or a batch)
are stacked into one plan if, slot by slot, they use one effect class or none. A model
without a family gets neutral parameters of the carrier class (``gap = 0``,
``e_inf = 1``, ``c = 0``) or a mask (friction, the dead-zone angle), which reproduce
"none" exactly. That lets a diagnosis evaluate every candidate model of a round, and their
finite-difference Jacobian columns, in one pass over the samples.

Supported effects: hardening ``none``, ``tanh``, ``three_segment``; backlash ``none``,
``dead_zone``; friction ``none``, ``dahl``; damping ``none``, ``viscous``. Other effects
(``dahl_slip``, ``coulomb``, ``maxwell_slip``) raise :class:`UnsupportedEffect`; use the
dynamic model for them (:func:`dynamic_locked_twist`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from hdsim.model import effects as fx
from hdsim.errors import InputError
from hdsim.model.drive import HarmonicDrive
from hdsim.physics import backlash as bl
from hdsim.physics import damping as dp
from hdsim.physics import friction as fr
from hdsim.physics import stiffness as st

__all__ = ["SUPPORTED", "UnsupportedEffect", "Plan", "stack_models", "locked_twist",
           "dynamic_locked_twist", "sample_grid", "supports"]

#: effect ids per family that the quasi-static evaluator handles
SUPPORTED = {
    "hardening": ("none", "tanh", "three_segment"),
    "backlash": ("none", "dead_zone"),
    "friction": ("none", "dahl"),
    "damping": ("none", "viscous"),
    "kinematic_error": ("none", "fourier"),  # enters the kinematic-error test only
}

#: parameters that make a carrier effect act as "none" exactly
_NEUTRAL = {
    ("hardening", "tanh"): {"e_inf": 1.0, "T_s": 1.0},
    ("hardening", "three_segment"): {"T1": 1.0, "T2": 2.0, "e2": 1.0, "e3": 1.0},
    ("backlash", "dead_zone"): {"gap": 0.0},
    ("friction", "dahl"): {"torque_max": 1.0, "sigma": 1.0},
    ("damping", "viscous"): {"coefficient": 0.0, "stiffness_share": 0.0},
}

class UnsupportedEffect(InputError):
    """An effect the quasi-static evaluator does not handle."""


def supports(model: HarmonicDrive) -> bool:
    """True when every slot of ``model`` holds an effect this evaluator handles."""
    return all(getattr(model, slot).id in SUPPORTED[slot] for slot in SUPPORTED)


@dataclass(frozen=True)
class Plan:
    """Models stacked into one batch of ``size`` parameter sets with one carrier per slot."""

    size: int
    c_struct: np.ndarray
    c_mesh: np.ndarray
    hardening: fx.Effect
    backlash: fx.Effect
    has_backlash: np.ndarray  # (M,) bool: the row has a dead zone
    friction: fx.Effect
    has_friction: np.ndarray  # (M,) float 0/1
    damping: np.ndarray  # (M,) viscous coefficient c₀ [N·m·s/rad], 0 for none
    stiffness_share: np.ndarray  # (M,) share of c₀ proportional to the tangent stiffness
    offsets: tuple[int, ...]  # first row of each stacked model


def _carrier(slot: str, models: list[HarmonicDrive], sizes: list[int]):
    ids = {getattr(m, slot).id for m in models}
    for effect_id in ids:
        if effect_id not in SUPPORTED[slot]:
            raise UnsupportedEffect(
                f"the quasi-static evaluator has no {slot} effect '{effect_id}'; "
                f"it handles {', '.join(SUPPORTED[slot])}")
    real = sorted(ids - {"none"})
    if len(real) > 1:
        raise InputError(f"cannot stack models with {slot} effects {real} in one batch")
    if not real:
        return fx.NO_EFFECT[slot], np.zeros(sum(sizes), dtype=bool)
    cls = fx.effect_class(slot, real[0])
    neutral = _NEUTRAL[(slot, real[0])]
    columns = {f.name: [] for f in fields(cls)}
    present = []
    for model, size in zip(models, sizes):
        effect = getattr(model, slot)
        on = effect.id != "none"
        present.append(np.full(size, on))
        for name in columns:
            value = getattr(effect, name) if on else neutral[name]
            columns[name].append(np.broadcast_to(np.asarray(value, dtype=float), (size,)))
    values = {name: np.concatenate(parts) for name, parts in columns.items()}
    return cls(**values), np.concatenate(present)


def stack_models(models) -> Plan:
    """Stack one or several (batch) models into a :class:`Plan` for :func:`locked_twist`."""
    if isinstance(models, HarmonicDrive):
        models = [models]
    models = list(models)
    sizes = [m.batch_size for m in models]
    cs, cm = [], []
    for model, size in zip(models, sizes):
        c_struct, c_mesh = model.split()
        cs.append(np.broadcast_to(np.asarray(c_struct, dtype=float), (size,)))
        cm.append(np.broadcast_to(np.asarray(c_mesh, dtype=float), (size,)))
    hardening, _ = _carrier("hardening", models, sizes)
    backlash, has_backlash = _carrier("backlash", models, sizes)
    friction, has_friction = _carrier("friction", models, sizes)
    damping, has_damping = _carrier("damping", models, sizes)
    size = sum(sizes)
    coefficient = np.broadcast_to(np.asarray(damping.coefficient, dtype=float) * has_damping, (size,))
    share = np.broadcast_to(np.asarray(damping.stiffness_share, dtype=float), (size,))
    offsets = tuple(int(v) for v in np.concatenate([[0], np.cumsum(sizes)[:-1]]))
    return Plan(size=int(sum(sizes)), c_struct=np.concatenate(cs), c_mesh=np.concatenate(cm),
                hardening=hardening, backlash=backlash, has_backlash=has_backlash,
                friction=friction, has_friction=has_friction.astype(float),
                damping=coefficient.astype(float), stiffness_share=share.astype(float),
                offsets=offsets)


# --------------------------------------------------------------------------- the step


def _phi_functions(mu):
    """β(μ) = μ/(e^μ − 1) and γ(μ) = (1 − β)/μ, with their limits β(0) = 1, γ(0) = 1/2.

    ``μ = ∞`` (no damping) gives β = γ = 0.
    """
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        beta = mu / np.expm1(mu)
        gamma = np.where(mu > 1e-4, (1.0 - beta) / mu, 0.5 - mu / 6.0)
    return beta, gamma


class _Kernel:
    """The torque balance of one step in the body twist, vectorised over the plan.

    The unknown is the body twist ``e`` (behind the dead zone), so the balance
    ``Φ(u(e) + z(e), c ė) = T`` is smooth and increasing in ``e``; the output twist
    follows from ``e`` and ``z`` afterwards (:meth:`output_twist`).

    Damping uses an *exponentially fitted* rate: over a step of length ``h`` with the
    torque linear in time, the rate entering ``d = c ė`` is ``ė = β Δe/h + γ ΔT/c``
    with ``β = μ/(e^μ − 1)``, ``γ = (1 − β)/μ`` and ``μ = k h/c`` (``k`` the tangent
    stiffness of the body at the start of the step). For a linear spring this makes the
    step *exact* for any ``h`` (the solution of ``c ė = T(t) − k e`` with ``T`` linear over
    the step); as ``c → 0`` it gives ``d → 0`` (rate independence) and as ``h → 0`` it
    tends to backward Euler ``Δe/h``.
    """

    def __init__(self, plan: Plan):
        cs, cm = plan.c_struct, plan.c_mesh
        self.k0 = 1.0 / (cs + cm)  # every supported hardening law starts from K0
        # Law arguments are computed once per evaluation; the laws themselves are the
        # library's pure functions (hdsim.physics), called exactly as the effects call them.
        hardening = plan.hardening
        if hardening.id == "none":
            k_lin = self.k0
            self._spring = lambda e: (k_lin * e, k_lin)
        elif hardening.id == "tanh":
            args = hardening._k(cs, cm)
            self._spring = lambda e: (st.tanh_hardening_torque(e, *args),
                                      st.tanh_hardening_tangent(e, *args))
        elif hardening.id == "three_segment":
            args = hardening._args(cs, cm)
            self._spring = lambda e: (st.smooth_three_segment_torque(e, *args),
                                      st.smooth_three_segment_tangent(e, *args))
        else:  # pragma: no cover - guarded by stack_models
            raise UnsupportedEffect(f"hardening '{hardening.id}'")
        backlash = plan.backlash
        self.gap = None
        if backlash.id == "dead_zone":
            self.gap = np.asarray(backlash.gap, dtype=float)
            self.width = backlash.contact_rounding * self.gap + 1e-12
        self.has_backlash = plan.has_backlash
        self.friction = plan.friction.id == "dahl"
        if self.friction:
            self.F = np.asarray(plan.friction.torque_max, dtype=float)
            sigma = np.asarray(plan.friction.sigma, dtype=float)
            self.fmask = plan.has_friction
            self.sigma_over_F = sigma / self.F
            self.sigma_f = sigma * self.fmask  # zero slope where the row has no friction
        self.c = plan.damping
        self.share = plan.stiffness_share
        self.any_damping = bool(np.any(self.c > 0))
        self.dg_floor = 1e-6 * self.k0

    def dahl(self, z0, de):
        """Exact Dahl update over the body-twist increment ``de`` (fixed sign) and dz/de."""
        if not self.friction:
            return z0, 0.0
        direction = np.copysign(1.0, de)
        target = direction * self.F
        z = (target - (target - z0) * np.exp(-self.sigma_over_F * np.abs(de))) * self.fmask
        return z, fr.dahl_slope(z, direction, self.sigma_f, self.F)

    def rate_coefficients(self, k, z0, dT, h):
        """(c β / h, γ ΔT) of the fitted rate for a step of length h (see the class doc).

        ``k`` is the spring tangent at the start of the step (from the previous step's
        last Newton evaluation); it also sets the load-dependent coefficient ``c(e)``.
        """
        if not self.any_damping or not np.isfinite(h):
            return None
        c = dp.load_dependent_coefficient(self.c, self.share, k / self.k0)
        if self.friction:
            direction = np.where(dT >= 0.0, 1.0, -1.0)
            k = k + fr.dahl_slope(z0, direction, self.sigma_f, self.F)
        mu = k * h / (c + 1e-300)  # c = 0: μ ≈ ∞, β = γ = 0
        beta, gamma = _phi_functions(mu)
        return c * beta / h, gamma * dT

    def balance(self, e, e0, z0, torque, rate):
        """(residual u + z + d − T, its derivative in e, spring tangent)."""
        u, k = self._spring(e)
        if self.friction:
            z, dz = self.dahl(z0, e - e0)
            u, k_body = u + z, k + dz
        else:
            k_body = k
        if rate is None:
            return u - torque, k_body, k
        cb, gdT = rate
        d = cb * (e - e0) + gdT
        return u + d - torque, k_body + cb, k

    def output_twist(self, e, torque):
        """Output twist x [rad] from body twist e (rows, steps) and the torque (steps).

        The dead zone carries the body's torque in series, so it takes the angle
        ``g(T) = dead_zone⁻¹(T/K₀) − T/K₀`` (`hdsim.simulation.path.ElasticPath`): ``x = e + g(T)``.
        """
        if self.gap is None:  # a dead-zone carrier means at least one row has backlash
            return e
        v = np.asarray(torque, dtype=float)[None, :] / self.k0[:, None]
        v = np.broadcast_to(v, e.shape)
        y = bl.inverse_smooth_dead_zone(v, 0.5 * self.gap[:, None], self.width[:, None])
        return np.where(self.has_backlash[:, None], e + (y - v), e)


def locked_twist(models, time, torque, *, grid=None, tol=1e-9, x_tol=1e-8, max_iter=60,
                 return_states=False):
    """Quasi-static output twist [rad] of the locked-WG bench under a measured torque.

    Parameters
    ----------
    models : HarmonicDrive or list of HarmonicDrive or Plan
        Single or batch models; several are stacked (see :func:`stack_models`).
    time : array_like, shape (n,)
        Sample times [s], strictly increasing.
    torque : array_like, shape (n,)
        Torque applied to the output [N·m] (the measured one).
    grid : array_like of int, int or "auto", optional
        Indices of the samples to step on (sorted, first 0, last n-1); the twist at other
        samples is interpolated linearly in time. Default: every sample. An int (a step
        budget) or ``"auto"`` (4000) chooses the grid by :func:`sample_grid`, dense where
        the torque is small (``|T| < 0.04·max|T| + 1.25·F`` with ``F`` the largest Dahl
        friction torque of the batch: the gap is crossed at zero torque and the friction
        state turns over within ``±F`` of it).
    tol : float
        Torque-balance tolerance relative to ``max |T|``.
    x_tol : float
        A Newton step smaller than this [rad] ends the iteration. Newton converges
        quadratically, so the error left is about ``x_tol² · g''/g'``, far below the
        encoder resolution.
    max_iter : int
        Newton iterations per step at most.
    return_states : bool
        Also return the Dahl friction torque ``z`` [N·m].

    Returns
    -------
    numpy.ndarray, shape (M, n)
        Twist of each stacked parameter set from the virgin state (zero twist, zero
        friction torque) at the first sample's torque.
    """
    plan = models if isinstance(models, Plan) else stack_models(models)
    with np.errstate(over="ignore"):  # cosh overflow far out on the tanh law: tangent → K∞
        return _locked_twist(plan, time, torque, grid, tol, x_tol, max_iter, return_states)


def _locked_twist(plan, time, torque, grid, tol, x_tol, max_iter, return_states):
    t = np.asarray(time, dtype=float)
    T = np.asarray(torque, dtype=float)
    if isinstance(grid, str) or (isinstance(grid, (int, np.integer)) and not isinstance(grid, bool)):
        budget = 4000 if isinstance(grid, str) else int(grid)
        f_max = 0.0
        if plan.friction.id == "dahl":
            f_max = float(np.max(np.asarray(plan.friction.torque_max) * plan.has_friction))
        t_max = max(float(np.max(np.abs(T))), 1e-12)
        grid = sample_grid(t, T, max_steps=budget, zero_band=min(0.04 + 1.25 * f_max / t_max, 0.5))
    idx = np.arange(t.size) if grid is None else np.asarray(grid, dtype=int)
    tg, Tg = t[idx], T[idx]
    kern = _Kernel(plan)
    M = plan.size
    tol_T = tol * max(float(np.max(np.abs(T))), 1e-12)
    e_out = np.empty((M, idx.size))
    z_out = np.empty((M, idx.size)) if return_states else None
    k0 = kern.k0
    zeros = np.zeros(M)
    e, z, k = _solve(kern, Tg[0] / k0, zeros, zeros, Tg[0], None, tol_T, x_tol,
                     max_iter, np.abs(Tg[0]) / k0)
    e_out[:, 0] = e
    if return_states:
        z_out[:, 0] = z
    e_prev, h_prev = e, None
    for j in range(1, idx.size):
        h = tg[j] - tg[j - 1]
        dT = Tg[j] - Tg[j - 1]
        guess = e + dT / k0 if h_prev is None else e + (e - e_prev) * (h / h_prev)
        rate = kern.rate_coefficients(k, z, dT, h)
        e_new, z, k = _solve(kern, guess, e, z, Tg[j], rate, tol_T, x_tol, max_iter,
                             np.abs(dT) / k0)
        e_prev, e, h_prev = e, e_new, h
        e_out[:, j] = e
        if return_states:
            z_out[:, j] = z
    if idx.size != t.size:
        # the body twist is smooth between steps; the dead-zone angle is exact at every sample
        e_out = _interp_rows(t, tg, e_out)
        if return_states:
            z_out = _interp_rows(t, tg, z_out)
    x_out = kern.output_twist(e_out, T)
    return (x_out, z_out) if return_states else x_out


def _solve(kern, guess, e0, z0, torque, rate, tol_T, x_tol, max_iter, x_scale):
    """Newton on the monotone balance of one step: (body twist, friction state, tangent).

    Plain Newton steps first; if they have not converged after three, the iteration
    keeps a bracket (the balance is increasing in e) and bisects when a Newton step
    leaves it, with unbracketed steps limited to a few expected increments.
    """
    x = guess
    lo = hi = None
    for it in range(max_iter):
        g, dg, k = kern.balance(x, e0, z0, torque, rate)
        # the balance is increasing in e (dg ≥ spring tangent > 0); the floor guards round-off
        step = -g / np.maximum(dg, kern.dg_floor)
        if it >= 3:
            if lo is None:
                lo = np.full_like(x, -np.inf)
                hi = np.full_like(x, np.inf)
                base = np.abs(x - e0) + x_scale + 1e-8
            lo = np.where(g < 0.0, np.maximum(lo, x), lo)
            hi = np.where(g > 0.0, np.minimum(hi, x), hi)
            limit = 4.0 * base
            step = np.clip(step, -limit, limit)
            xn = x + step
            both = np.isfinite(lo) & np.isfinite(hi)
            with np.errstate(invalid="ignore"):
                mid = 0.5 * (lo + hi)
            xn = np.where(both & ((xn <= lo) | (xn >= hi)), mid, xn)
            base = np.where(both, base, 2.0 * base)
            step = np.where(np.abs(g) <= tol_T, 0.0, xn - x)
        x = x + step
        if np.abs(step).max() <= x_tol:
            break
    z = kern.dahl(z0, x - e0)[0] if kern.friction else z0
    return x, z, k


def _interp_rows(t, tg, values):
    out = np.empty((values.shape[0], t.size))
    for i in range(values.shape[0]):
        out[i] = np.interp(t, tg, values[i])
    return out


# --------------------------------------------------------------------------- grids


def sample_grid(time, torque, max_steps: int = 4000, zero_band: float = 0.04):
    """Sample indices to step on for a long record (all of them when ``n <= max_steps``).

    Elsewhere every ``k``-th sample, plus every sample near zero torque (``|T| <
    zero_band·max|T|``, where the dead-zone angle changes fast) and around
    each turning point of the torque (where friction states change fast); the twist
    between steps is interpolated. The memory states change on torque scales of several
    N·m while neighbouring samples of a 20,000-row bench record differ by ~0.03 N·m, so
    the interpolation error stays far below encoder noise (``tests/test_fit.py``).
    """
    T = np.asarray(torque, dtype=float)
    n = T.size
    if n <= max_steps:
        return np.arange(n)
    k = int(np.ceil(n / (0.6 * max_steps)))
    keep = np.zeros(n, dtype=bool)
    keep[::k] = True
    keep[[0, n - 1]] = True
    keep |= np.abs(T) < zero_band * np.max(np.abs(T))
    smooth = np.convolve(T, np.ones(k) / k, mode="same")
    rate = np.sign(np.diff(smooth))
    turns = np.flatnonzero(rate[1:] * rate[:-1] < 0) + 1
    for i in turns:
        keep[max(i - 2 * k, 0):i + 2 * k + 1] = True
    # keep the torque step between grid points small as well
    chosen = np.flatnonzero(keep)
    if chosen.size > max_steps:
        chosen = np.unique(np.concatenate([chosen[:: int(np.ceil(chosen.size / max_steps))], [n - 1]]))
    return chosen


# --------------------------------------------------------------------------- reference


def dynamic_locked_twist(model: HarmonicDrive, time, torque, options=None) -> np.ndarray:
    """The same bench with inertia, by :func:`hdsim.simulation.path.locked_wave_generator` (slow).

    The measured torque is interpolated linearly between samples. Any effect is allowed;
    this is the reference the quasi-static evaluator is tested against, and the fallback
    for effects it does not handle.
    """
    from hdsim.simulation.path import locked_wave_generator
    from hdsim.simulation.solver import SolverOptions, integrate

    t = np.asarray(time, dtype=float)
    T = np.asarray(torque, dtype=float)

    def applied(ti):
        return np.interp(ti, t, T)

    system = locked_wave_generator(model, applied)
    dt = float(np.min(np.diff(t)))
    opts = options or SolverOptions(max_step=dt)
    result = integrate(system, (t[0], t[-1]), t, opts)
    return np.asarray(result.signals["twist_rad"])
