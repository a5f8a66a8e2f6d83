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
faster than `hdsim.simulation.path.locked_wave_generator` with Radau, which is what makes
hundreds of refits affordable (the test suite checks both agree on a slow profile).

What it solves
--------------
The same elastic path as `hdsim.simulation.path.ElasticPath`, through the same effect
objects (the `HarmonicDrive` slots)::

    e            body twist, behind the dead zone
    B(e, s)      = friction.body_torque: spring u(e − slip(s)) + friction torque(s)
    d            = c(e) · ė, c(e) = damping.coefficient_at(K_t/K₀)   viscous damping torque
    B + d = T(t)                                 the torque balance, inertia dropped
    x            = e + g(T), g = backlash.twist_at_torque(T, K₀)   output twist (= the angle θ)

The dead zone is in series with the body and carries the same torque, so its angle
``g`` is a function of the transmitted torque alone.

Each step from sample ``k`` to ``k+1`` solves the balance at ``t_{k+1}`` for the new
body twist with an exponentially fitted rate for ``ė`` (the coefficient ``c(e)`` taken at
the start of the step); the friction states are advanced over the twist increment by
the friction effect (`Friction.quasistatic`: exactly for Dahl, Coulomb and
Maxwell-slip, whose laws are rate-independent, by sub-steps of the rate law for any
other). The scalar equation per sample is monotone in the new body twist (the dead
zone is not inside it) and is solved by Newton's method kept inside a bracket
(bisection when a Newton step leaves it), vectorised over a batch of parameter sets;
the output twist follows from the torque by the dead zone's inverse. Without damping
(``c = 0``) the result does not depend on the time step at all (rate independence).

A batch may mix *models*: several `HarmonicDrive` objects (each single or a batch)
are stacked into one plan if, slot by slot, they use one effect class or none. A model
without a family gets the carrier class's neutral values (`Effect.neutral`: ``gap = 0``,
``e_inf = 1``, ``c = 0``, a zero friction slope), which reproduce "none" exactly. That
lets a diagnosis evaluate every candidate model of a round, and their
finite-difference Jacobian columns, in one pass over the samples.

Every registered effect works here, including a law defined outside the package;
`dynamic_locked_twist` is the reference with inertia. Where numba is installed and
every law of a batch has a compiled twin (`Effect.compiled`), the same step runs
compiled, one parameter set at a time (`hdsim.simulation.quasistatic_compiled`: a pass
5–30× faster, a 20,000-row diagnosis 4×); the numpy loop here is the reference it is
tested against.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from hdsim.errors import InputError, SolverError
from hdsim.model import effects as fx
from hdsim.model.drive import SLOTS, HarmonicDrive

__all__ = ["UnsupportedEffect", "Plan", "stack_models", "stackable_groups", "locked_twist",
           "dynamic_locked_twist", "sample_grid", "first_mode_period"]


#: how the step loop runs (`locked_twist`'s ``engine``)
ENGINES = ("auto", "compiled", "numpy")


class UnsupportedEffect(InputError):
    """Models that cannot be stacked into one quasi-static batch."""


@dataclass(frozen=True)
class Plan:
    """Models stacked into one batch of ``size`` parameter sets with one carrier per slot."""

    size: int
    c_struct: np.ndarray
    c_mesh: np.ndarray
    hardening: fx.Effect
    backlash: fx.Effect
    friction: fx.Effect
    damping: fx.Effect
    offsets: tuple[int, ...]  # first row of each stacked model


def _carrier(slot: str, models: list[HarmonicDrive], sizes: list[int]) -> fx.Effect:
    effects = [getattr(m, slot) for m in models]
    classes = {type(e) for e in effects if not e.is_null}
    if len(classes) > 1:
        names = sorted(c.id for c in classes)
        raise UnsupportedEffect(f"cannot stack models with {slot} effects {names} in one batch")
    if not classes:
        return fx.NO_EFFECT[slot]
    return classes.pop().stack(effects, sizes)


