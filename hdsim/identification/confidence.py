"""How sure a diagnosis is: block-bootstrap inclusion probabilities and a comparison table.

Blocks
------
Neighbouring samples of a bench record are not independent (the residual of an
imperfect model is smooth over a cycle), so the record is resampled by whole blocks:
the torque cycles of a locked test (a cycle closes with a rising leg after a falling
one), the wave-generator revolutions of a kinematic-error test (ten per block when
there are enough for ten blocks).

Inclusion probability
---------------------
Each round of a diagnosis compares the model with every candidate family added. For
``R`` resamples of the blocks (with replacement, Efron's bootstrap applied to blocks as
in Künsch 1989), the sums of squares that enter the acceptance rule (all-rows fit,
hold-out predictions of both folds) are re-added with the resampled block counts and
the rule is applied again: the share of resamples in which a family would be the one
added is its inclusion probability for that round, and the share in which none would
be added is the probability of stopping there. The fits are not redone per resample
(that would cost a diagnosis each); the hold-out terms, which come from fits that did
not see those rows, carry the optimism a refit would show. It is the block-resampled
analogue of the inclusion probabilities of ensemble SINDy (Fasel et al., 2022).

Comparison table
----------------
In the manner of ``loo_compare`` (Vehtari, Gelman & Gabry, 2017): for every model of a
round, the expected log predictive density of its hold-out predictions under a Gaussian
error with the best model's hold-out variance, ``elpd = Σ_i −½ ln(2πσ²) − r_i²/(2σ²)``
[nats], its difference from the best and the standard error of that difference,
``se = √(B · var_b(d_b))`` over the ``B`` blocks' summed pointwise differences ``d_b``
(blocks instead of points, for the same reason as above).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hdsim.identification.folds import blocks
from hdsim.identification.policy import Thresholds, explains_as_well
from hdsim.identification.selection import holdout_gain_needed, rule

__all__ = ["BlockSums", "block_labels", "block_sums", "resample_counts", "comparison_table", "RESAMPLES",
           "diagnosis_confidence"]

#: resamples of the blocks: the standard error of a probability p is √(p(1−p)/R) ≤ 0.016
RESAMPLES = 1000


def block_labels(n: int, starts) -> np.ndarray:
    """Block index (0, 1, …) of each of ``n`` rows, blocks starting at the row indices ``starts``."""
    starts = np.unique(np.clip(np.asarray(list(starts), dtype=int), 0, max(n - 1, 0)))
    # rows before the first start (and every row when there is none) belong to block 0
    return np.maximum(np.searchsorted(starts, np.arange(n), side="right") - 1, 0)


@dataclass(frozen=True)
class BlockSums:
    """Per-block sums (shape (B,)) of one model's squared residuals.

    ``fit``: the all-rows fit's residual; ``holdout``: the hold-out prediction of each
    row (by the fold fit that did not see it); ``holdout_by_fold``: the same, split by
    the fold a row belongs to (shape (2, B)).
    """

    fit: np.ndarray
    holdout: np.ndarray
    holdout_by_fold: np.ndarray


def block_sums(labels: np.ndarray, n_blocks: int, fit_residual, holdout_residual, fold_of_row) -> BlockSums:
    """`BlockSums` of one model from its residuals (all NaN-free, shape (n,))."""
    sq_fit = np.bincount(labels, weights=np.square(fit_residual), minlength=n_blocks)
    sq_ho = np.square(holdout_residual)
    by_fold = np.array([np.bincount(labels, weights=np.where(fold_of_row == k, sq_ho, 0.0), minlength=n_blocks)
                        for k in (0, 1)])
    return BlockSums(fit=sq_fit, holdout=by_fold.sum(axis=0), holdout_by_fold=by_fold)


def resample_counts(n_blocks: int, resamples: int = RESAMPLES, seed: int = 0) -> np.ndarray:
    """(resamples, n_blocks) counts of each block in a resample with replacement."""
    draws = np.random.default_rng(seed).integers(0, n_blocks, size=(resamples, n_blocks))
    return np.stack([np.bincount(row, minlength=n_blocks) for row in draws]).astype(float)


def comparison_table(names, holdout_residuals, labels: np.ndarray) -> list[dict]:
    """``loo_compare``-style rows, best first: model, elpd, elpd_diff, se_diff [nats].

    Parameters
    ----------
    names : list of str
        Model names.
    holdout_residuals : list of numpy.ndarray
        Each model's hold-out residual at every row [rad] (or any unit, the same for all).
    labels : numpy.ndarray
        Block index of each row (`block_labels`).
    """
    R = np.asarray(holdout_residuals, dtype=float)
    mse = np.mean(R * R, axis=1)
    best = int(np.argmin(mse))
    var = max(float(mse[best]), 1e-300)
    lpd = -0.5 * math.log(2.0 * math.pi * var) - R * R / (2.0 * var)
    n_blocks = int(labels.max()) + 1 if labels.size else 1
    per_block = np.stack([np.bincount(labels, weights=row, minlength=n_blocks) for row in lpd])
    elpd = per_block.sum(axis=1)
    rows = []
    for i in np.argsort(-elpd):
        d = per_block[i] - per_block[best]
        se = math.sqrt(n_blocks * float(np.var(d, ddof=1))) if n_blocks > 1 else None
        rows.append({"model": names[i], "elpd": float(elpd[i]), "elpd_diff": float(elpd[i] - elpd[best]),
                     "se_diff": 0.0 if i == best else se})
    return rows


def diagnosis_confidence(meas, steps: list, masks: list, one_rate: bool, thresholds: Thresholds, rate_partner) -> dict:
    """Inclusion probabilities and comparison tables by round (`hdsim.identification.confidence`),
    with the acceptance rule of ``thresholds`` and the rate pairs of ``rate_partner``
    (family -> the family one loading rate cannot tell it from)."""
    starts, block_rule = blocks(meas)
    n = len(meas)
    labels = block_labels(n, starts)
    B = int(labels.max()) + 1
    counts = resample_counts(B) if B >= 2 else None
    fold_of_row = masks[1].astype(int)
    n_star = counts @ np.bincount(labels, minlength=B) if counts is not None else None

    def sums(fit, fold_fits):
        holdout = np.where(masks[0], fold_fits[1].residual, fold_fits[0].residual)
        return block_sums(labels, B, fit.residual, holdout, fold_of_row), holdout

    out_rounds, inclusion = [], {}
    for k, step in enumerate(steps):
        cands = [c for c in step.candidates if c.fit is not None and len(c.fold_fits) == 2]
        if not cands:
            continue
        base, base_holdout = sums(step.fit, step.fold_fits)
        holdouts, probabilities = [base_holdout], {}
        scores, ok = [], []
        for c in cands:
            cs, holdout = sums(c.fit, c.fold_fits)
            holdouts.append(holdout)
            if counts is None:
                continue
            ratio = lambda a, b: np.maximum(counts @ a, 1e-300) / np.maximum(counts @ b, 1e-300)  # noqa: E731
            n_eff = np.maximum(n_star * c.n_eff / n, 2.0)
            score = n_eff * np.log(ratio(cs.fit, base.fit)) + (c.fit.n_params - step.fit.n_params) * np.log(n_eff)
            fold_min = np.minimum(*(1.0 - np.sqrt(ratio(cs.holdout_by_fold[i], base.holdout_by_fold[i]))
                                    for i in (0, 1)))
            parts = rule(score, fold_min, 1.0 - np.sqrt(ratio(cs.holdout, base.holdout)),
                         1.0 - np.sqrt(ratio(cs.fit, base.fit)), holdout_gain_needed(step.fit, thresholds),
                         thresholds)
            scores.append(score)
            ok.append(parts[0] & parts[1] & parts[2])
        if counts is not None:
            S = np.where(np.array(ok), np.array(scores), np.inf)
            best = np.argmin(S, axis=0)
            chosen = np.isfinite(np.min(S, axis=0))
            if one_rate:  # the same stop as the procedure's when one rate cannot separate the pair
                fams = [c.family for c in cands]
                for i, c in enumerate(cands):
                    other = rate_partner(c.family)
                    if not other:
                        continue
                    mine = chosen & (best == i)
                    if other in step.effects:
                        chosen &= ~mine
                    elif other in fams:
                        chosen &= ~(mine & explains_as_well(S[i], scores[fams.index(other)], thresholds))
            probabilities = {c.family: float(np.mean(chosen & (best == i))) for i, c in enumerate(cands)}
            # a family's figure is from its last round as a candidate: the round that
            # added it (it is no candidate afterwards), else the round the procedure stopped
            inclusion.update(probabilities)
            probabilities["none"] = float(1.0 - np.mean(chosen))
        names = ["(nothing added)"] + [c.family for c in cands]
        out_rounds.append({"round": k + 1, "probabilities": probabilities,
                           "comparison": comparison_table(names, holdouts, labels)})
    return {"blocks": B, "block_rule": block_rule, "resamples": 0 if counts is None else int(counts.shape[0]),
            "inclusion": inclusion, "rounds": out_rounds}
