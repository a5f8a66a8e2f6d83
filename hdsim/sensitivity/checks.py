"""Consistency safeguards on a set of Sobol' indices (docs/sensitivity.md, section 6).

Generic truths for independent inputs, each tested with a tolerance that adds the
estimate's own replicate half-widths (in quadrature) to a fixed ``tol``:

* ΣS ≤ 1 + tol and ΣST ≥ 1 − tol,
* S_i ≤ ST_i + tol (first order never exceeds total),
* ST_i − S_i ≤ 1 − ΣS + tol (interactions of i fit in what main effects leave),
* S_i ≥ −tol (negative beyond noise means N is too small).

Two flags point at mistakes in the study itself: a model additive within its
intervals (ΣS ≈ 1, the interval narrower than the gap judged) whose ST ≠ S beyond
them — impossible for a correct design — and "every input total ≈ 1 with no main
effects", the signature of outputs not paired with their rows (or a pure-interaction
model). A third (`resolution_flags`) asks whether the output moves at all: indices of
an output that varies less across the design than its simulator resolves measure the
solver's error, and pass every check above.
"""

from __future__ import annotations

import numpy as np


def consistency_checks(S1, ST, S1_half=None, ST_half=None, names=None, tol=0.02) -> dict:
    """Run the safeguards on one set of indices.

    Parameters
    ----------
    S1, ST : array_like
        First-order and total indices, one per input [-].
    S1_half, ST_half : array_like, optional
        Their replicate half-widths [-]; zero when omitted.
    names : list of str, optional
        Input names for the messages; ``x1, x2, ...`` when omitted.
    tol : float
        Fixed part of every tolerance [-].

    Returns
    -------
    dict
        JSON-ready: ``ok``, ``tol``, ``sum_S1``, ``sum_ST``, ``interaction_share``,
        ``items`` (one ``{check, value, limit, ok}`` per check) and ``flags`` (text).
    """
    S1, ST = np.asarray(S1, float), np.asarray(ST, float)
    h1 = np.zeros_like(S1) if S1_half is None else np.asarray(S1_half, float)
    hT = np.zeros_like(ST) if ST_half is None else np.asarray(ST_half, float)
    names = list(names) if names is not None else [f"x{i + 1}" for i in range(len(S1))]
    sum1, sumT = float(S1.sum()), float(ST.sum())
    tol1, tolT = tol + float(np.sqrt(np.sum(h1**2))), tol + float(np.sqrt(np.sum(hT**2)))
    items = [_item("sum(S1) <= 1 + tol", sum1, 1 + tol1, sum1 <= 1 + tol1),
             _item("sum(ST) >= 1 - tol", sumT, 1 - tolT, sumT >= 1 - tolT)]
    for i, name in enumerate(names):
        pair = tol + float(np.hypot(h1[i], hT[i]))
        items.append(_item(f"S1[{name}] <= ST[{name}] + tol", float(S1[i]),
                           float(ST[i]) + pair, S1[i] <= ST[i] + pair))
        gap, room = float(ST[i] - S1[i]), 1 - sum1 + tol1 + pair - tol
        items.append(_item(f"ST[{name}] - S1[{name}] <= 1 - sum(S1) + tol", gap, room,
                           gap <= room))
        items.append(_item(f"S1[{name}] >= -tol", float(S1[i]), -(tol + h1[i]),
                           S1[i] >= -(tol + h1[i])))
    flags = []
    gaps = ST - S1
    beyond = gaps - additive_room(sum1, tol1, h1, hT)
    if sum1 >= 1 - tol1 and np.any(beyond > 0):
        worst = int(np.argmax(beyond))
        flags.append(f"model looks additive (sum S1 = {sum1:.3f}) but ST != S1 "
                     f"(ST - S1 = {gaps[worst]:.3f} for {names[worst]}): the design or the row "
                     "pairing is broken")
    if len(S1) >= 2 and abs(sum1) < 0.1 and np.all(ST > 0.8):
        flags.append(f"every input has total index near 1 and no main effect "
                     f"(sum S1 = {sum1:.3f}, sum ST = {sumT:.3f}): outputs not paired with "
                     "their rows, or a pure-interaction model")
    return {"ok": bool(all(it["ok"] for it in items) and not flags), "tol": tol,
            "sum_S1": sum1, "sum_ST": sumT, "interaction_share": 1 - sum1,
            "items": items, "flags": flags}


def additive_room(sum1: float, tol1: float, h1, hT) -> np.ndarray:
    """The largest ST_i - S1_i that a study whose ΣS1 is 1 within its interval may show
    without contradicting itself: the interactions ΣS1 leaves at the low end of its
    interval, ``max(0, 1 - ΣS1) + tol1``, plus the noise of the gap itself. ΣS1 near 1
    makes a model additive only when its interval is narrower than the gap judged; a
    noisy study of a model with interactions (Ishigami at N = 256: ΣS1 = 0.87 ± 0.26,
    ST - S1 = 0.28) is no evidence of a broken design."""
    return max(0.0, 1.0 - sum1) + tol1 + np.hypot(h1, hT)


#: a study that dropped more than this share of its blocks (rows that failed) is flagged
DROPPED_SHARE = 0.1


def dropped_flags(used: int, dropped: int) -> list[str]:
    """A flag when more than `DROPPED_SHARE` of the design's blocks were dropped: the indices
    then describe the part of the box whose rows ran (a corner the model refuses is left
    out), and pass every check above."""
    total = used + dropped
    if not total or dropped <= DROPPED_SHARE * total:
        return []
    return [f"{dropped} of {total} blocks were dropped (rows that failed, listed above): the indices describe "
            "the part of the ranges that ran, not the whole; narrow the ranges to what the model accepts"]


#: an output must vary across the design by this many times the simulator's resolution
RESOLVED_SPREAD = 10.0


def resolution_flags(y, resolution: float | None) -> list[str]:
    """A flag when the outputs ``y`` vary less than `RESOLVED_SPREAD` × ``resolution``.

    Parameters
    ----------
    y : array_like
        The study's outputs (NaN for failed rows).
    resolution : float or None
        The size of the simulator's own error on one output, in its unit (a model's
        ``resolution(y)``); None for a model that does not say.

    Returns
    -------
    list of str
        One sentence, or none.
    """
    y = np.asarray(y, dtype=float)
    y = y[np.isfinite(y)]
    if resolution is None or y.size < 2:
        return []
    spread = float(np.std(y))
    if spread >= RESOLVED_SPREAD * resolution:
        return []
    return [f"the output varies by {spread:.3g} (standard deviation) across the design, under "
            f"{RESOLVED_SPREAD:g}x the simulator's resolution ({resolution:.3g}): the indices measure the "
            "solver's error, not the parameters; widen the ranges or study another output"]


def _item(check, value, limit, ok) -> dict:
    return {"check": check, "value": float(value), "limit": float(limit), "ok": bool(ok)}


def failed_messages(checks: dict) -> list[str]:
    """One line per failed check or flag, for stderr.

    Parameters
    ----------
    checks : dict
        What `consistency_checks` returned.

    Returns
    -------
    list of str
        ``check failed: ...`` lines, then ``warning: ...`` lines.
    """
    lines = [f"check failed: {it['check']} (value {it['value']:.4g}, limit {it['limit']:.4g})"
             for it in checks["items"] if not it["ok"]]
    return lines + [f"warning: {flag}" for flag in checks["flags"]]
