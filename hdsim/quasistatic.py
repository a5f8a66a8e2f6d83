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
faster than :func:`hdsim.dynamics.locked_wave_generator` with Radau, which is what makes
hundreds of refits affordable (``tests/test_fit.py`` checks both agree on a slow profile).

What it solves
--------------
The same elastic path as :class:`hdsim.dynamics.ElasticPath`, with the library's effect
objects and laws (the same :class:`~hdsim.model.HarmonicDrive` slots)::

    x            twist across dead zone + spring (= the output angle θ)
    e, κ         = backlash.engage(x)            engaged twist, contact factor
    u            = hardening.torque(e, C_s, C_m) spring torque
    d            = c · κ · ẋ                     viscous damping torque
    Φ            = backlash.contact_torque(u, d) (u + d without backlash)
    z            Dahl friction torque, dz/dθ = σ (1 − z/F · sgn θ̇)
    Φ + z = T(t)                                 the torque balance, inertia dropped

Each step from sample ``k`` to ``k+1`` solves the balance at ``t_{k+1}`` for the new
twist with implicit (backward) Euler for ``ẋ``; the Dahl state is advanced *exactly*
over the twist increment (the law is rate-independent: for a fixed sign of ``θ̇``,
``z(θ) = s F − (s F − z₀) exp(−σ|Δθ|/F)``). The scalar equation per sample is monotone in
the new twist and is solved by Newton's method kept inside a bracket (bisection when a
Newton step leaves it), vectorised over a batch of parameter sets. Without damping
(``c = 0``) the result does not depend on the time step at all (rate independence).

A batch may mix *models*: several :class:`HarmonicDrive` objects (each single or a batch)
are stacked into one plan if, slot by slot, they use one effect class or none. A model
without a family gets neutral parameters of the carrier class (``gap = 0``,
``e_inf = 1``, ``c = 0``) or a mask (friction, the backlash contact rule), which reproduce
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

from hdsim import effects as fx
from hdsim.errors import InputError
from hdsim.model import HarmonicDrive

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
    ("damping", "viscous"): {"coefficient": 0.0},
}

_BODY = ("hardening", "backlash", "friction", "damping")


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
    has_backlash: np.ndarray  # (M,) bool: the ElastoBacklash contact rule applies
    friction: fx.Effect
    has_friction: np.ndarray  # (M,) float 0/1
    damping: np.ndarray  # (M,) viscous coefficient [N·m·s/rad], 0 for none
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
    coefficient = (np.asarray(damping.coefficient, dtype=float) * has_damping
                   if damping.id != "none" else np.zeros(sum(sizes)))
    offsets = tuple(int(v) for v in np.concatenate([[0], np.cumsum(sizes)[:-1]]))
    return Plan(size=int(sum(sizes)), c_struct=np.concatenate(cs), c_mesh=np.concatenate(cm),
                hardening=hardening, backlash=backlash, has_backlash=has_backlash,
                friction=friction, has_friction=has_friction.astype(float),
                damping=np.broadcast_to(coefficient, (sum(sizes),)).astype(float), offsets=offsets)


# --------------------------------------------------------------------------- the step


class _Kernel:
    """The torque balance of one step and its derivative, vectorised over the plan."""

    def __init__(self, plan: Plan):
        self.plan = plan
        self.cs, self.cm = plan.c_struct, plan.c_mesh
        self.elasto = plan.has_backlash
        self.any_elasto = bool(np.any(plan.has_backlash))
        self.friction = plan.friction.id == "dahl"
        if self.friction:
            self.F = np.asarray(plan.friction.torque_max, dtype=float)
            self.sigma = np.asarray(plan.friction.sigma, dtype=float)
            self.fmask = plan.has_friction
        self.c = plan.damping
        self.any_damping = bool(np.any(self.c > 0))

    def spring(self, x):
        """(spring torque u, tangent K_t·κ) at twist x across the dead zone."""
        hardening = self.plan.hardening
        engaged, contact = self.plan.backlash.engage(x)
        u = hardening.torque(engaged, self.cs, self.cm)
        k = hardening.tangent(engaged, self.cs, self.cm) * contact
        return u, k, contact

    def dahl(self, z0, dx):
        """Exact Dahl update over the twist increment ``dx`` and its derivative."""
        direction = np.where(dx >= 0.0, 1.0, -1.0)
        target = direction * self.F
        z = target - (target - z0) * np.exp(-self.sigma * np.abs(dx) / self.F)
        dz = self.sigma * (1.0 - direction * z / self.F)
        return z * self.fmask, dz * self.fmask

    def balance(self, x, x0, z0, torque, h):
        """(residual Φ + z − T, its derivative in x, new friction state)."""
        u, k, contact = self.spring(x)
        if self.any_damping:
            d = self.c * contact * (x - x0) / h
            dd = self.c * contact / h
            if self.any_elasto:
                limit = np.maximum(np.abs(u), 1e-300)
                a = d / limit
                th = np.tanh(a)
                sech2 = 1.0 - th * th
                phi_e = u + limit * th
                # ∂Φ/∂u and ∂Φ/∂d of u + |u| tanh(d/|u|)
                du_e = 1.0 + np.sign(u) * (th - a * sech2)
                phi = np.where(self.elasto, phi_e, u + d)
                dphi = np.where(self.elasto, du_e * k + sech2 * dd, k + dd)
            else:
                phi, dphi = u + d, k + dd
        else:
            phi, dphi = u, k
        if self.friction:
            z, dz = self.dahl(z0, x - x0)
            return phi + z - torque, dphi + dz, z
        return phi - torque, dphi, z0


