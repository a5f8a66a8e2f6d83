"""Which effect is missing: greedy forward selection over the effect families.

Procedure
---------
1. Fit the baseline (the base model plus the families the user names) to all rows, and
   to each of two *hold-out folds* (`hdsim.identification.folds`: whole torque cycles
   alternated within each loading rate; for a kinematic-error test, alternate blocks of
   ten wave-generator revolutions, so that each fold holds both load directions). A fold
   fit minimises the residual on its own rows only; the other fold's rows are its hold-out.
2. For every family not yet in the model, add its effect (the family's default effect,
   or the one named in ``candidates``, and its `Effect.entry_forms`: friction enters both
   beside the spring, Dahl, and in series with it, distributed micro-slip, the best
   passing form standing for the family) and refit all rows and both folds, each from
   the baseline's values and afresh (the lower optimum counts). All the fits of a round
   run in lockstep in one batched pass per iteration (`hdsim.identification.fit.fit_many`):
   a pass costs about the same whatever it holds, so a round costs about as many passes
   as its slowest fit.
3. Score each candidate by the change of an information criterion, BIC computed with an
   *effective* sample size::

       score = ΔBIC = n_eff · ln(RSS_candidate / RSS_baseline) + Δk · ln(n_eff),
       n_eff = n (1 − ρ₁)/(1 + ρ₁)

   with ``ρ₁`` the lag-one autocorrelation of the candidate's residual. A model that
   leaves a smooth, structured residual has far fewer independent samples than rows; an
   ordinary BIC would then reward any extra flexibility that soaks up some of the
   structure. Lower is better; the ranking is by score.
4. Add the best-scoring candidate among those that pass **all** of: ``score < −10`` (Kass–Raftery "very
   strong" evidence), or a hold-out gain of at least 10 % on both folds (a residual so
   correlated that n_eff makes the score timid); its hold-out prediction error, the two folds pooled, is at least
   5 % below the baseline's; and the fit on all rows lowers the rms error by at least
   5 %. (Pooled, not fold by fold: when the folds are the two loading rates, a fit on
   the slow rate alone cannot tell damping from friction, so its prediction of the fast
   rate is poor for baseline and candidate alike and the gain there says nothing about
   the candidate; judged fold by fold, the battery misses a third of its true findings.) Then it
   becomes the baseline and the next round starts; the procedure stops when nothing
   passes, or when the residual is explained (white, or at the noise floor).
5. *Other forms* (the proxy guard): before the best candidate is added, every family
   already in the model is refitted in its other forms (`Effect.other_forms`: the smooth
   hardening and the catalog's three segments, Dahl friction, Maxwell-slip elements and
   distributed micro-slip, a dead zone with fixed and with fitted rounding), in one more
   lockstep, scored the same way. An imperfect shape leaves a structured residual that another family
   absorbs in part (damping after a gap that closes gradually); when another form
   passes and scores better than the candidate by more than the tie margin, the family
   changes form instead and the next round starts from there (each family once). Within
   the tie margin the candidate is added and the pair reported as ambiguous. When no
   candidate passes against the user's baseline and its residual is not explained, the
   baseline's families are tried in their other forms too, and the best form that
   passes is taken (the user names families, not forms). The ranking reported is that
   of the first round not settled by a change of form (`Diagnosis.ranking_round`).
6. *Ambiguity*: when the runner-up also passes and its score is within
   ``max(10, 10 %)`` of the best, the pair is reported with the measurement that would
   separate them (`SEPARATING`); the better one is still added. At one loading rate,
   damping and friction are not told apart by a guess: when one is best and the other
   is in the model, or explains the residual within max(20, 25 %) of it, neither is
   added and the pair is reported (`hdsim.identification.selection.rate_ambiguity`). The
   pair is reported too when nothing passes but one of it, beside its partner, explains
   part of what is left (`hdsim.identification.selection.rate_question_left`).
7. *How sure*: block-bootstrap inclusion probabilities and a ``loo_compare``-style table
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
from hdsim.identification.selection import (HOLDOUT_GAIN, MIN_GAIN, SCORE_THRESHOLD, SEPARATING, Candidate,
                                            near_tie, rate_ambiguity, rate_question_left,
                                            score_candidate, separating)
from hdsim.identification.residuals import findings, whiteness

__all__ = ["Diagnosis", "diagnose", "folds", "SEPARATING", "SCORE_THRESHOLD",
           "HOLDOUT_GAIN", "MIN_GAIN"]

#: iterations of every fit of a diagnosis at most. A round's lockstep takes as many passes
#: as its slowest fit, and stopping the slow ones early errs towards not adding (the score
#: only falls with iterations). 15 was the cap while a pass cost 0.3-0.9 s. The compiled
#: evaluator made passes cheap, and at 15 a fold fit can stop far from its optimum and
#: sink a candidate's hold-out gain: in the battery, a hidden backlash at 4.4 % against
#: 5 %, passing at 20 % with 25 iterations (validation/README.md §4)
MAX_ITERATIONS = 25

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
    #: the families of the model tried in their other forms (the proxy guard)
    reshapes: list = field(default_factory=list)
    #: ``{"family", "from", "to", "score", "instead_of", "round"}`` when a form changed instead
    reshaped: dict | None = None
    #: the family of a damping/friction pair one loading rate cannot separate, put in the
    #: model (not added) so that the other families are tried against a model with the loss
    provisional: str | None = None


@dataclass
class Diagnosis:
    """Result of `diagnose`; `to_json` gives the object ``hdsim diagnose --json`` prints (docs/cli.md)."""

    measurement: Measurement
    steps: list
    added: list
    ambiguous: list
    reshaped: list
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
    def ranking_round(self) -> int:
        """The round (1-based) whose candidates are `ranking`: the first round settled by an
        addition, a one-rate stand-in or a stop, not by a change of form.

        A round settled by a change of form (the proxy guard) found that the residual was
        the shape of a family already in the model (friction named by the user, fitted as
        Dahl where the record holds series micro-slip): its candidates were scored against
        a baseline the diagnosis then replaced, and their order says which family imitates
        that shape best, not which is missing. The ranking a reader acts on is the first
        one scored against the baseline in the forms the diagnosis kept; the superseded
        rounds stay in ``rounds`` and ``reshaped``.
        """
        for k, step in enumerate(self.steps):
            if step.candidates and step.reshaped is None:
                return k + 1
        return 1

    @property
    def ranking(self) -> list:
        """The candidates of `ranking_round`, best score first."""
        return sorted(self.steps[self.ranking_round - 1].candidates, key=lambda c: c.score)

    @property
    def success(self) -> bool:
        """True only when the final residual is explained (white or at the noise floor)."""
        return bool(self.whiteness["explained"])

    def table(self) -> list[dict]:
        """Before/after table: one row per step (effects, rms, max error, score)."""
        rows = []
        for i, step in enumerate(self.steps):
            cand = prev = None
            if i > 0:
                prev = self.steps[i - 1]
                if prev.reshaped is not None:
                    cand = next(c for c in prev.reshapes if c.family == prev.reshaped["family"]
                                and c.effect == prev.reshaped["to"])
                else:
                    cand = next(c for c in prev.candidates if c.family in (prev.added, prev.provisional))
            rows.append({"step": i, "effects": list(step.effects),
                         "added": None if prev is None else prev.added,
                         "provisional": None if prev is None else prev.provisional,
                         "other_form": None if prev is None or prev.reshaped is None
                         else {prev.reshaped["family"]: prev.reshaped["to"]},
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
            "ranking_round": self.ranking_round,
            "added": list(self.added),
            "final": {"effects": list(final.effects), "rmse_rad": final.fit.rmse_rad,
                      "max_abs_error_rad": final.fit.max_abs_rad,
                      "effect_ids": dict(final.fit.effects),
                      "params": {k: float(v) for k, v in final.fit.params.items()},
                      "uncertainty": {k: float(v) for k, v in final.fit.uncertainty.items()},
                      "offset_rad": final.fit.offset},
            "ambiguous": list(self.ambiguous),
            "reshaped": list(self.reshaped),
            "rounds": [{"effects": list(s.effects), "rmse_rad": s.fit.rmse_rad,
                        "candidates": [c.to_json() for c in sorted(s.candidates, key=lambda c: c.score)],
                        "other_forms": [c.to_json() for c in sorted(s.reshapes, key=lambda c: c.score)],
                        "added": s.added, "reshaped": s.reshaped, "provisional": s.provisional}
                       for s in self.steps],
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
    reshaped = []  # families whose form was changed instead of adding another family
    undecidable = set()  # the damping/friction pair once one loading rate could not separate it
    while True:
        round_no = len(steps)
        todo = [f for f in pool if f not in current and f not in undecidable]
        if not todo or (max_rounds is not None and len(added) >= max_rounds):
            break
        residual_test = whiteness(step.fit.residual)  # once a round: the stop and the guard read it
        if residual_test["white"]:
            break
        # one lockstep for the round: every candidate on all rows and on each hold-out
        # fold, each from the baseline's values and afresh. A pass costs about the same
        # whatever it holds (the evaluator's cost is its loop over the samples), so the
        # fold fits ride along instead of waiting for the all-rows optimum
        trials = [(family, form, {**current, family: form}) for family in todo
                  for form in _entry_forms(family, stand_in[family])]
        scored, n = _lockstep(trials, unit, meas, ev, masks, step, unit_name)
        scored = _best_form_per_family(scored)
        passes += n
        step.candidates = scored
        ranked = sorted(scored, key=lambda c: c.score)
        say(f"round {round_no}: " + ", ".join(f"{c.family} {c.score:.1f}" for c in ranked))
        # the best score among the candidates that pass: a better score whose hold-out
        # predictions fail is an over-fit, and it should not hide a runner-up that passes
        # (the block bootstrap of `diagnosis_confidence` applies the rule the same way)
        passing = [c for c in ranked if c.accepted]
        best = passing[0] if passing else None  # None: nothing to add, unless a form changes
        # the proxy guard: the families already in the model in their other forms. When
        # one explains the residual clearly better than the best candidate, the residual
        # is that family's shape, not a missing family (`Effect.other_forms`). When no
        # candidate passes against the user's baseline and its residual is not explained,
        # the form of a family the user named may be what hides the missing one (Preisach
        # friction fitted as Dahl leaves a residual against which a hard gap lowers the
        # error by 3 %): a form that passes is taken and the candidates are tried again
        # against it. Only while nothing has been added and no form changed (the user's
        # baseline, with a one-rate loss standing in if there is one): the user names
        # families, not forms, and every later round's families have had their forms
        # tried in the round that added one (in every round that stops, it would cost the
        # 20,000-row bench 5 s more)
        forms = _other_forms(current, {r["family"] for r in reshaped})
        on_baseline = not added and not reshaped and not residual_test["explained"]
        if forms and (best is not None or on_baseline):
            step.reshapes, n = _lockstep(forms, unit, meas, ev, masks, step, unit_name)
            passes += n
            say(f"round {round_no}, other forms: " + ", ".join(f"{c.family}={c.effect} {c.score:.1f}"
                                                                for c in step.reshapes))
            ordered = sorted(step.reshapes, key=lambda c: c.score)
            if best is None:  # nothing to add: the best form that passes is taken, if any
                form = next((c for c in ordered if c.accepted), None)
                changes = form is not None
            elif ordered[0].accepted and near_tie(best.score, ordered[0].score):
                # too close to call: the family is added (a new effect is the more useful
                # lead for the bench), the other form named with the separating measurement
                form, changes = ordered[0], False
                ambiguous.append(_tie_entry(best, form, round_no, other_form={form.family: form.effect}))
            else:
                form = ordered[0]
                changes = form.accepted and form.score < best.score
            if changes:
                step.reshaped = {"family": form.family, "from": current[form.family], "to": form.effect,
                                 "score": form.score, "instead_of": best.family if best else None,
                                 "round": round_no}
                reshaped.append(step.reshaped)
                step = _advance(steps, current, form)
                continue
        if best is None:
            # a loss that explains part of what is left, beside its partner, but too little
            # to be added: at one rate that is the pair's question, not "nothing more"
            pair = rate_question_left(ranked, current) if one_rate else None
            if pair is not None:
                ambiguous.append(_pair_entry(pair, scored, round_no))
            break
        pair = rate_ambiguity(best, scored, current) if one_rate else None
        if pair is not None:
            # one loading rate cannot say whether this loss grows with the rate: report
            # the pair and the measurement that separates it, add neither
            ambiguous.append(_pair_entry(pair, scored, round_no))
            if set(pair) & set(current):
                break  # the question is whether the loss in the model grows with the rate
            # a loss is missing and only its rate law is undecidable: it stands in the model,
            # not added, while the families that do not hinge on the rate are tried (a gap
            # behind a one-rate friction is invisible until the loss is in: score +0.5)
            step.provisional = best.family
            undecidable |= set(pair)
            step = _advance(steps, current, best)
            continue
        if len(passing) > 1 and near_tie(best.score, passing[1].score):
            ambiguous.append(_tie_entry(best, passing[1], round_no))
        step.added = best.family
        added.append(best.family)
        step = _advance(steps, current, best)
        # the next round runs unless the residual is white, as after the baseline: a
        # residual near the noise floor may still hold a second family's structure (a
        # smooth gap beside a hardening leaves 1.2x the noise), and the candidates'
        # own tests (score, hold-out gain) keep noise-level structure from being added
    held = next((k for k, s in enumerate(steps) if s.provisional is not None), None)
    if held is not None and not any(s.added for s in steps[held:]):
        # nothing was added once the loss stood in: the record said no more than the pair,
        # and the model stays the one before it (a form changed against the stand-in goes too)
        del steps[held + 1:]
        steps[held].provisional = None
        reshaped = [r for r in reshaped if r["round"] <= held]
        ambiguous = [a for a in ambiguous if a["round"] <= held + 1]
        step = steps[held]
    elif held is not None:  # the stand-in stays: its pair's entry names it
        pair_entry = next(a for a in ambiguous if a["round"] == held + 1 and a["added"] is False)
        pair_entry["provisional"] = steps[held].provisional
    w = whiteness(step.fit.residual)
    return Diagnosis(measurement=meas, steps=steps, added=added, ambiguous=ambiguous, reshaped=reshaped,
                     fold_rule=rule,
                     whiteness=w, findings_before=findings_before,
                     findings_after=findings(meas, step.fit.residual),
                     seconds=time.perf_counter() - t0, passes=passes,
                     confidence=diagnosis_confidence(meas, steps, masks, one_rate))


def _lockstep(trials: list, unit, meas, ev, masks, step: Step, unit_name: str) -> tuple[list, int]:
    """Fit every trial ``(family, effect id, {family: effect id})`` on all rows and on each
    fold in one lockstep and score it against ``step``; returns the candidates and the passes.

    A trial that cannot be built or fitted is a candidate rejected with the reason, never fatal.
    """
    built, scored = [], []
    for family, effect_id, structure in trials:
        try:
            model = build_model(unit, structure, meas)
            slots = _slots(model, meas, ev, masks, [dict(step.fit.internal), None],
                           [[dict(f.internal), None] for f in step.fold_fits], family)
        except (InputError, SolverError) as exc:
            scored.append(Candidate.failed(family, effect_id, str(exc)))
            continue
        built.append((family, effect_id, slots))
    passes = fit_many(ev, [p for _, _, slots in built for slot in slots for p in slot]) if built else 0
    for family, effect_id, slots in built:
        try:
            res = _results(ev, [_best(slot) for slot in slots], unit_name)
        except (InputError, SolverError) as exc:
            scored.append(Candidate.failed(family, effect_id, str(exc)))
            continue
        scored.append(score_candidate(family, effect_id, res, step))
    return scored, passes


def _entry_forms(family: str, effect_id: str) -> tuple:
    """The forms a family is tried in when it enters: its stand-in and the stand-in's
    `Effect.entry_forms`."""
    return (effect_id,) + tuple(fx.effect_class(family, effect_id).entry_forms)


def _best_form_per_family(scored: list) -> list:
    """One candidate per family: the best-scoring form among those that pass, else the
    best-scoring form (the rule that picks the round's addition, applied within a family)."""
    best = {}
    for c in scored:
        held = best.get(c.family)
        if held is None or (c.accepted, -c.score) > (held.accepted, -held.score):
            best[c.family] = c
    return list(best.values())


def _other_forms(current: dict, done: set) -> list:
    """Trials of the model with one family in another form (`Effect.other_forms`); a family
    changes form once at most (``done``), so the procedure cannot swing between two forms."""
    trials = []
    for family, effect_id in current.items():
        if family in done:
            continue
        for other in fx.effect_class(family, effect_id).other_forms:
            trials.append((family, other, {**current, family: other}))
    return trials


def _advance(steps: list, current: dict, chosen: Candidate) -> Step:
    """Make ``chosen``'s model the current one: its family and effect enter ``current``,
    its fits a new step."""
    current[chosen.family] = chosen.effect
    step = Step(effects=[f for f in SLOTS if f in current], fit=chosen.fit, fold_fits=chosen.fold_fits)
    steps.append(step)
    return step


def _tie_entry(best: Candidate, rival: Candidate, round_no: int, **extra) -> dict:
    """The ``ambiguous`` entry of a near-tie in which ``best`` is added."""
    return {"families": [best.family, rival.family], "scores": [best.score, rival.score], "round": round_no,
            "measurement": separating(best.family, rival.family), "added": True, **extra}


def _pair_entry(pair: list, scored: list, round_no: int) -> dict:
    """The ambiguous entry of the damping/friction pair one loading rate cannot separate."""
    by_family = {c.family: c.score for c in scored}
    return {"families": pair, "scores": [by_family.get(f) for f in pair], "round": round_no,
            "measurement": separating(*pair), "added": False}
