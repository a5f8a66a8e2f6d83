"""Diagnosis of a running-torque test: which families the sweep needs beyond the Coulomb level.

The same loop as the twist tests (`hdsim.identification.diagnosis`): fit the base model
and the given families, try every other family of a running-torque test
(`hdsim.model.running_terms.RUNNING_FAMILIES`), rank them, add the best if it passes,
refit, repeat. The error is a torque (``rmse_Nm``); the noise floor
(``noise_floor_Nm``) is the record's own, measured without a model.

A candidate passes only if all of these hold:

1. **Information criterion:** its BIC, with the residual's effective sample count,
   improves by more than `BIC_MARGIN`, or its hold-out gain (2.) exceeds
   `STRONG_HOLDOUT_GAIN` on both halves: a model far from the record leaves a residual
   correlated over many rows, whose few effective samples make the BIC timid.
2. **Hold-out:** fitted on the first half of every plateau (and the ramps) it predicts
   the second half better than the model without it by `HOLDOUT_GAIN`, and the other
   way round. Each half holds every speed and direction, so the hold-out stays valid
   however unequal the dwell times are. When the model's rms is already within
   `EXPLAINED_RATIO` of the record's noise floor the bar is `HOLDOUT_GAIN_AT_FLOOR`:
   an effect under the noise must still predict unseen data clearly better.
3. **A real share of what is missing:** it removes at least `MIN_SHARE` of the residual
   variance above the noise floor. An effect that only patches the imperfect form of
   another family removes a few per cent; a missing family removes most of it.
4. **Not a proxy:** the families already in the model are allowed other shapes of their
   own (`hdsim.model.running_terms.RunningTerm.other_shapes`: a churning loss growing as
   √ω and ω², Stribeck curves of other shapes, higher ripple orders); on top of that
   widened model the candidate must still predict both held-out halves better by
   `PROXY_HOLDOUT_GAIN`. A Stribeck rise that only bends a
   viscous line into the power law of the drive's real churning is then not credited
   as friction.

Two candidates that pass and explain the residual within `AMBIGUOUS_SHARE` of each
other are reported as ``ambiguous``, with the measurement that would separate them.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from hdsim.errors import InputError
from hdsim.identification.residuals import EXPLAINED_RATIO, whiteness
from hdsim.identification.running_fit import RunningFit, SweepRecord, fit_running
from hdsim.io.measurement import Measurement
from hdsim.model.running_terms import RUNNING_FAMILIES, parse_running_effects

__all__ = ["RunningDiagnosis", "diagnose_running", "running_limits", "BIC_MARGIN", "MIN_SHARE"]

#: a family must lower the BIC by more than this
BIC_MARGIN = 10.0
#: … and remove at least this share of the residual variance above the noise floor
MIN_SHARE = 0.2
#: … and lower the held-out error on both halves by this share
HOLDOUT_GAIN = 0.02
#: … or by this share when the rms is already at the noise floor
HOLDOUT_GAIN_AT_FLOOR = 0.1
#: a held-out gain this large stands for the BIC when a record is so far from the model that its
#: residual is correlated over many rows (few effective samples make the BIC timid)
STRONG_HOLDOUT_GAIN = 0.1
#: … and still predict held-out halves this much better when the families in the model may take
#: other shapes of their own
PROXY_HOLDOUT_GAIN = 0.05
#: two passing candidates whose shares differ by less than this are ambiguous
AMBIGUOUS_SHARE = 0.05

#: what separates two families of a running-torque test
SEPARATING = {
    frozenset({"friction", "damping"}): "a sweep over at least three speeds a decade apart: viscous loss grows "
                                        "with speed, a Stribeck rise falls with it",
    frozenset({"friction", "ripple"}): "longer plateaus (several wave-generator revolutions each): a ripple "
                                       "averages out over a revolution, a friction level does not",
    frozenset({"damping", "ripple"}): "longer plateaus at several speeds: a ripple averages out over a "
                                      "revolution, a viscous loss grows with speed",
}


@dataclass
class RunningCandidate:
    """One family tried in one round."""

    family: str
    fit: RunningFit | None
    score: float = math.inf
    share: float = 0.0
    holdout_gain: list = field(default_factory=list)
    accepted: bool = False
    reason: str = ""

    def to_json(self) -> dict:
        effect = RUNNING_FAMILIES[self.family].id
        if self.fit is None:
            return {"family": self.family, "effect": effect, "rmse_Nm": None, "score": None,
                    "passes": False, "why": self.reason}
        return {"family": self.family, "effect": effect, "rmse_Nm": self.fit.rmse_Nm, "score": self.score,
                "n_eff": self.fit.n_eff, "share_explained": self.share, "holdout_gain": self.holdout_gain,
                "passes": self.accepted, "why": self.reason}


@dataclass
class RunningStep:
    """The model after a round and what was tried on it."""

    effects: list
    fit: RunningFit
    folds: list
    candidates: list = field(default_factory=list)
    added: str | None = None
    #: held-out RSS of this model with its families widened: the proxy test of every candidate of the
    #: round compares with it, so it is computed once (``False``: not yet)
    widened_folds: list | None | bool = False


@dataclass
class RunningDiagnosis:
    """Result of `diagnose_running`; `to_json` is the ``hdsim diagnose --json`` object."""

    record: SweepRecord
    steps: list
    added: list
    ambiguous: list
    seconds: float

    @property
    def measurement(self) -> Measurement:
        return self.record.measurement

    @property
    def baseline(self) -> RunningStep:
        return self.steps[0]

    @property
    def final(self) -> RunningStep:
        return self.steps[-1]

    @property
    def ranking(self) -> list:
        return sorted(self.steps[0].candidates, key=lambda c: c.score)

    @functools.cached_property
    def whiteness(self) -> dict:
        """Whiteness and noise-floor verdict of the final residual (read by ``success``, the verdict
        and the JSON; computed once)."""
        return _explained(self.final.fit)

    @property
    def success(self) -> bool:
        return bool(self.whiteness["explained"])

    def verdict(self) -> str:
        w = self.whiteness
        if w["explained"]:
            return f"explained: the residual is at the noise level (rms {w['rms_over_noise']:.2f}× the noise floor)"
        return (f"the residual keeps structure (rms {w['rms_over_noise']:.1f}× the noise floor): the sweep holds an "
                "effect that no running-torque family explains, or explains only in part")

    def table(self) -> list[dict]:
        return [{"step": i, "effects": list(s.effects), "added": None if i == 0 else self.steps[i - 1].added,
                 "rmse_Nm": s.fit.rmse_Nm} for i, s in enumerate(self.steps)]

    def to_json(self) -> dict:
        base, final = self.baseline.fit, self.final.fit
        summary = final.summary()
        return {
            "test": "running_torque",
            "baseline": {"effects": list(self.baseline.effects), "rmse_Nm": base.rmse_Nm},
            "ranking": [c.to_json() for c in self.ranking],
            "added": list(self.added),
            "final": {"effects": list(self.final.effects), "rmse_Nm": final.rmse_Nm,
                      "fitted": summary["fitted"], "uncertainty": summary["uncertainty"], "law": summary["law"]},
            "ambiguous": list(self.ambiguous),
            "metrics": summary["metrics"],
            "noise_floor_Nm": summary["noise_floor_Nm"],
            "rounds": [{"effects": list(s.effects), "rmse_Nm": s.fit.rmse_Nm,
                        "candidates": [c.to_json() for c in sorted(s.candidates, key=lambda c: c.score)],
                        "added": s.added} for s in self.steps],
            "table": self.table(),
            "holdout": "first and second half of every plateau",
            "whiteness": self.whiteness,
            "success": self.success,
            "verdict": self.verdict(),
            "seconds": round(self.seconds, 3),
        }


def _explained(fit: RunningFit) -> dict:
    """Whiteness of the residual, judged against the record's model-free noise floor."""
    r = fit.residual[fit.rows]
    w = whiteness(r)
    floor = abs(fit.record.side_factor) * fit.record.noise_floor
    # the rms about zero, not about the mean: a torque model has no offset, and a level that
    # differs between directions shows as a mean
    rms = fit.rmse_Nm
    ratio = rms / floor if floor > 0 else math.inf
    white = w["white"] and abs(float(np.mean(r))) < 3.0 * floor / math.sqrt(max(fit.n_eff, 1.0))
    return {"ljung_box_q": w["ljung_box_q"], "p_value": w["p_value"], "white": bool(white),
            "noise_floor_Nm": floor, "rmse_Nm": rms, "rms_over_noise": ratio,
            "explained": bool(white or ratio <= EXPLAINED_RATIO)}


