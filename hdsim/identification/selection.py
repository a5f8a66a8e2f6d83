"""The acceptance rules of a diagnosis: how a candidate is scored, when it is added, when
two explanations are too close to call.

The procedure that applies them is `hdsim.identification.diagnosis` (its module text
gives the reasoning for each threshold); the block bootstrap of
`hdsim.identification.confidence` applies the same rules to resampled sums of squares.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hdsim.identification.fit import FitResult, effective_n
from hdsim.identification.residuals import whiteness

__all__ = ["Candidate", "score_candidate", "rule", "holdout_gain_needed", "rate_ambiguity", "explains_as_well",
           "near_tie", "rate_question_left", "separating", "SEPARATING", "SCORE_THRESHOLD", "HOLDOUT_GAIN",
           "FLOOR_HOLDOUT_GAIN", "MIN_GAIN", "TIE_FRACTION", "STRONG_HOLDOUT_GAIN", "SHAPE_MARGIN", "RATE_PAIR"]

#: accept only below this score (ΔBIC with the effective sample size)
SCORE_THRESHOLD = -10.0
#: hold-out prediction error, both folds pooled, must fall by at least this fraction
HOLDOUT_GAIN = 0.05
#: ... and by this much once the residual is at the noise floor (rms within
#: `hdsim.identification.residuals.EXPLAINED_RATIO` of it): a family can then only remove
#: the little structure left, and an imperfect form's proxy removes a few per cent of it
#: (zoo: a backlash after damping with an exponential hardening, 7 %)
FLOOR_HOLDOUT_GAIN = 0.10
#: rms error on all rows must fall by at least this fraction
MIN_GAIN = 0.05
#: near-tie: runner-up within max(10, this fraction of |best score|)
TIE_FRACTION = 0.10
#: a hold-out gain this large on *both* folds stands for the score: a model far from the
#: record leaves a strongly correlated residual whose n_eff makes the BIC timid (the
#: kinematic error under a varying load halves the rms at a score of +7)
STRONG_HOLDOUT_GAIN = 0.10
#: at one loading rate, damping and friction are told apart by loop shape only when their
#: scores differ by more than max(20, this fraction of |best score|)
SHAPE_MARGIN = 0.25
#: the families whose difference is the loading rate
RATE_PAIR = frozenset({"damping", "friction"})

#: the measurement that separates two families explaining the residual about equally well
SEPARATING = {
    frozenset({"damping", "friction"}): "a second loading rate: a damping loop widens with the "
                                        "rate, a friction loop does not",
    frozenset({"backlash", "friction"}): "a small-amplitude cycle (±4 % T_N lost-motion test): "
                                         "backlash is a step of fixed width at zero torque, a "
                                         "friction loop shrinks with the amplitude",
    frozenset({"backlash", "damping"}): "a second loading rate: backlash does not change with "
                                        "the rate, damping does",
    frozenset({"backlash", "hardening"}): "a cycle to a larger torque and a small-amplitude "
                                          "cycle: hardening bends the curve at high load, "
                                          "backlash acts only at zero torque",
    frozenset({"friction", "hardening"}): "unloading from several peak torques: a friction "
                                          "loop reverses at every peak, hardening follows one curve",
    frozenset({"damping", "hardening"}): "a second loading rate: hardening does not change with "
                                         "the rate",
}

def separating(a: str, b: str) -> str:
    if "kinematic_error" in (a, b):
        return ("a kinematic-error test over several output revolutions at constant load: the "
                "kinematic error repeats with the wave-generator angle, the other does not")
    return SEPARATING.get(frozenset({a, b}), "a test at another loading rate and amplitude")


@dataclass
class Candidate:
    """One family tried in one round."""

    family: str
    effect: str
    fit: FitResult
    fold_fits: list
    score: float
    n_eff: float
    holdout_rmse: list
    holdout_gain: list
    pooled_holdout_gain: float
    gain: float
    accepted: bool = False
    reason: str = ""

    @classmethod
    def failed(cls, family: str, effect: str, why: str) -> "Candidate":
        """A candidate whose model could not be built or fitted: rejected, with the reason."""
        return cls(family=family, effect=effect, fit=None, fold_fits=[], score=math.inf, n_eff=0.0,
                   holdout_rmse=[], holdout_gain=[], pooled_holdout_gain=0.0, gain=0.0, accepted=False,
                   reason=f"could not be fitted: {why}")

    def to_json(self) -> dict:
        if self.fit is None:
            return {"family": self.family, "effect": self.effect, "rmse_rad": None, "score": None,
                    "passes": False, "why": self.reason}
        return {"family": self.family, "effect": self.effect, "rmse_rad": self.fit.rmse_rad,
                "score": self.score, "n_eff": self.n_eff,
                "max_abs_error_rad": self.fit.max_abs_rad,
                "holdout_rmse_rad": self.holdout_rmse, "holdout_gain": self.holdout_gain,
                "pooled_holdout_gain": self.pooled_holdout_gain,
                "rmse_gain": self.gain, "passes": self.accepted, "why": self.reason}


def rule(score, fold_gain_min, pooled, gain, holdout_gain: float = HOLDOUT_GAIN):
    """The three conditions of step 4 (numpy-vectorised, for the bootstrap of `_confidence`):
    evidence (score, or a strong hold-out gain on both folds), hold-out gain, rms gain."""
    return ((score < SCORE_THRESHOLD) | (fold_gain_min >= STRONG_HOLDOUT_GAIN),
            pooled >= holdout_gain, gain >= MIN_GAIN)


def holdout_gain_needed(base_fit: FitResult) -> float:
    """The pooled hold-out gain a candidate needs against ``base_fit``: `HOLDOUT_GAIN`, or
    `FLOOR_HOLDOUT_GAIN` when that residual is already at its noise floor."""
    return FLOOR_HOLDOUT_GAIN if whiteness(base_fit.residual)["explained"] else HOLDOUT_GAIN


def rate_ambiguity(best: Candidate, scored: list, current: dict):
    """The damping–friction pair when one loading rate cannot separate them, else None.

    Damping is an extra loss that grows with the rate, friction one that does not; at one
    rate only the loop's shape tells them apart, and an imperfect friction form leaves a
    shape that damping mimics. So: when the best candidate is one of the pair and the
    other is already in the model, or is a candidate that also explains the residual
    (score below the threshold) within ``SHAPE_MARGIN`` of the best, the record cannot
    decide between them.
    """
    if best.family not in RATE_PAIR:
        return None
    other = next(iter(RATE_PAIR - {best.family}))
    if other in current:
        return sorted(RATE_PAIR)
    rival = next((c for c in scored if c.family == other), None)
    if rival is None or not explains_as_well(best.score, rival.score):
        return None
    return sorted(RATE_PAIR)


def rate_question_left(ranked: list, current: dict):
    """The damping–friction pair when, at one loading rate, nothing passes yet a loss is left.

    The rate-pair family best scored of all is one whose partner is already in the model,
    and it explains part of the residual: evidence (score below the threshold) and a
    better prediction of *both* hold-out folds, only too little of it to be added (the
    gain floors). One rate cannot say whether that loss grows with the rate (a damping)
    or is the friction's own shape (its form), so the pair is reported with the second
    rate that separates them instead of a silent "nothing more" (zoo: a damping at 3x
    the noise beside a LuGre friction at one rate, score -96, hold-out gain 5 %).

    Parameters
    ----------
    ranked : list of Candidate
        The round's candidates, best score first.
    current : dict
        Family -> effect of the model they were scored against.

    Returns
    -------
    list of str or None
        ``["damping", "friction"]``, or None.
    """
    if not ranked or ranked[0].family not in RATE_PAIR:
        return None
    top = ranked[0]  # one that could not be fitted scores +inf and has no folds: never a question
    if not (RATE_PAIR - {top.family}) <= set(current):
        return None
    predicts = len(top.holdout_gain) == 2 and min(top.holdout_gain) > 0.0
    return sorted(RATE_PAIR) if top.score < SCORE_THRESHOLD and predicts else None


def near_tie(best_score: float, rival_score: float) -> bool:
    """The rival's score within max(10, ``TIE_FRACTION``·|best|) of the best's, either side."""
    return abs(rival_score - best_score) < max(10.0, TIE_FRACTION * abs(best_score))


def explains_as_well(best_score, rival_score):
    """The rival also explains the residual (score below the threshold) within
    max(20, ``SHAPE_MARGIN``·|best|) of the best score (numpy-vectorised)."""
    return (rival_score < SCORE_THRESHOLD) & (rival_score - best_score
                                               < np.maximum(20.0, SHAPE_MARGIN * np.abs(best_score)))


def score_candidate(family: str, effect_id: str, res: list, base) -> Candidate:
    """Score ``res`` (the fits on all rows, then on each fold) against the model ``base``
    (a diagnosis step: its ``fit`` and ``fold_fits``) and apply the acceptance rule."""
    fit_all, fold_fits = res[0], res[1:]
    r = fit_all.residual[fit_all.rows]
    n_eff = effective_n(r)
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
    needed = holdout_gain_needed(base.fit)
    evidence, holds_out, lowers = rule(score, fold_min, pooled, gain, needed)
    reasons = []
    if not evidence:
        reasons.append(f"score {score:.1f} not below {SCORE_THRESHOLD:g}")
    if not holds_out:
        reasons.append(f"hold-out error falls by only {100 * pooled:.1f} %"
                       + (f" ({100 * needed:.0f} % needed at the noise floor)" if needed > HOLDOUT_GAIN else ""))
    if not lowers:
        reasons.append(f"rms error falls by only {100 * gain:.1f} %")
    ok = not reasons
    return Candidate(family=family, effect=effect_id, fit=fit_all, fold_fits=fold_fits,
                     score=float(score), n_eff=float(n_eff), holdout_rmse=hold, holdout_gain=gains,
                     pooled_holdout_gain=float(pooled),
                     gain=float(gain), accepted=ok, reason="passes" if ok else "; ".join(reasons))
