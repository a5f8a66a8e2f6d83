"""Which effect is missing: greedy forward selection over the effect families.

Procedure
---------
1. Fit the baseline (the base model plus the families the user names) to all rows, and
   to each of two *hold-out folds*: distinct experiments in the record (the loading-rate
   blocks when the torque has more than one rate, else the first and second half of the
   loading legs; for a kinematic-error test, alternate blocks of ten wave-generator
   revolutions, so that each fold holds both load directions). A fold fit minimises the residual on its own rows only; the other
   fold's rows are its hold-out.
2. For every family not yet in the model, add its effect (the family's default effect, or the one named in ``candidates``)
   and refit all rows and both folds, each from the baseline's values and afresh (the
   lower optimum counts). All the fits of a round run in lockstep in one batched pass per
   iteration (`hdsim.identification.fit.fit_many`): a pass costs about the same whatever
   it holds, so a round costs about as many passes as its slowest fit.
3. Score each candidate by the change of an information criterion, BIC computed with an
   *effective* sample size::

       score = ΔBIC = n_eff · ln(RSS_candidate / RSS_baseline) + Δk · ln(n_eff),
       n_eff = n (1 − ρ₁)/(1 + ρ₁)

   with ``ρ₁`` the lag-one autocorrelation of the candidate's residual. A model that
   leaves a smooth, structured residual has far fewer independent samples than rows; an
   ordinary BIC would then reward any extra flexibility that soaks up some of the
   structure. Lower is better; the ranking is by score.
4. Accept the best candidate only if **all** of: ``score < −10`` (Kass–Raftery "very
   strong" evidence), or a hold-out gain of at least 10 % on both folds (a residual so
   correlated that n_eff makes the score timid); its hold-out prediction error, the two folds pooled, is at least
   5 % below the baseline's; and the fit on all rows lowers the rms error by at least
   5 %. (Pooled, not fold by fold: when the folds are the two loading rates, a fit on
   the slow rate alone cannot tell damping from friction, so its prediction of the fast
   rate is poor for baseline and candidate alike and the gain there says nothing about
   the candidate; judged fold by fold, the battery misses a third of its true findings.) Then it
   becomes the baseline and the next round starts; the procedure stops when nothing
   passes, or when the residual is explained (white, or at the noise floor).
5. *Ambiguity*: when the runner-up also passes and its score is within
   ``max(10, 10 %)`` of the best, the pair is reported with the measurement that would
   separate them (`SEPARATING`); the better one is still added. At one loading rate,
   damping and friction are not told apart by a guess: when one is best and the other
   is in the model, or explains the residual within max(20, 25 %) of it, neither is
   added and the pair is reported (`hdsim.identification.selection.rate_ambiguity`).
6. *How sure*: block-bootstrap inclusion probabilities and a ``loo_compare``-style table
   per round (`hdsim.identification.confidence`).

Whiteness of the final residual (`hdsim.identification.residuals.whiteness`) decides the verdict:
a residual that is neither white nor at the noise floor means the model still misses
something (a form the library lacks, or an effect outside it) and no success is claimed.

The acceptance rule is tuned on the battery ``validation/diagnosis_battery.py`` (truth
data from ``tests/truth.py``, forms unlike the library's; the slow tests of
``tests/test_diagnosis.py`` run a part of it) and checked on held-out seeds of the truth
zoo (``validation/zoo_battery.py``): its rates are in the tutorial
``docs/tutorial-find-missing-effect.md``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from hdsim.errors import InputError, SolverError
from hdsim.identification.fit import (Evaluator, FitResult, build_model, fit_many, make_problem,
                                      parse_effects, result_of)
from hdsim.identification.problem import other_starts
from hdsim.model import effects as fx
from hdsim.io.measurement import Measurement
from hdsim.model.drive import SLOTS
from hdsim.identification.confidence import diagnosis_confidence
from hdsim.identification.folds import folds, one_loading_rate
from hdsim.identification.selection import (HOLDOUT_GAIN, MIN_GAIN, SCORE_THRESHOLD, SEPARATING, TIE_FRACTION,
                                            Candidate, rate_ambiguity, score_candidate, separating)
from hdsim.identification.residuals import findings, whiteness

__all__ = ["Diagnosis", "diagnose", "folds", "SEPARATING", "SCORE_THRESHOLD",
           "HOLDOUT_GAIN", "MIN_GAIN"]

#: iterations of every fit of a diagnosis at most. A round's lockstep takes as many passes
#: as its slowest fit; past 15 the slow ones are fits crawling towards a proxy's optimum,
#: and stopping them early errs towards not adding (the score only falls with iterations).
#: On the 20,000-row bench: 43 passes instead of 55, the same decisions
MAX_ITERATIONS = 15

#: families a test can show (the stiffness test locks the wave generator: no kinematic error)
FAMILIES_BY_TEST = {
    "stiffness": ("hardening", "backlash", "friction", "damping"),
    "kinematic_error": ("kinematic_error", "hardening", "backlash", "friction", "damping"),
    "running_torque": ("friction", "damping", "ripple"),
}


# --------------------------------------------------------------------------- results


@dataclass
class Step:
    """The model after a round: its fit, and what was tried to improve on it."""

    effects: list
    fit: FitResult
    fold_fits: list
    candidates: list = field(default_factory=list)
    added: str | None = None


@dataclass
class Diagnosis:
    """Result of `diagnose`; `to_json` gives the object ``hdsim diagnose --json`` prints (docs/cli.md)."""

    measurement: Measurement
    steps: list
    added: list
    ambiguous: list
    fold_rule: str
    whiteness: dict
    findings_before: list
    findings_after: list
    seconds: float
    passes: int
    confidence: dict = field(default_factory=dict)

    @property
    def baseline(self) -> Step:
        return self.steps[0]

    @property
    def final(self) -> Step:
        return self.steps[-1]

    @property
    def ranking(self) -> list:
        return sorted(self.steps[0].candidates, key=lambda c: c.score)

    @property
    def success(self) -> bool:
        """True only when the final residual is explained (white or at the noise floor)."""
        return bool(self.whiteness["explained"])

    def table(self) -> list[dict]:
        """Before/after table: one row per step (effects, rms, max error, score)."""
        rows = []
        for i, step in enumerate(self.steps):
            cand = None
            if i > 0:
                prev = self.steps[i - 1]
                cand = next(c for c in prev.candidates if c.family == prev.added)
            rows.append({"step": i, "effects": list(step.effects),
                         "added": None if i == 0 else self.steps[i - 1].added,
                         "rmse_rad": step.fit.rmse_rad, "max_abs_error_rad": step.fit.max_abs_rad,
                         "score": None if cand is None else cand.score,
                         "holdout_rmse_rad": [float(f.rmse(~f.rows)) for f in step.fold_fits]})
        return rows

    def verdict(self) -> str:
        w = self.whiteness
        if w["explained"]:
            return (f"explained: the residual is at the noise level "
                    f"(rms {w['rms_over_noise']:.2f}× the noise floor)")
        return (f"residual not white (Ljung-Box p = {w['p_value']:.2g}, rms "
                f"{w['rms_over_noise']:.1f}× the noise floor): the model still misses an effect "
                f"that no family in the library explains, or explains only in part; "
                f"this is not a success")

    def to_json(self) -> dict:
        base, final = self.baseline, self.final
        return {
            "test": self.measurement.test,
            "baseline": {"effects": list(base.effects), "rmse_rad": base.fit.rmse_rad,
                         "max_abs_error_rad": base.fit.max_abs_rad},
            "ranking": [c.to_json() for c in self.ranking],
            "added": list(self.added),
            "final": {"effects": list(final.effects), "rmse_rad": final.fit.rmse_rad,
                      "max_abs_error_rad": final.fit.max_abs_rad,
                      "effect_ids": dict(final.fit.effects),
                      "params": {k: float(v) for k, v in final.fit.params.items()},
                      "uncertainty": {k: float(v) for k, v in final.fit.uncertainty.items()},
                      "offset_rad": final.fit.offset},
            "ambiguous": list(self.ambiguous),
            "rounds": [{"effects": list(s.effects), "rmse_rad": s.fit.rmse_rad,
                        "candidates": [c.to_json() for c in sorted(s.candidates, key=lambda c: c.score)],
                        "added": s.added} for s in self.steps],
            "table": self.table(),
            "holdout": self.fold_rule,
            "whiteness": dict(self.whiteness),
            "success": self.success,
            "verdict": self.verdict(),
            "findings": {"baseline": self.findings_before, "final": self.findings_after},
            "confidence": self.confidence,
            "seconds": round(self.seconds, 3),
            "passes": self.passes,
        }


# --------------------------------------------------------------------------- procedure


def _slots(model, meas, ev, masks, all_starts: list, fold_starts: list, label: str) -> list[list]:
    """The fits of one model: all rows and each fold, one problem per start (the effects'
    `other_starts` added to every slot); the lowest cost of a slot counts (`_best`)."""
    alts = other_starts(model, meas)
    slots = [[make_problem(model, meas, ev, start=s, label=f"{label}:all") for s in all_starts + alts]]
    for i, mask in enumerate(masks):
        slots.append([make_problem(model, meas, ev, rows=mask, start=s, label=f"{label}:fold{i}")
                      for s in fold_starts[i] + alts])
    for slot in slots:
        for p in slot:
            p.max_iter = MAX_ITERATIONS
    return slots


def _best(slot: list):
    return min(slot, key=lambda p: p.cost)


def _results(ev, probs, unit):
    return [result_of(ev, p, unit=unit) for p in probs]


def diagnose(meas: Measurement, effects=None, *, unit=None, families=None, candidates: dict | None = None,
             max_rounds: int | None = None, max_steps: int | None = None, log=None) -> Diagnosis:
    """Find the effect families a measurement needs beyond ``effects``.

    Parameters
    ----------
    meas : Measurement
        A stiffness, kinematic-error or running-torque test.
    effects : str, list or dict, optional
        The baseline's families or effect ids (see `hdsim.identification.fit.parse_effects`).
    unit : str or HarmonicDrive, optional
        Built-in unit (default: the catalog default).
    families : iterable of str, optional
        Families to try (default: all the test can show).
    candidates : dict, optional
        ``{family: effect id}``: the effect that stands for a family when it is tried
        (default: the family's default effect, `hdsim.model.effects.default_effect`).
    max_rounds : int, optional
        Stop after this many additions.
    max_steps : int, optional
        Quasi-static steps at most per evaluation; default
        `hdsim.identification.problem.STEP_BUDGET`.
    log : callable, optional
        Progress messages (e.g. ``print`` to stderr).

    Returns
    -------
    Diagnosis or hdsim.identification.running_diagnosis.RunningDiagnosis
        Every step with its fit and the candidates tried, what was added, the
        ambiguities, the whiteness of the final residual and the findings (the latter
        for a running-torque test, which has its own law and families).
    """
    if meas.test == "running_torque":
        from hdsim.identification.running_diagnosis import diagnose_running

        return diagnose_running(meas, effects, families=families, max_rounds=max_rounds, log=log)
    t0 = time.perf_counter()
    chosen = effects if isinstance(effects, dict) else parse_effects(effects)
    stand_in = {f: fx.default_effect(f) for f in SLOTS}
    for family, effect_id in (candidates or {}).items():
        fx.effect_class(family, effect_id)
        stand_in[family] = effect_id
    pool = list(families) if families is not None else list(FAMILIES_BY_TEST[meas.test])
    for f in pool:
        if f not in FAMILIES_BY_TEST[meas.test]:
            raise InputError(f"a {meas.test} test cannot show the {f} family")
    ev = Evaluator(meas, max_steps=max_steps)
    masks, rule = folds(meas)
    one_rate = meas.test == "stiffness" and one_loading_rate(meas)
    passes = 0
    say = log or (lambda *_: None)

    model = build_model(unit, chosen, meas)
    unit_name = model.name
    slots = _slots(model, meas, ev, masks, [None], [[None], [None]], "baseline")
    passes += fit_many(ev, [p for slot in slots for p in slot])
    fits = _results(ev, [_best(slot) for slot in slots], unit_name)
    current = dict(chosen)
    step = Step(effects=[f for f in SLOTS if f in current], fit=fits[0], fold_fits=fits[1:])
    steps = [step]
    added, ambiguous = [], []
    findings_before = findings(meas, step.fit.residual)
    say(f"baseline {step.effects}: rms {step.fit.rmse_rad:.3g} rad")
    rounds = 0
    while True:
        todo = [f for f in pool if f not in current]
        if not todo or (max_rounds is not None and rounds >= max_rounds):
            break
        if whiteness(step.fit.residual)["white"]:
            break
        # one lockstep for the round: every candidate on all rows and on each hold-out
        # fold, each from the baseline's values and afresh. A pass costs about the same
        # whatever it holds (the evaluator's cost is its loop over the samples), so the
        # fold fits ride along instead of waiting for the all-rows optimum
        cands = []
        failed = []  # candidates that could not be built: rejected with the reason, never fatal
        for family in todo:
            trial = dict(current)
            trial[family] = stand_in[family]
            try:
                cmodel = build_model(unit, trial, meas)
                slots = _slots(cmodel, meas, ev, masks, [dict(step.fit.internal), None],
                               [[dict(f.internal), None] for f in step.fold_fits], family)
            except (InputError, SolverError) as exc:
                failed.append(Candidate.failed(family, stand_in[family], str(exc)))
                continue
            cands.append((family, slots))
        groups = [slot for _, slots in cands for slot in slots]
        passes += fit_many(ev, [p for slot in groups for p in slot])
        scored = list(failed)
        for family, slots in cands:
            probs = [_best(slot) for slot in slots]
            try:
                res = _results(ev, probs, unit_name)
            except (InputError, SolverError) as exc:
                scored.append(Candidate.failed(family, stand_in[family], str(exc)))
                continue
            scored.append(score_candidate(family, stand_in[family], res, step))
        step.candidates = scored
        ranked = sorted(scored, key=lambda c: c.score)
        say("round %d: " % (rounds + 1) + ", ".join(f"{c.family} {c.score:.1f}" for c in ranked))
        best = ranked[0]
        if not best.accepted:
            break
        pair = rate_ambiguity(best, scored, current) if one_rate else None
        if pair is not None:
            # one loading rate cannot say whether this loss grows with the rate: report
            # the pair and the measurement that separates it, add neither
            by_family = {c.family: c.score for c in scored}
            ambiguous.append({"families": pair, "scores": [by_family.get(f) for f in pair],
                              "round": rounds + 1, "measurement": separating(*pair), "added": False})
            break
        if len(ranked) > 1:
            second = ranked[1]
            tie = max(10.0, TIE_FRACTION * abs(best.score))
            if second.accepted and second.score - best.score < tie:
                ambiguous.append({"families": [best.family, second.family],
                                  "scores": [best.score, second.score],
                                  "round": rounds + 1,
                                  "measurement": separating(best.family, second.family), "added": True})
        step.added = best.family
        added.append(best.family)
        current[best.family] = best.effect
        step = Step(effects=[f for f in SLOTS if f in current], fit=best.fit, fold_fits=best.fold_fits)
        steps.append(step)
        rounds += 1
        if whiteness(step.fit.residual)["explained"]:
            break
    w = whiteness(step.fit.residual)
    return Diagnosis(measurement=meas, steps=steps, added=added, ambiguous=ambiguous, fold_rule=rule,
                     whiteness=w, findings_before=findings_before,
                     findings_after=findings(meas, step.fit.residual),
                     seconds=time.perf_counter() - t0, passes=passes,
                     confidence=diagnosis_confidence(meas, steps, masks, one_rate))