def _halves(rec: SweepRecord) -> list[np.ndarray]:
    """Two folds: the first and the second half of every plateau; ramps train both, test neither."""
    first = np.zeros(rec.speed.size, dtype=bool)
    second = np.zeros_like(first)
    for s in rec.segments:
        mid = (s.start + s.stop) // 2
        first[s.start:mid] = True
        second[mid:s.stop] = True
    ramps = ~(first | second)
    return [first | ramps, second | ramps], [second, first]


def _holdout_rss(rec, families, folds, widened=()) -> list[float] | None:
    """Held-out RSS of each fold; None when a half is too short to fit."""
    train, test = folds
    out = []
    for fit_rows, test_rows in zip(train, test):
        try:
            fit = fit_running(rec, families, rows=fit_rows, widened=widened)
        except InputError:
            return None
        r = fit.residual[test_rows & rec.moving]
        out.append(float(r @ r))
    return out


def _gains(held, before) -> list[float]:
    """Relative fall of the held-out RSS per fold ([] when either could not be held out)."""
    if held is None or before is None:
        return []
    return [1.0 - h / b if b > 0 else 0.0 for h, b in zip(held, before)]


def _share(rec, before: RunningFit, after: RunningFit) -> float:
    """Share of the residual variance above the noise floor that ``after`` removes from ``before``."""
    missing = before.rss - (rec.noise_floor * abs(rec.side_factor)) ** 2 * before.n
    return min(max((before.rss - after.rss) / missing, 0.0), 1.0) if missing > 0 else 0.0


