"""The quasi-static evaluator's step loop, compiled (numba): one parameter set at a time.

The numpy loop of `hdsim.simulation.quasistatic` steps every parameter set of a batch
in lockstep, so each sample costs some forty numpy calls whatever the batch size:
Python's overhead, not arithmetic, sets its speed. Here the same step (the same torque
balance, fitted damping rate, Newton iteration with its bracket, friction step) runs
as scalar code per parameter set, through the laws' compiled twins
(`hdsim.model.effects.kernels`, chosen by each effect's `Effect.compiled`). The
parameter sets are independent, so they are also spread over the cores.

The loop takes the laws as first-class functions of fixed signatures, so it is compiled
once for every combination of laws and cached on disk. The output at every sample (the
body twist interpolated between steps plus the dead zone's angle, `output_twist`) is
compiled too: at 20,000 samples it costs as much as the steps in numpy. The grid is
chosen in numpy (`hdsim.simulation.quasistatic.sample_grid`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange, types

from hdsim.model.effects.kernels import FUNCTION_TYPES

_F8 = types.float64
_I8 = types.int64
_ROW = types.float64[::1]
_MATRIX = types.float64[:, ::1]
_READ_ROW = types.Array(types.float64, 1, "C", readonly=True)  # a measurement's samples are read-only

_NEWTON = types.UniTuple(_F8, 4)(FUNCTION_TYPES["spring"], FUNCTION_TYPES["friction_step"], _ROW, _ROW, _F8, _ROW,
                                 _ROW, _F8, _F8, _F8, _F8, _F8, _F8, _F8, _I8, _F8)


@njit(_NEWTON, cache=True, error_model="numpy")
def _newton(spring, friction_step, ph, pf, e0, s0, s_out, guess, torque, cb, gdT, tol_T, x_tol, dg_floor,
            max_iter, x_scale):
    """One step's balance ``u(e) + friction(e) + cb (e − e0) + gdT = T`` by Newton's method.

    The scalar form of `hdsim.simulation.quasistatic._solve`: plain Newton steps first,
    then a bracket with bisection and steps limited to a few expected increments, and a
    step still unsolved after ``max_iter`` is bisected on its bracket.
    Returns (e, spring torque, spring tangent, 1.0 if solved else 0.0) and writes the
    friction states at e to ``s_out``.
    """
    x = guess
    lo, hi, base = -math.inf, math.inf, 0.0
    g = step = math.nan
    u = k = 0.0
    for it in range(max_iter):
        body, slope, u, k = friction_step(spring, ph, s0, e0, x, 1.0 if x - e0 >= 0.0 else -1.0, pf, s_out)
        g = body + cb * (x - e0) + gdT - torque
        dg = slope + cb
        step = -g / max(dg, dg_floor)
        if it >= 3:
            if it == 3:
                base = abs(x - e0) + x_scale + 1e-8
            if g < 0.0:
                lo = max(lo, x)
            elif g > 0.0:
                hi = min(hi, x)
            limit = 4.0 * base
            xn = x + min(max(step, -limit), limit)
            both = math.isfinite(lo) and math.isfinite(hi)
            if both and (xn <= lo or xn >= hi):
                xn = 0.5 * (lo + hi)
            if not both:
                base *= 2.0
            step = 0.0 if abs(g) <= tol_T else xn - x
        x += step
        if abs(step) <= x_tol:
            break
    solved = (abs(step) <= x_tol or abs(g) <= tol_T) and math.isfinite(x)
    if not solved and math.isfinite(lo) and math.isfinite(hi):  # crawling inside its bracket: bisect it
        for it in range(max_iter):
            x = 0.5 * (lo + hi)
            body, slope, u, k = friction_step(spring, ph, s0, e0, x, 1.0 if x - e0 >= 0.0 else -1.0, pf, s_out)
            g = body + cb * (x - e0) + gdT - torque
            if g < 0.0:
                lo = x
            elif g > 0.0:
                hi = x
            if abs(g) <= tol_T or hi - lo <= 2.0 * x_tol:
                solved = True
                break
    friction_step(spring, ph, s0, e0, x, 1.0 if x - e0 >= 0.0 else -1.0, pf, s_out)
    return x, u, k, 1.0 if solved else 0.0


@njit(types.void(FUNCTION_TYPES["spring"], FUNCTION_TYPES["friction_step"], FUNCTION_TYPES["damping"], _MATRIX,
                 _MATRIX, _MATRIX, _ROW, _ROW, _ROW, _F8, _F8, _I8, _I8, _MATRIX, types.float64[:, :, ::1],
                 types.int64[::1]),
      cache=True, parallel=True, error_model="numpy")
def _run(spring, friction_step, damping, PH, PF, PD, k0, tg, Tg, tol_T, x_tol, max_iter, n_states, E, S, failed):
    M, N = E.shape
    for i in prange(M):
        ph, pf, pd = PH[i], PF[i], PD[i]
        s = np.zeros(n_states)
        s_new = np.zeros(n_states)
        keep = S.shape[1] == N  # the caller wants the states at every step
        dg_floor = 1e-6 * k0[i]
        e, u, k, ok = _newton(spring, friction_step, ph, pf, 0.0, s, s_new, Tg[0] / k0[i], Tg[0], 0.0, 0.0,
                              tol_T, x_tol, dg_floor, max_iter, abs(Tg[0]) / k0[i])
        s[:] = s_new
        failed[i] = -1 if ok else 0
        E[i, 0] = e
        S[i, 0, :] = s
        e_prev, h_prev = e, math.nan
        for j in range(1, N):
            if failed[i] >= 0:  # the row is lost (NaN in the caller): stop spending on it
                E[i, j] = math.nan
                continue
            h, dT = tg[j] - tg[j - 1], Tg[j] - Tg[j - 1]
            guess = e + dT / k0[i] if math.isnan(h_prev) else e + (e - e_prev) * (h / h_prev)
            # exponentially fitted damping rate (see `_Kernel` in the numpy evaluator)
            cb = gdT = 0.0
            c = damping(k / k0[i], pd)
            if c > 0.0:
                # the body's path tangent at the start of the step (a step of zero twist)
                _, slope, _, _ = friction_step(spring, ph, s, e, e, 1.0 if dT >= 0.0 else -1.0, pf, s_new)
                mu = slope * h / c
                beta = mu / math.expm1(mu) if mu < 700.0 else 0.0
                gamma = (1.0 - beta) / mu if mu > 1e-4 else 0.5 - mu / 6.0
                cb, gdT = c * beta / h, gamma * dT
            e_new, u, k, ok = _newton(spring, friction_step, ph, pf, e, s, s_new, guess, Tg[j], cb, gdT, tol_T,
                                      x_tol, dg_floor, max_iter, abs(dT) / k0[i])
            s[:] = s_new
            if not ok:
                failed[i] = j
            e_prev, e, h_prev = e, e_new, h
            E[i, j] = e
            if keep:
                S[i, j, :] = s


@njit(types.float64[:, ::1](types.int64[::1], _ROW, _MATRIX, _READ_ROW, _READ_ROW, _F8, _ROW,
                            FUNCTION_TYPES["gap_twist"], _MATRIX),
      cache=True, parallel=True, error_model="numpy")
def _output(left, weight, E, T, Tg, step_floor, k0, gap_twist, PB):
    M = E.shape[0]
    out = np.empty((M, T.size))
    for i in prange(M):
        compliance = 1.0 / k0[i]
        for n in range(T.size):
            g = left[n]
            dT = Tg[g + 1] - Tg[g]
            de = E[i, g + 1] - E[i, g]
            # the sample's own torque through the branch's compliance, as
            # `hdsim.simulation.quasistatic.branch_compliance`
            c = compliance
            if abs(dT) > step_floor:
                c = min(max(de / dT, 0.0), compliance)
            # T − (Tg + ΔT·w) may be an ulp from 0 on a step (w = 1), where numpy's interp is
            # exact; written the other way round it is exact too, but that ulp flipped a
            # borderline zoo decision (validation/README.md, stop 42), so the form of the
            # frozen runs is kept
            departure = T[n] - (Tg[g] + dT * weight[n])
            out[i, n] = E[i, g] + de * weight[n] + departure * c + gap_twist(T[n] * compliance, PB[i])
    return out


@dataclass(frozen=True)
class CompiledLaws:
    """The compiled twins of a plan's laws (`Effect.compiled`) and their parameter rows."""

    spring: object
    friction_step: object
    damping: object
    gap_twist: object
    rows: tuple  # (hardening, friction, damping, backlash) parameter rows, (M, p) each
    k0: np.ndarray  # base stiffness of each parameter set [N·m/rad]
    n_states: int