def stack_models(models) -> Plan:
    """Stack one or several (batch) models into a `Plan` for `locked_twist`."""
    if isinstance(models, HarmonicDrive):
        models = [models]
    models = list(models)
    sizes = [m.batch_size for m in models]
    cs, cm = [], []
    for model, size in zip(models, sizes):
        c_struct, c_mesh = model.split()
        cs.append(np.broadcast_to(np.asarray(c_struct, dtype=float), (size,)))
        cm.append(np.broadcast_to(np.asarray(c_mesh, dtype=float), (size,)))
    offsets = tuple(int(v) for v in np.concatenate([[0], np.cumsum(sizes)[:-1]]))
    return Plan(size=int(sum(sizes)), c_struct=np.concatenate(cs), c_mesh=np.concatenate(cm),
                hardening=_carrier("hardening", models, sizes), backlash=_carrier("backlash", models, sizes),
                friction=_carrier("friction", models, sizes), damping=_carrier("damping", models, sizes),
                offsets=offsets)


def stackable_groups(models) -> list[list[int]]:
    """Indices of ``models`` split into groups that `stack_models` can stack (slot by
    slot one effect class or none), in order of first appearance."""
    groups, classes = [], []
    for i, model in enumerate(models):
        mine = {slot: type(getattr(model, slot)) for slot in SLOTS if not getattr(model, slot).is_null}
        for members, seen in zip(groups, classes):
            if all(seen.get(slot, cls) is cls for slot, cls in mine.items()):
                members.append(i)
                seen.update(mine)
                break
        else:
            groups.append([i])
            classes.append(dict(mine))
    return groups


# --------------------------------------------------------------------------- the step


def _phi_functions(mu):
    """β(μ) = μ/(e^μ − 1) and γ(μ) = (1 − β)/μ, with their limits β(0) = 1, γ(0) = 1/2.

    ``μ = ∞`` (no damping) gives β = γ = 0. Overflow and ∞/∞ are expected here: the
    caller (`locked_twist`) runs under ``np.errstate`` that ignores them.
    """
    beta = mu / np.expm1(mu)
    gamma = np.where(mu > 1e-4, (1.0 - beta) / mu, 0.5 - mu / 6.0)
    return beta, gamma


class _Kernel:
    """The torque balance of one step in the body twist, vectorised over the plan.

    The unknown is the body twist ``e`` (behind the dead zone), so the balance
    ``B(e) + c ė = T`` is smooth and increasing in ``e``; the output twist follows from
    ``e`` and the torque afterwards (`output_twist`).

    Damping uses an *exponentially fitted* rate: over a step of length ``h`` with the
    torque linear in time, the rate entering ``d = c ė`` is ``ė = β Δe/h + γ ΔT/c``
    with ``β = μ/(e^μ − 1)``, ``γ = (1 − β)/μ`` and ``μ = k h/c`` (``k`` the tangent
    stiffness of the body at the start of the step). For a linear spring this makes the
    step *exact* for any ``h`` (the solution of ``c ė = T(t) − k e`` with ``T`` linear over
    the step); as ``c → 0`` it gives ``d → 0`` (rate independence) and as ``h → 0`` it
    tends to backward Euler ``Δe/h``.
    """

    def __init__(self, plan: Plan):
        self.plan = plan
        self.k0 = 1.0 / (plan.c_struct + plan.c_mesh)  # every hardening law starts from K0
        self.spring = plan.hardening.spring_law(plan.c_struct, plan.c_mesh)
        self.friction = plan.friction
        self.n_states = len(plan.friction.state_names)
        self.damping = plan.damping
        self.follows_stiffness = plan.damping.follows_stiffness
        self.any_damping = bool(np.any(np.asarray(plan.damping.coefficient_at(1.0)) > 0))
        self.dg_floor = 1e-6 * self.k0

    def zero_states(self) -> np.ndarray:
        return np.zeros((self.n_states, self.plan.size))

    def coefficient(self, spring_tangent):
        ratio = spring_tangent / self.k0 if self.follows_stiffness else 1.0
        return np.asarray(self.damping.coefficient_at(ratio), dtype=float)

    def rate_coefficients(self, k, u, states, dT, h):
        """(c β / h, γ ΔT) of the fitted rate for a step of length h (see the class doc).

        ``k`` and ``u`` are the spring's tangent and torque at the start of the step (from
        the previous step's last Newton evaluation); ``k`` also sets ``c(e)``.
        """
        if not self.any_damping or not math.isfinite(h):
            return None
        c = self.coefficient(k)
        k_body = self.friction.path_tangent(states, 1.0 if dT >= 0.0 else -1.0, u, k)
        mu = k_body * h / (c + 1e-300)  # c = 0: μ ≈ ∞, β = γ = 0
        beta, gamma = _phi_functions(mu)
        return c * beta / h, gamma * dT

    def balance(self, e, e0, states0, torque, rate):
        """(residual B + d − T, its derivative in e, spring torque, spring tangent)."""
        B, D, _, u, k = self.friction.quasistatic(states0, e0, e, self.spring)
        if rate is None:
            return B - torque, D, u, k
        cb, gdT = rate
        return B + cb * (e - e0) + gdT - torque, D + cb, u, k

    def output_twist(self, e, torque):
        """Output twist x [rad] from body twist e (rows, steps) and the torque (steps)."""
        T = np.broadcast_to(np.asarray(torque, dtype=float)[None, :], e.shape)
        return e + self.plan.backlash.twist_at_torque(T, self.k0[:, None])