def _proxy_gains(rec, current: RunningStep, family: str, folds) -> list[float] | None:
    """Held-out gains of ``family`` over the model whose families may take their other shapes
    (None when the model has no family to widen)."""
    if not current.effects:
        return None
    if current.widened_folds is False:
        current.widened_folds = _holdout_rss(rec, current.effects, folds, widened=current.effects)
    widened = current.widened_folds
    both = _holdout_rss(rec, current.effects + [family], folds, widened=current.effects)
    return _gains(both, widened) or [0.0]


def _try(rec, current: RunningStep, family: str, folds, at_floor: bool) -> RunningCandidate:
    families = current.effects + [family]
    fit = fit_running(rec, families)
    base = current.fit
    n_eff = fit.n_eff
    score = fit.bic(n_eff) - base.bic(n_eff)
    share = _share(rec, base, fit)
    gains = _gains(_holdout_rss(rec, families, folds), current.folds)
    cand = RunningCandidate(family, fit, float(score), float(share), gains)
    bar = HOLDOUT_GAIN_AT_FLOOR if at_floor else HOLDOUT_GAIN
    if not gains:
        cand.reason = "the plateaus are too short to hold half of each out: nothing is added unvalidated"
    elif score >= -BIC_MARGIN and min(gains) < STRONG_HOLDOUT_GAIN:
        cand.reason = f"the BIC changes by {score:+.3g}; it must fall by more than {BIC_MARGIN:g}"
    elif min(gains) < bar:
        cand.reason = (f"it predicts held-out halves of the plateaus better by {100 * min(gains):.1f} %, less than "
                       f"{100 * bar:.0f} %" + (" (the rms is at the noise floor already)" if at_floor else ""))
    elif share < MIN_SHARE:
        cand.reason = (f"it removes {100 * share:.0f} % of the residual above the noise floor, less than "
                       f"{100 * MIN_SHARE:.0f} %: a patch for another family's form, not a missing family")
    else:
        proxy = _proxy_gains(rec, current, family, folds)
        if proxy is not None and min(proxy) < PROXY_HOLDOUT_GAIN:
            cand.reason = (f"a proxy: once {', '.join(current.effects)} may take other shapes of their own, it "
                           f"predicts held-out halves better by {100 * min(proxy):.1f} % only (less than "
                           f"{100 * PROXY_HOLDOUT_GAIN:.0f} %)")
        else:
            cand.accepted = True
            cand.reason = f"removes {100 * share:.0f} % of the residual above the noise floor"
    return cand