def locked_twist(models, time, torque, *, grid=None, tol=1e-9, max_iter=60, return_states=False):
    """Quasi-static output twist [rad] of the locked-WG bench under a measured torque.

    Parameters
    ----------
    models : HarmonicDrive or list of HarmonicDrive
        Single or batch models; several are stacked (see :func:`stack_models`).
    time : array_like, shape (n,)
        Sample times [s], strictly increasing.
    torque : array_like, shape (n,)
        Torque applied to the output [N·m] (the measured one).
    grid : array_like of int, optional
        Indices of the samples to step on (sorted, first 0, last n-1); the twist at other
        samples is interpolated linearly in time. Default: every sample (see
        :func:`sample_grid` for long records).
    tol : float
        Torque-balance tolerance relative to ``max |T|``.
    max_iter : int
        Newton iterations per step at most.
    return_states : bool
        Also return the Dahl friction torque ``z`` [N·m].

    Returns
    -------
    numpy.ndarray, shape (M, n)
        Twist of each stacked parameter set, zero at zero torque from the virgin state.
    """
    plan = models if isinstance(models, Plan) else stack_models(models)
    t = np.asarray(time, dtype=float)
    T = np.asarray(torque, dtype=float)
    idx = np.arange(t.size) if grid is None else np.asarray(grid, dtype=int)
    tg, Tg = t[idx], T[idx]
    kern = _Kernel(plan)
    M = plan.size
    tol_T = tol * max(float(np.max(np.abs(T))), 1e-12)
    x_out = np.empty((M, idx.size))
    z_out = np.empty((M, idx.size)) if return_states else None
    x = np.zeros(M)
    z = np.zeros(M)
    # start on the balance at the first sample (virgin state, at rest)
    x = _solve(kern, x, x, z, Tg[0], np.inf, tol_T, max_iter, x_scale=None)
    if kern.friction:
        # the virgin Dahl curve from zero: z follows the loading from the rest state
        _, _, z = kern.balance(x, np.zeros(M), np.zeros(M), Tg[0], np.inf)
    x_out[:, 0] = x
    if return_states:
        z_out[:, 0] = z
    x_prev = x.copy()
    h_prev = None
    k0 = _stiffness_scale(plan)
    for j in range(1, idx.size):
        h = tg[j] - tg[j - 1]
        if h_prev is None:
            guess = x + (Tg[j] - Tg[j - 1]) / k0
        else:
            guess = x + (x - x_prev) * (h / h_prev)
        x_new = _solve(kern, guess, x, z, Tg[j], h, tol_T, max_iter,
                       x_scale=np.abs(Tg[j] - Tg[j - 1]) / k0)
        _, _, z = kern.balance(x_new, x, z, Tg[j], h)
        x_prev, x, h_prev = x, x_new, h
        x_out[:, j] = x
        if return_states:
            z_out[:, j] = z
    if idx.size != t.size:
        x_out = _interp_rows(t, tg, x_out)
        if return_states:
            z_out = _interp_rows(t, tg, z_out)
    return (x_out, z_out) if return_states else x_out


def _stiffness_scale(plan: Plan) -> np.ndarray:
    return 1.0 / (plan.c_struct + plan.c_mesh)


def _solve(kern, guess, x0, z0, torque, h, tol_T, max_iter, x_scale):
    """Newton inside a bracket on the monotone balance of one step."""
    x = np.array(guess, dtype=float)
    lo = np.full_like(x, -np.inf)
    hi = np.full_like(x, np.inf)
    base = np.abs(x - x0) + (0.0 if x_scale is None else x_scale) + 1e-7
    for _ in range(max_iter):
        g, dg, _ = kern.balance(x, x0, z0, torque, h)
        if np.all(np.abs(g) <= tol_T):
            return x
        lo = np.where(g < 0.0, np.maximum(lo, x), lo)
        hi = np.where(g > 0.0, np.minimum(hi, x), hi)
        step = -g / np.maximum(dg, 1e-300)
        # an unbracketed side: do not jump further than a few expected increments
        limit = 4.0 * base
        step = np.clip(step, -limit, limit)
        xn = x + step
        both = np.isfinite(lo) & np.isfinite(hi)
        outside = both & ((xn <= lo) | (xn >= hi))
        xn = np.where(outside, 0.5 * (lo + hi), xn)
        base = np.where(both, base, 2.0 * base)
        x = np.where(np.abs(g) <= tol_T, x, xn)
    return x


def _interp_rows(t, tg, values):
    out = np.empty((values.shape[0], t.size))
    for i in range(values.shape[0]):
        out[i] = np.interp(t, tg, values[i])
    return out


# --------------------------------------------------------------------------- grids


def sample_grid(time, torque, max_steps: int = 4000, zero_band: float = 0.04):
    """Sample indices to step on for a long record (all of them when ``n <= max_steps``).

    Elsewhere every ``k``-th sample, plus every sample near zero torque (``|T| <
    zero_band·max|T|``, where backlash and the damping contact rule act fast) and around
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
    """The same bench with inertia, by :func:`hdsim.dynamics.locked_wave_generator` (slow).

    The measured torque is interpolated linearly between samples. Any effect is allowed;
    this is the reference the quasi-static evaluator is tested against, and the fallback
    for effects it does not handle.
    """
    from hdsim.dynamics import locked_wave_generator
    from hdsim.simulate import SolverOptions, integrate

    t = np.asarray(time, dtype=float)
    T = np.asarray(torque, dtype=float)

    def applied(ti):
        return np.interp(ti, t, T)

    system = locked_wave_generator(model, applied)
    dt = float(np.min(np.diff(t)))
    opts = options or SolverOptions(max_step=dt)
    result = integrate(system, (t[0], t[-1]), t, opts)
    return np.asarray(result.signals["twist_rad"])
