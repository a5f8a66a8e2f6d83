"""Levenberg–Marquardt fits in lockstep, residuals by variable projection, fit statistics.

Optimiser
---------
Levenberg–Marquardt with forward-difference Jacobians. Many fits run *in lockstep*: at
every tick each active fit asks for its Jacobian columns and a few trial steps (three
damping values, using the Jacobian of the previous tick updated by Broyden's rule), and
all of them are evaluated in one batched pass of the quasi-static evaluator. A diagnosis
round (every candidate, every hold-out fold) therefore costs about as many passes as one
fit.

Uncertainty
-----------
The covariance ``s² (JᵀJ)⁻¹`` at the optimum (offset included), with ``s²`` the residual
variance, mapped to the physical parameters by the derivative of the transform; it is
widened by ``√(n/n_eff)``, ``n_eff = n (1 − ρ₁)/(1 + ρ₁)`` with ``ρ₁`` the lag-one
autocorrelation of the residual, because a correlated residual carries less information
than ``n`` independent samples.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import MappingProxyType

import numpy as np

from hdsim.identification.problem import Evaluator, FitProblem

__all__ = ["fit_many", "residuals", "bic", "lag1", "effective_n", "uncertainty", "FittedRows", "check_nested",
           "judge_nested", "NESTING_TOLERANCE"]


def _on_rows(prob: FitProblem, a: np.ndarray) -> np.ndarray:
    """``a`` (samples on its last axis) on the problem's fitted rows, without a copy when
    they are all of them."""
    return a if prob.row_index is None else np.take(a, prob.row_index, axis=-1)


def residuals(ev: Evaluator, prob: FitProblem, twist: np.ndarray):
    """(residual on the problem's rows (M, n_rows), full residual (M, n), linear coefficients)."""
    target = ev.y_rel[None, :] - twist
    coef = _on_rows(prob, target) @ prob.basis_pinv.T
    full = target - coef @ prob.basis.T
    return _on_rows(prob, full), full, coef


def row_residuals(ev: Evaluator, prob: FitProblem, twist: np.ndarray) -> np.ndarray:
    """The residual on the problem's rows alone (M, n_rows), as `residuals` gives it: the
    optimiser's every pass needs only these, and a fold's rows are a part of the record."""
    target = _on_rows(prob, ev.y_rel)[None, :] - _on_rows(prob, twist)
    return target - (target @ prob.basis_pinv.T) @ _on_rows(prob, prob.basis.T)


def fit_many(ev: Evaluator, problems: list[FitProblem], *, tol: float = 1e-3) -> int:
    """Run the Levenberg–Marquardt fits of ``problems`` in lockstep (in place).

    A fit stops after two iterations in a row that lower its cost by less than ``tol``
    (relative; 1e-3 of the RSS is a BIC change of n·1e-3, below any decision threshold),
    after ``max_iter`` iterations, or when no damping value gives a lower cost. A fit
    whose start holds a fitted model it contains (`hdsim.identification.problem.NestedStart`)
    evaluates that model's optimum on its first pass and ends there if it would end above
    it: the stopping rule and the iteration limit end a fit wherever it is, and a start
    guessed from the data may lie in another basin.
    Returns the number of batched passes (ticks) it took.
    """
    pending = [p for p in problems if not p.done]
    ticks = 0
    while pending:
        requests = []
        for p in pending:
            steps = p.fd_steps()
            first = p.J is None
            if first:  # first tick: the start and its Jacobian (and the nested start)
                trials = None
                U = np.vstack([p.u[None, :], p.u[None, :] + np.diag(steps)])
                if _takes_nested(p, first):
                    U = np.vstack([U, p.nested.u[None, :]])
            else:  # Jacobian at the current point and trial steps from the previous one
                trials = _trial_points(p)
                U = np.vstack([p.u[None, :] + np.diag(steps), trials])
            requests.append((p, first, steps, U, trials))
        models = [p.batch_model(U) for p, _, _, U, _ in requests]
        twist = ev.twist(models)
        ticks += 1
        row = 0
        for p, first, steps, U, trials in requests:
            block = twist[row:row + U.shape[0]]
            row += U.shape[0]
            r_rows = row_residuals(ev, p, block)
            if _takes_nested(p, first):
                _hold_nested(p, r_rows[-1], block[-1])
                r_rows, block = r_rows[:-1], block[:-1]
            _update(p, r_rows, first, steps, trials, tol, block)
            if p.done:
                _keep_nested(p)
        pending = [p for p in pending if not p.done]
    return ticks


def _takes_nested(p: FitProblem, first: bool) -> bool:
    """True on the first pass of a fit with a nested start not yet evaluated."""
    return first and p.nested is not None and p.nested.r is None


def _hold_nested(p: FitProblem, r: np.ndarray, twist: np.ndarray) -> None:
    """Keep the nested start's residual on the problem's rows, its cost and its twist."""
    cost = float(r @ r)
    p.nested.r, p.nested.twist = r, twist
    p.nested.cost = cost if np.isfinite(cost) else np.inf


def _keep_nested(p: FitProblem) -> None:
    """Go back to the nested start when the finished fit ended above it (or failed).

    Its Jacobian is evaluated on one more pass (the uncertainties need it), after which
    the fit is done (`_update`)."""
    nest = p.nested
    if nest is None or nest.kept or nest.r is None or not np.isfinite(nest.cost) or p.cost <= nest.cost:
        return
    p.u, p.r, p.cost, p.twist_at_u = nest.u.copy(), nest.r, nest.cost, nest.twist
    p.J, p.done, nest.kept = None, False, True


def _trial_points(p: FitProblem) -> np.ndarray:
    """Trial steps from the current Jacobian for three damping values."""
    J, r = p.J, p.r
    A = J.T @ J
    g = J.T @ r
    D = np.maximum(np.diag(A), 1e-12 * max(np.max(np.diag(A)), 1e-300))
    out = []
    for factor in (0.1, 1.0, 10.0):
        lam = p.lam * factor
        try:
            step = -np.linalg.solve(A + lam * np.diag(D), g)
        except np.linalg.LinAlgError:
            step = -g / (D * (1 + lam))
        step = np.clip(np.where(np.isfinite(step), step, 0.0), -5.0, 5.0)
        out.append(p.u + step)
    return np.array(out)


def _update(p: FitProblem, r_rows: np.ndarray, has_base: bool, steps, trials, tol, twist) -> None:
    k = p.u.size
    if has_base:  # first tick: base point and Jacobian
        base = r_rows[0]
        if not (p.nested is not None and p.nested.kept):
            p.r, p.twist_at_u = base, twist[0]
        # else the kept model stays as first evaluated: the evaluator's result moves with
        # the batch a row is in (a parameter array of one row and of two round differently
        # in the last bit, and a stiff friction law's Newton stop turns that into ~1e-7 rad),
        # and the fit is judged against the cost it had then; the Jacobian differences
        # below are taken within this batch
        p.cost = float(p.r @ p.r)
        if not np.isfinite(p.cost):
            p.done, p.message = True, "failed: the model cannot be evaluated at the start values"
            return
        J = ((r_rows[1:1 + k] - base) / steps[:, None]).T
        # a column the evaluator could not solve carries no slope (a NaN would make every step NaN)
        p.J = np.where(np.isfinite(J), J, 0.0)
        if p.nested is not None and p.nested.kept:
            p.done, p.message = True, (f"converged: kept the fitted model it contains ({', '.join(p.nested.families)} "
                                       "neutral); the fit from its start ended above it")
        return
    Jcols = r_rows[:k]
    trial_r = r_rows[k:]
    # the Jacobian at the current point (evaluated around p.u); base residual is p.r
    J_new = ((Jcols - p.r) / steps[:, None]).T
    if not np.all(np.isfinite(J_new)):  # a column the evaluator could not solve: keep the old one
        J_new = np.where(np.isfinite(J_new), J_new, p.J)
    costs = np.einsum("ij,ij->i", trial_r, trial_r)
    costs = np.where(np.isfinite(costs), costs, np.inf)  # a trial the evaluator could not solve
    best = int(np.argmin(costs))
    p.iterations += 1
    if costs[best] < p.cost:
        du = trials[best] - p.u
        r_best = trial_r[best]
        # Broyden update of the fresh Jacobian to the accepted point
        pred = p.r + J_new @ du
        denom = float(du @ du)
        if denom > 0:
            J_new = J_new + np.outer(r_best - pred, du) / denom
        rel = (p.cost - costs[best]) / max(p.cost, 1e-300)
        p.u, p.r, p.twist_at_u, p.cost = trials[best], r_best, twist[k + best], float(costs[best])
        p.lam = max(p.lam * (0.1, 1.0, 10.0)[best] * 0.5, 1e-9)
        p.stalls = p.stalls + 1 if rel < tol else 0
    else:
        p.lam = min(p.lam * 100.0, 1e10)
        p.stalls += 1
    p.J = J_new
    if p.stalls >= 2:
        p.done, p.message = True, f"converged: the cost fell by less than {tol:g} twice in a row"
    elif p.lam >= 1e10:
        p.done, p.message = True, "converged: no step lowers the cost (a minimum)"
    elif p.iterations >= p.max_iter:
        p.done, p.message = True, f"not converged: stopped at the iteration limit ({p.max_iter})"


#: a fit may end above the model it contains by this share of that model's cost at most
#: (the evaluator's round-off; a larger excess is a defect of the fit, not a result)
NESTING_TOLERANCE = 1e-6


def _no_worse(cost: float, baseline_cost: float) -> bool:
    """``cost`` at most ``baseline_cost`` within `NESTING_TOLERANCE` (False for NaN)."""
    return cost <= baseline_cost * (1.0 + NESTING_TOLERANCE) + 1e-300


def check_nested(candidate_cost: float, baseline_cost: float, label: str = "") -> None:
    """Raise `RuntimeError` (an internal error) when a fit ends worse than a model it contains.

    Parameters
    ----------
    candidate_cost, baseline_cost : float
        RSS of the larger model and of the model it contains, on the same rows [rad² or N²·m²].
    label : str
        What was fitted, for the message.
    """
    if not _no_worse(candidate_cost, baseline_cost):
        raise RuntimeError(f"internal error: the fit of {label or 'a model'} ended at RSS {candidate_cost:.9g}, "
                           f"above the {baseline_cost:.9g} of the model it contains (by "
                           f"{candidate_cost / max(baseline_cost, 1e-300) - 1.0:.3g} relative; at most "
                           f"{NESTING_TOLERANCE:g})")


def judge_nested(candidate, fit, baseline_cost: float, label: str) -> bool:
    """Hold ``fit`` (a fit of ``candidate``'s model) to its contained model's ``baseline_cost``:
    True once `check_nested` has found it no worse, when it can be judged; else False, with
    ``candidate`` marked not judged.

    It can be judged when it ends at or below ``baseline_cost`` (nothing to explain: whatever
    its structure's path), or when its structure gives the contained model the same cost
    (``fit.contained_cost`` within `NESTING_TOLERANCE`): `check_nested` then holds it to never
    ending above. It cannot when it ends above and its structure gives the contained model a
    higher cost: the evaluator's own error on the record exceeds its noise (a zero gap or a
    zero damping changes the path the quasi-static evaluator takes, and on a nearly
    noise-free record the micro-slip friction's twist moves by ~1e-6 rad).
    """
    contained = getattr(fit, "contained_cost", None)
    if _no_worse(fit.rss, baseline_cost) or contained is None or _no_worse(contained, baseline_cost):
        check_nested(fit.rss, baseline_cost, label)
        return True
    excess = contained / max(baseline_cost, 1e-300) - 1.0
    candidate.accepted = False
    candidate.reason = (f"not judged: in this form the model it contains costs {100 * excess:.3g} % more than it "
                        "was fitted at (the evaluator's resolution on this record is coarser than its noise)")
    return False


class FittedRows:
    """``rss`` and ``n`` over the rows a fit minimised (``residual`` and ``rows`` of a fit result)."""

    residual: np.ndarray
    rows: np.ndarray
    #: what `hdsim.fit` found of the record and of the fit against the datasheet (the data
    #: checks and plausibility warnings, as JSON objects) and the data summary; empty for a
    #: fit made below the workflow
    checks: Sequence = ()
    data: Mapping = MappingProxyType({})

    @property
    def rss(self) -> float:
        r = self.residual[self.rows]
        return float(r @ r)

    @property
    def n(self) -> int:
        return int(np.count_nonzero(self.rows))

    def save(self, path) -> Path:
        """Write the fit's file (its ``to_toml``) to ``path`` atomically; returns the path."""
        from hdsim.atomic import write_text_atomic

        path = Path(path)
        write_text_atomic(path, self.to_toml())
        return path


def bic(rss: float, n: float, k: int) -> float:
    """Bayesian information criterion ``n ln(RSS/n) + k ln n`` (Gaussian errors)."""
    return n * math.log(max(rss, 1e-300) / n) + k * math.log(n)


def lag1(r: np.ndarray) -> float:
    r = np.asarray(r, dtype=float) - np.mean(r)
    den = float(r @ r)
    return float(r[1:] @ r[:-1]) / den if den > 0 else 0.0


def effective_n(r: np.ndarray) -> float:
    """``n (1 − ρ₁)/(1 + ρ₁)``: samples worth of independent information in a residual."""
    rho = min(max(lag1(r), 0.0), 0.999)
    return max(r.size * (1.0 - rho) / (1.0 + rho), 2.0)


#: a combination of parameters whose singular value, columns scaled to unit norm, is below
#: this share of the largest is one the record does not determine
UNDETERMINED_SINGULAR = 1e-12


def inverse_gram(A: np.ndarray) -> np.ndarray:
    """``(AᵀA)⁻¹`` of a least-squares design ``A`` (rows × parameters), with an infinite
    variance for each parameter the design does not determine.

    The columns are scaled to unit norm first: a parameter's column may be twenty orders of
    magnitude smaller than another's (a twist per unit of a stiffness coordinate against
    one per radian of offset), and a pseudo-inverse of the unscaled ``AᵀA`` would truncate
    it and report a variance of zero for what the record hardly sees. A parameter with no
    effect (a zero column), or with weight in a combination the scaled design does not
    determine (`UNDETERMINED_SINGULAR`), gets an infinite variance and no covariance.
    """
    k = A.shape[1]
    norms = np.sqrt(np.einsum("ij,ij->j", A, A))
    seen = norms > 0
    _, sv, vt = np.linalg.svd(A[:, seen] / norms[seen], full_matrices=False)
    kept = sv > UNDETERMINED_SINGULAR * sv[0] if sv.size else sv > 0
    inverse = (vt[kept].T / sv[kept] ** 2) @ vt[kept] / np.outer(norms[seen], norms[seen])
    out = np.zeros((k, k))
    out[np.ix_(seen, seen)] = inverse
    lost = ~seen
    lost[np.flatnonzero(seen)] = np.sum(vt[~kept] ** 2, axis=0) > 1e-6
    out[lost, :] = 0.0
    out[:, lost] = 0.0
    out[lost, lost] = np.inf
    return out


def json_finite(values: dict) -> dict:
    """``values`` for JSON, which has no number for an infinite or undefined float: each such
    float (a variance `inverse_gram` could not determine, a ratio over a zero floor) is None."""
    return {k: (float(v) if math.isfinite(v) else None) if isinstance(v, float) else v for k, v in values.items()}


def covariance(prob: FitProblem, r: np.ndarray) -> np.ndarray | None:
    """Covariance of the fitted coordinates ``u`` and the offset (last row and column),
    ``s² (JᵀJ)⁻¹`` (`inverse_gram`: infinite for what the record does not determine) widened
    by ``n / n_eff`` for a correlated residual; None without a Jacobian."""
    if prob.J is None:
        return None
    try:
        return widened_inverse(np.hstack([prob.J, np.ones((r.size, 1))]), r)
    except np.linalg.LinAlgError:
        return None


def widened_inverse(A: np.ndarray, r: np.ndarray, extra_dof: int = 0) -> np.ndarray:
    """``s² (AᵀA)⁻¹`` (`inverse_gram`) widened by ``n / n_eff`` for a correlated residual
    ``r``, with ``s² = rᵀr / (n − columns − extra_dof)``: the covariance of the twist fits,
    their linear coefficients and the sweep. (A breakaway fit's is ``s² (AᵀA)⁻¹`` unwidened:
    its rows are a few short starts, whose residual is not the long correlated record the
    widening is for; left as the battery measured it.)"""
    n = r.size
    s2 = float(r @ r) / max(n - A.shape[1] - extra_dof, 1)
    return inverse_gram(A) * s2 * (n / effective_n(r))


def linear_covariance(prob: FitProblem, r: np.ndarray) -> np.ndarray:
    """Covariance of the coefficients solved linearly at the fitted coordinates (the offset
    first, then the kinematic error's), ``s² (BᵀB)⁻¹`` on the fitted rows widened by
    ``n / n_eff`` as `covariance` is: conditional on the fitted coordinates, as the offset's
    own variance there is."""
    return widened_inverse(prob.basis[prob.rows], r, prob.u.size)


def uncertainty(prob: FitProblem, cov: np.ndarray | None) -> dict:
    """1-sigma uncertainties of the physical parameters and the offset from the covariance
    of the fitted coordinates (`covariance`: Jacobian with the offset column, n_eff-widened);
    empty without a covariance."""
    if cov is None:
        return {}
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    # an undetermined coordinate stays undetermined whatever its transform's slope (0 at a bound)
    out = {name: float(abs(tr.dphys_du(u)) * s) if np.isfinite(s) else math.inf
           for name, tr, u, s in zip(prob.names, prob.transforms, prob.u, sd)}
    out["offset_rad"] = float(sd[-1])
    return out