def compiled_laws(plan) -> CompiledLaws | None:
    """The plan's laws compiled, or None when some law has no compiled form."""
    forms = [effect.compiled(plan.size, plan.c_struct, plan.c_mesh)
             for effect in (plan.hardening, plan.friction, plan.damping, plan.backlash)]
    if any(form is None for form in forms):
        return None
    (spring,), (friction_step,), (damping,), (gap_twist,) = (functions for functions, _ in forms)
    return CompiledLaws(spring, friction_step, damping, gap_twist, tuple(rows for _, rows in forms),
                        np.ascontiguousarray(1.0 / (plan.c_struct + plan.c_mesh), dtype=float),
                        len(plan.friction.state_names))


def step_loop(laws: CompiledLaws, tg, Tg, tol_T, x_tol, max_iter, want_states):
    """Body twist (M, G) on the grid, friction states (n_states, M, G) or None, and the
    first grid index each parameter set failed at (−1: solved throughout)."""
    size = laws.k0.size
    ph, pf, pd, _ = laws.rows
    E = np.empty((size, tg.size))
    S = np.zeros((size, tg.size if want_states else 1, laws.n_states))
    failed = np.full(size, -1, dtype=np.int64)
    _run(laws.spring, laws.friction_step, laws.damping, ph, pf, pd, laws.k0, np.ascontiguousarray(tg, dtype=float),
         np.ascontiguousarray(Tg, dtype=float), float(tol_T), float(x_tol), int(max_iter), laws.n_states, E, S, failed)
    return E, (np.moveaxis(S, 2, 0) if want_states else None), failed


def output_twist(laws: CompiledLaws, t, tg, e_grid, torque, step_floor: float = 0.0):
    """Output twist (M, n) at every sample: the body twist interpolated linearly from the
    grid (as `numpy.interp`, row by row) and moved by the sample's own torque through the
    branch's compliance (`hdsim.simulation.quasistatic.branch_compliance`), plus the dead
    zone's angle at the sample's torque; a torque step between two steps not above
    ``step_floor`` [N·m] gives no secant."""
    t = np.asarray(t, dtype=float)
    tg = np.asarray(tg, dtype=float)
    # every row shares the grid (first and last sample included, >= 2 points): where each
    # sample falls and its weight, once
    left = np.clip(np.searchsorted(tg, t, side="right") - 1, 0, tg.size - 2).astype(np.int64)
    weight = (t - tg[left]) / (tg[left + 1] - tg[left])
    T = np.ascontiguousarray(torque, dtype=float)
    Tg = np.ascontiguousarray(np.interp(tg, t, T))  # the torque at the steps
    return _output(left, weight, np.ascontiguousarray(e_grid), T, Tg, step_floor, laws.k0, laws.gap_twist,
                   laws.rows[3])
