"""The acceptance rule of the twist tests (stiffness, kinematic error): how a candidate is
scored and when it passes.

The procedure that applies it is `hdsim.identification.engine` with the policy of
`hdsim.identification.policy`; the reasoning for each threshold is in
`hdsim.identification.diagnosis` and the history of their tuning in validation/README.md.
The block bootstrap of `hdsim.identification.confidence` applies the same rule to
resampled sums of squares.
"""

from __future__ import annotations

import math

from hdsim.identification.engine import Candidate
from hdsim.identification.fit import FitResult, effective_n
from hdsim.identification.policy import Thresholds
from hdsim.identification.residuals import whiteness

__all__ = ["TWIST_THRESHOLDS", "score_candidate", "rule", "holdout_gain_needed"]

#: the thresholds of the twist tests: ΔBIC below -10 (Kass-Raftery "very strong"), or a 10 %
#: hold-out gain on both folds; a pooled hold-out gain of 5 % (10 % at the noise floor: a
#: backlash proxy after damping with an exponential hardening removes 7 % there); an rms
#: gain of 5 %; near ties within max(10, 10 %); one loading rate tells damping from friction
#: by shape only beyond max(20, 25 %)
TWIST_THRESHOLDS = Thresholds(score=-10.0, holdout_gain=0.05, floor_holdout_gain=0.10, strong_holdout_gain=0.10,
                              min_gain=0.05, tie_fraction=0.10, tie_floor=10.0, shape_margin=0.25,
                              shape_floor=20.0)


def rule(score, fold_gain_min, pooled, gain, holdout_gain: float, thresholds: Thresholds = TWIST_THRESHOLDS):
    """The three conditions a candidate must meet (numpy-vectorised, for the bootstrap):
    evidence (score, or a strong hold-out gain on both folds), pooled hold-out gain, rms gain."""
    return ((score < thresholds.score) | (fold_gain_min >= thresholds.strong_holdout_gain),
            pooled >= holdout_gain, gain >= thresholds.min_gain)


def holdout_gain_needed(base_fit: FitResult, thresholds: Thresholds = TWIST_THRESHOLDS) -> float:
    """The pooled hold-out gain a candidate needs against ``base_fit``: the kind's
    ``holdout_gain``, or ``floor_holdout_gain`` when that residual is already at its noise floor."""
    return thresholds.floor_holdout_gain if whiteness(base_fit.residual)["explained"] else thresholds.holdout_gain


def score_candidate(family: str, effect_id: str, res: list, base,
                    thresholds: Thresholds = TWIST_THRESHOLDS) -> Candidate:
    """Score ``res`` (the fits on all rows, then on each fold) against the model ``base``
    (a diagnosis step: its ``fit`` and ``fold_fits``) and apply the acceptance rule."""
    fit_all, fold_fits = res[0], res[1:]
    n_eff = effective_n(fit_all.residual[fit_all.rows])
    dk = fit_all.n_params - base.fit.n_params
    score = n_eff * math.log(max(fit_all.rss, 1e-300) / max(base.fit.rss, 1e-300)) + dk * math.log(n_eff)
    hold, gains = [], []
    pooled_c = pooled_b = 0.0
    for cf, bf in zip(fold_fits, base.fold_fits):
        out = ~cf.rows
        rc, rb = cf.rmse(out), bf.rmse(out)
        hold.append(rc)
        gains.append(1.0 - rc / rb if rb > 0 else 0.0)
        pooled_c += out.sum() * rc**2
        pooled_b += out.sum() * rb**2
    pooled = 1.0 - math.sqrt(pooled_c / pooled_b) if pooled_b > 0 else 0.0
    gain = 1.0 - fit_all.rmse_rad / base.fit.rmse_rad if base.fit.rmse_rad > 0 else 0.0
    fold_min = min(gains) if len(gains) == 2 else -math.inf
    needed = holdout_gain_needed(base.fit, thresholds)
    evidence, holds_out, lowers = rule(score, fold_min, pooled, gain, needed, thresholds)
    reasons = []
    if not evidence:
        reasons.append(f"score {score:.1f} not below {thresholds.score:g}")
    if not holds_out:
        reasons.append(_change("hold-out error", pooled, needed)
                       + (" at the noise floor" if needed > thresholds.holdout_gain else ""))
    if not lowers:
        reasons.append(_change("rms error", gain, thresholds.min_gain))
    ok = not reasons
    figures = {"rmse_rad": fit_all.rmse_rad, "max_abs_error_rad": fit_all.max_abs_rad, "holdout_rmse_rad": hold,
               "pooled_holdout_gain": float(pooled), "rmse_gain": float(gain)}
    return Candidate(family=family, effect=effect_id, fit=fit_all, fold_fits=fold_fits, score=float(score),
                     n_eff=float(n_eff), holdout_gain=gains, accepted=ok, reason="passes" if ok else "; ".join(reasons),
                     figures=figures)


def _change(what: str, gain: float, needed: float) -> str:
    """How an error changed against the fall needed, in words: "falls by only 3.2 %", "does
    not change", "rises by 250 %" (never "falls by only -0.0 %")."""
    if abs(gain) < 5e-4:
        told = "does not change"
    elif gain > 0:
        told = f"falls by only {100 * gain:.1f} %"
    else:
        told = f"rises by {100 * -gain:.3g} %"
    return f"{what} {told} ({100 * needed:.0f} % fall needed)"