def locked_twist(models, time, torque, *, grid=None, tol=1e-9, x_tol=1e-8, max_iter=60,
                 return_states=False, on_failure: str = "raise", engine: str | None = None):
    """Quasi-static output twist [rad] of the locked-WG bench under a measured torque.

    Parameters
    ----------
    models : HarmonicDrive or list of HarmonicDrive or Plan
        Single or batch models; several are stacked (see `stack_models`).
    time : array_like, shape (n,)
        Sample times [s], strictly increasing.
    torque : array_like, shape (n,)
        Torque applied to the output [N·m] (the measured one).
    grid : array_like of int, int or "auto", optional
        Indices of the samples to step on (sorted, first 0, last n-1); the twist at other
        samples is interpolated linearly in time and follows the sample's own torque
        through the branch's compliance (`branch_compliance`). Default: every sample. An int (a step
        budget) or ``"auto"`` (4000) chooses the grid by `sample_grid` from the torque
        alone, so a parameter set's twist does not depend on the others in its batch.
    tol : float
        Torque-balance tolerance relative to ``max |T|``.
    x_tol : float
        A Newton step smaller than this [rad] ends the iteration. Newton converges
        quadratically, so the error left is about ``x_tol² · g''/g'``, far below the
        encoder resolution.
    max_iter : int
        Newton iterations per step at most.
    return_states : bool
        Also return the friction states: shape (M, n) for a one-state law (the Dahl
        torque ``z`` [N·m]), else (n_states, M, n).
    on_failure : {"raise", "nan"}
        What to do with a parameter set whose torque balance Newton could not solve
        within ``max_iter`` at some sample: raise `SolverError` naming the sample, or
        give that row NaN (the fit treats it as a trial that failed).
    engine : {"auto", "compiled", "numpy"}, optional
        How the steps run: "compiled" by numba (`hdsim.simulation.quasistatic_compiled`,
        parameter sets one by one, spread over the cores), "numpy" (all parameter sets in
        lockstep, pure numpy), "auto" the compiled loop where numba is installed and
        every law of the batch has a compiled form, else numpy. Default: the
        environment variable ``HDSIM_ENGINE``, else "auto". The two agree to the Newton
        tolerance.

    Raises
    ------
    InputError
        Time and torque of different lengths, not finite, or time not strictly increasing.
    SolverError
        A torque balance not solved (with ``on_failure="raise"``).

    Returns
    -------
    numpy.ndarray, shape (M, n)
        Twist of each stacked parameter set from the virgin state (zero twist, zero
        friction torque) at the first sample's torque.
    """
    t = np.asarray(time, dtype=float)
    T = np.asarray(torque, dtype=float)
    if t.ndim != 1 or t.shape != T.shape or t.size < 2:
        raise InputError(f"time and torque must be 1-D of one length (>= 2), got {t.shape} and {T.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(T))):
        raise InputError("time and torque must be finite")
    if np.any(np.diff(t) <= 0.0):
        i = int(np.argmax(np.diff(t) <= 0.0))
        raise InputError(f"time must be strictly increasing: sample {i + 1} is at {t[i + 1]:g} s "
                         f"after {t[i]:g} s")
    if on_failure not in ("raise", "nan"):
        raise InputError(f"on_failure must be 'raise' or 'nan', got {on_failure!r}")
    engine = engine or os.environ.get("HDSIM_ENGINE") or "auto"
    if engine not in ENGINES:
        raise InputError(f"engine must be one of {ENGINES}, got {engine!r}")
    plan = models if isinstance(models, Plan) else stack_models(models)
    # cosh overflow far out on the tanh law (tangent → K∞); e^μ overflow and ∞/∞ in the
    # fitted rate of an undamped row (β = γ = 0, `_phi_functions`); an empty bracket's midpoint
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        out, failed = _locked_twist(plan, t, T, grid, tol, x_tol, max_iter, return_states, engine)
    if np.any(failed >= 0):
        x = out[0] if return_states else out
        if on_failure == "raise":
            row = int(np.argmax(failed >= 0))
            raise SolverError(f"quasi-static bench: the torque balance of parameter set {row} was not "
                              f"solved at sample {failed[row]} (t = {t[failed[row]]:g} s) within "
                              f"{max_iter} Newton iterations")
        x[failed >= 0] = np.nan
    return out


def _locked_twist(plan, t, T, grid, tol, x_tol, max_iter, return_states, engine):
    if isinstance(grid, str) or (isinstance(grid, (int, np.integer)) and not isinstance(grid, bool)):
        grid = sample_grid(t, T, max_steps=4000 if isinstance(grid, str) else int(grid))
    idx = np.arange(t.size) if grid is None else np.asarray(grid, dtype=int)
    tg, Tg = t[idx], T[idx]
    tol_T = tol * max(float(np.max(np.abs(T))), 1e-12)
    compiled = None if engine == "numpy" else _compiled_laws(plan, engine)
    if compiled is not None:
        module, laws = compiled
        e_grid, s_out, failed = module.step_loop(laws, tg, Tg, tol_T, x_tol, max_iter, return_states)
        # the body twist is smooth between steps; the dead-zone angle is exact at every sample
        x_out = module.output_twist(laws, t, tg, e_grid, T, _step_floor(Tg))
    else:
        kern = _Kernel(plan)
        e_grid, s_out, failed = _numpy_steps(kern, tg, Tg, tol_T, x_tol, max_iter, return_states)
        e_out = _between_steps(t, tg, e_grid, T, idx, kern.k0) if idx.size != t.size else e_grid
        x_out = kern.output_twist(e_out, T)
    n_states = len(plan.friction.state_names)
    if return_states and idx.size != t.size:
        s_out = np.array([_interp_rows(t, tg, rows) for rows in s_out]).reshape(n_states, plan.size, t.size)
    failed = np.where(failed >= 0, idx[np.maximum(failed, 0)], -1)  # first unsolved sample
    if not return_states:
        return x_out, failed
    return (x_out, (s_out[0] if n_states == 1 else s_out)), failed


def _compiled_laws(plan, engine):
    """(`hdsim.simulation.quasistatic_compiled`, the plan's compiled laws), or None for
    the numpy loop: numba missing, or a law without a compiled form, and engine "auto"."""
    try:
        from hdsim.simulation import quasistatic_compiled
    except ImportError:
        if engine == "compiled":
            raise InputError("the compiled quasi-static engine needs numba: pip install 'hdsim[fast]'") from None
        return None
    laws = quasistatic_compiled.compiled_laws(plan)
    if laws is None:
        if engine == "compiled":
            raise UnsupportedEffect("a law of this model has no compiled form; use engine 'numpy' or 'auto'")
        return None
    return quasistatic_compiled, laws


def _numpy_steps(kern, tg, Tg, tol_T, x_tol, max_iter, return_states):
    """Body twist (M, G) and friction states (n_states, M, G) on the grid, all parameter
    sets in lockstep, and the first grid index each set failed at (−1: none)."""
    M, G = kern.plan.size, tg.size
    e_out = np.empty((M, G))
    s_out = np.empty((kern.n_states, M, G)) if return_states else None
    k0 = kern.k0
    solved = np.empty((M, G), dtype=bool)  # balance solved, per row and grid sample
    e, s, u, k, solved[:, 0] = _solve(kern, Tg[0] / k0, np.zeros(M), kern.zero_states(), Tg[0], None, tol_T,
                                      x_tol, max_iter, np.abs(Tg[0]) / k0)
    e_out[:, 0] = e
    if return_states:
        s_out[:, :, 0] = s
    e_prev, h_prev = e, None
    steps, torque_steps = np.diff(tg).tolist(), np.diff(Tg).tolist()  # Python floats: cheaper per step
    for j in range(1, G):
        h, dT = steps[j - 1], torque_steps[j - 1]
        guess = e + dT / k0 if h_prev is None else e + (e - e_prev) * (h / h_prev)
        rate = kern.rate_coefficients(k, u, s, dT, h)
        e_new, s, u, k, solved[:, j] = _solve(kern, guess, e, s, Tg[j], rate, tol_T, x_tol, max_iter,
                                              abs(dT) / k0)
        e_prev, e, h_prev = e, e_new, h
        e_out[:, j] = e
        if return_states:
            s_out[:, :, j] = s
    return e_out, s_out, np.where(solved.all(axis=1), -1, np.argmin(solved, axis=1))


def _solve(kern, guess, e0, s0, torque, rate, tol_T, x_tol, max_iter, x_scale):
    """Newton on the monotone balance of one step.

    Returns (body twist, friction states, spring torque, spring tangent, solved): a row
    is solved when its last Newton step fell below ``x_tol`` or its balance residual
    below ``tol_T``.

    Plain Newton steps first; if they have not converged after three, the iteration
    keeps a bracket (the balance is increasing in e) and bisects when a Newton step
    leaves it, with unbracketed steps limited to a few expected increments. A row that
    has a bracket but is still not solved after ``max_iter`` steps is bisected on it
    (`_bisect_bracket`): where a friction law's analytic slope is not its sub-stepped
    step's, Newton steps land inside the bracket on alternate sides and crawl.
    """
    x = guess
    lo = hi = None
    for it in range(max_iter):
        g, dg, u, k = kern.balance(x, e0, s0, torque, rate)
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
            mid = 0.5 * (lo + hi)
            xn = np.where(both & ((xn <= lo) | (xn >= hi)), mid, xn)
            base = np.where(both, base, 2.0 * base)
            step = np.where(np.abs(g) <= tol_T, 0.0, xn - x)
        x = x + step
        # a row whose balance is not finite is lost (the caller gets NaN for it): it must not
        # keep the batch iterating to max_iter at every step, as the compiled loop's rows don't
        if np.all((np.abs(step) <= x_tol) | ~np.isfinite(step)):
            break
    solved = (np.abs(step) <= x_tol) | (np.abs(g) <= tol_T)
    if lo is not None and not np.all(solved):
        x, u, k, solved = _bisect_bracket(kern, x, u, k, solved, lo, hi, e0, s0, torque, rate, tol_T, x_tol,
                                          max_iter)
    s = kern.friction.advance(s0, e0, x, kern.spring) if kern.n_states else s0
    return x, s, u, k, solved & np.isfinite(x)


def _bisect_bracket(kern, x, u, k, solved, lo, hi, e0, s0, torque, rate, tol_T, x_tol, max_iter):
    """Bisect the unsolved rows that hold a bracket (``lo < root < hi``) until the balance
    residual is below ``tol_T`` or the bracket narrower than ``2 x_tol``; the solved rows are
    left exactly as they are. Returns (x, u, k, solved)."""
    rows = ~solved & np.isfinite(lo) & np.isfinite(hi)
    for _ in range(max_iter):
        if not rows.any():
            break
        mid = np.where(rows, 0.5 * (lo + hi), x)
        g, _, u_mid, k_mid = kern.balance(mid, e0, s0, torque, rate)
        x, u, k = np.where(rows, mid, x), np.where(rows, u_mid, u), np.where(rows, k_mid, k)
        lo = np.where(rows & (g < 0.0), mid, lo)
        hi = np.where(rows & (g > 0.0), mid, hi)
        done = rows & ((np.abs(g) <= tol_T) | (hi - lo <= 2.0 * x_tol))
        solved = solved | done
        rows = rows & ~done
    return x, u, k, solved


def _between_steps(t, tg, e_grid, T, idx, k0):
    """Body twist (M, n) at every sample from its values on the grid: interpolated in time,
    plus the sample's own torque departure from the torque interpolated the same way, times
    the branch's compliance between the two steps (`branch_compliance`).

    Without the second term a sample between steps would not see its own torque: a noisy
    torque channel's noise, which passes through the compliance into the measured angle's
    model at a step, would be smoothed away between steps, and the residual of a correct
    model would hold that noise coloured (autocorrelated over the grid's spacing) instead
    of white, above its noise floor (a linear spring under 0.1 N·m of torque noise: rms
    1.6× the floor, Ljung–Box p = 0)."""
    Tg = T[idx]
    out = _interp_rows(t, tg, e_grid)
    left = np.clip(np.searchsorted(tg, t, side="right") - 1, 0, tg.size - 2)
    departure = T - np.interp(t, tg, Tg)
    return out + departure[None, :] * branch_compliance(e_grid, Tg, k0)[:, left]


def branch_compliance(e_grid, Tg, k0):
    """(M, steps − 1) compliance [rad/(N·m)] of each interval between two steps: the secant
    of the body twist over the torque, held between 0 and the base compliance ``1/k0``,
    and ``1/k0`` where the torque hardly changes between the steps. A sample's departure
    from the interpolated torque is small and reverses quickly (noise, a ripple), so a
    slipping friction law sees it elastically, at no more than the base compliance; a
    negative secant is a reversal's, and a small torque step makes the secant noise."""
    dT = np.diff(Tg)
    base = 1.0 / np.asarray(k0, dtype=float)[:, None]
    steps = np.abs(dT) > _step_floor(Tg)
    with np.errstate(divide="ignore", invalid="ignore"):
        secant = np.diff(e_grid, axis=1) / np.where(steps, dT, 1.0)[None, :]
    return np.where(steps[None, :], np.clip(secant, 0.0, base), base)


#: a torque step between two grid samples smaller than this share of max |T| gives no secant
SECANT_TORQUE_SHARE = 1e-9


def _step_floor(Tg) -> float:
    return SECANT_TORQUE_SHARE * max(float(np.max(np.abs(Tg))), 1e-300)


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


def sticking_tangent(model: HarmonicDrive) -> tuple[np.ndarray, np.ndarray]:
    """(the spring's base stiffness, the friction's path tangent at rest) [N·m/rad], one per
    sample of a batch (which may vary the geometry or the friction): their ratio is how much
    stiffer than the spring the friction holds the output while it sticks."""
    K = np.broadcast_to(np.asarray(model.base_stiffness, dtype=float), (model.batch_size,))
    rest = np.zeros((len(model.friction.state_names), K.size))
    tangent = np.broadcast_to(np.asarray(model.friction.path_tangent(rest, 1.0, 0.0 * K, K), dtype=float), K.shape)
    return K, tangent


def first_mode_period(model: HarmonicDrive, torque, inertia) -> float:
    """Period [s] of the output's torsional mode at its stiffest up to a torque: the time scale
    the quasi-static evaluator may drop.

    ``2π √(J / K_max)`` with ``K_max`` the largest tangent of the hardening law up to twice
    the twist the base stiffness gives at ``torque`` (the law hardens, so the real twist is
    smaller); the shortest period of a batch.

    Parameters
    ----------
    model : HarmonicDrive
        Single or batch model.
    torque : float or array_like
        Largest torque the path carries [N·m], per parameter set.
    inertia : float or array_like
        Inertia on the output [kg·m²] (the drive's ``J_out`` plus any load), per parameter set.
    """
    c_struct, c_mesh = model.split()
    k0 = 1.0 / (np.asarray(c_struct, dtype=float) + np.asarray(c_mesh, dtype=float))
    reach = 2.0 * np.abs(np.asarray(torque, dtype=float)) / k0
    twist = np.linspace(0.0, 1.0, 33)[:, None] * np.atleast_1d(reach)[None, :]
    k_max = float(np.max(np.abs(model.hardening.tangent(twist, c_struct, c_mesh))))
    return float(2.0 * np.pi * np.sqrt(np.min(np.asarray(inertia, dtype=float)) / k_max))


# --------------------------------------------------------------------------- reference


def dynamic_locked_twist(model: HarmonicDrive, time, torque, options=None) -> np.ndarray:
    """The same bench with inertia, by `hdsim.simulation.path.locked_wave_generator` (slow).

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