def diagnose_running(meas: Measurement | SweepRecord, effects=None, *, families=None,
                     max_rounds: int | None = None, log=None) -> RunningDiagnosis:
    """Find the running-torque families a sweep needs beyond ``effects``.

    Parameters
    ----------
    meas : Measurement or SweepRecord
        A ``running_torque`` record.
    effects : str or iterable, optional
        Families (or term ids) already in the model.
    families : iterable of str, optional
        Candidates to try (default every running-torque family not in ``effects``).
    max_rounds : int, optional
        Add at most this many families.
    log : callable, optional
        Receives one line per round.

    Returns
    -------
    RunningDiagnosis
        Every round, the families added and the ambiguous pairs.
    """
    start = time.perf_counter()
    rec = meas if isinstance(meas, SweepRecord) else SweepRecord.of(meas)
    chosen = parse_running_effects(effects)
    pool = parse_running_effects(families) if families is not None else list(RUNNING_FAMILIES)
    folds = _halves(rec)
    step = RunningStep(chosen, fit_running(rec, chosen), _holdout_rss(rec, chosen, folds))
    steps, added, ambiguous = [step], [], []
    rounds = len(pool) if max_rounds is None else max_rounds
    while True:
        at_floor = _explained(step.fit)["rms_over_noise"] <= EXPLAINED_RATIO
        for family in [f for f in pool if f not in step.effects]:
            try:
                step.candidates.append(_try(rec, step, family, folds, at_floor))
            except InputError as exc:  # a candidate that cannot be fitted is rejected, never the end
                step.candidates.append(RunningCandidate(family, None, reason=f"could not be fitted: {exc}"))
        passing = sorted((c for c in step.candidates if c.accepted), key=lambda c: c.score)
        if log:
            log(f"{', '.join(step.effects) or 'base'}: rms {step.fit.rmse_Nm:.3g} N·m; "
                + "; ".join(f"{c.family} {c.score:.3g}" for c in sorted(step.candidates, key=lambda c: c.score)))
        if not passing or len(added) >= rounds:
            break
        best = passing[0]
        for other in passing[1:]:
            if abs(other.share - best.share) < AMBIGUOUS_SHARE:
                pair = frozenset({best.family, other.family})
                entry = {"families": sorted(pair), "measurement": SEPARATING.get(pair, "")}
                if entry not in ambiguous:  # the same pair may come up again in a later round
                    ambiguous.append(entry)
        step.added = best.family
        added.append(best.family)
        effects = step.effects + [best.family]
        step = RunningStep(effects, best.fit, _holdout_rss(rec, effects, folds))
        steps.append(step)
    return RunningDiagnosis(rec, steps, added, ambiguous, time.perf_counter() - start)


def running_limits(diagnosis_json: dict, data: dict, ranking: list) -> list[str]:
    """What kept a sweep from deciding, each as the measurement that would (for `outcome.assess`)."""
    out = []
    speeds = data.get("speeds_rpm", [])
    if len(speeds) < 2:
        out.append("a sweep at three or more speeds, a decade apart: with one speed a loss that grows with speed "
                   "cannot be told from a constant friction level")
    if data.get("reversals", 0) < 1:
        out.append("the same sweep in the other direction: a level that differs between directions needs both")
    out += [pair["measurement"] for pair in diagnosis_json.get("ambiguous", []) if pair.get("measurement")]
    return out
