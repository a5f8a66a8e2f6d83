"""One identification engine for every test kind: greedy forward selection of families.

Each round fits the model plus every family not yet in it (its entry forms), scores the
candidates against the model, and lets `hdsim.identification.policy.decide_round` decide:
add the best candidate that passes, change a family's form instead, let a loss stand in
the model while its rate law is undecidable, or stop. What a test kind brings (how a
candidate is fitted and scored, its folds, its noise floor) comes from its *session*
(`hdsim.identification.test_kinds.TestKind.session`); the loop, the result types and
the JSON are the same for all. The procedure is explained step by step in
``docs/tutorial-find-missing-effect.md``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from hdsim.identification.optimizer import judge_nested, json_finite
from hdsim.identification.policy import RoundState, decide_round, wants_other_forms

__all__ = ["Candidate", "Step", "Diagnosis", "run_diagnosis"]


@dataclass
class Candidate:
    """One family (in one form) tried in one round.

    ``figures`` holds what the test kind reports of it beside the common fields (its rms
    error under the kind's key, hold-out errors, the share explained …), in the order of
    the JSON; ``share`` is the share of the residual above the noise floor it removes,
    for the kinds whose ties are judged by it.
    """

    family: str
    effect: str
    fit: object | None
    fold_fits: list = field(default_factory=list)
    score: float = math.inf
    n_eff: float = 0.0
    holdout_gain: list = field(default_factory=list)
    accepted: bool = False
    reason: str = ""
    share: float = 0.0
    figures: dict = field(default_factory=dict)

    @classmethod
    def failed(cls, family: str, effect: str, why: str) -> "Candidate":
        """A candidate whose model could not be built or fitted: rejected, with the reason."""
        return cls(family=family, effect=effect, fit=None, reason=f"could not be fitted: {why}")

    def to_json(self, error_key: str = "rmse_rad") -> dict:
        if self.fit is None:
            return {"family": self.family, "effect": self.effect, error_key: None, "score": None,
                    "passes": False, "why": self.reason}
        return {"family": self.family, "effect": self.effect, **self.figures, "score": self.score,
                "n_eff": self.n_eff, "holdout_gain": self.holdout_gain, "passes": self.accepted,
                "why": self.reason}


@dataclass
class Step:
    """The model after a round: its fit, its fold fits, and what was tried to improve on it."""

    effects: list
    fit: object
    fold_fits: list
    candidates: list = field(default_factory=list)
    added: str | None = None
    #: the families of the model tried in their other forms (the proxy guard)
    reshapes: list = field(default_factory=list)
    #: ``{"family", "from", "to", "score", "instead_of", "round"}`` when a form changed instead
    reshaped: dict | None = None
    #: the family of a rate pair one loading rate cannot separate, put in the model (not
    #: added) so that the other families are tried against a model with the loss
    provisional: str | None = None
    #: what the session keeps of this model between rounds (a cache; never in the JSON)
    memo: dict = field(default_factory=dict)


@dataclass
class Diagnosis:
    """The result of a diagnosis of any test kind; `to_json` is the object ``hdsim diagnose
    --json`` prints (docs/cli.md)."""

    kind: object
    measurement: object
    steps: list
    added: list
    ambiguous: list
    reshaped: list
    fold_rule: str
    whiteness: dict
    seconds: float
    passes: int
    confidence: dict = field(default_factory=dict)
    findings_before: list = field(default_factory=list)
    findings_after: list = field(default_factory=list)

    @property
    def test(self) -> str:
        return self.kind.name

    @property
    def baseline(self) -> Step:
        return self.steps[0]

    @property
    def final(self) -> Step:
        return self.steps[-1]

    @property
    def ranking_round(self) -> int:
        """The round (1-based) whose candidates are `ranking`: the first round settled by an
        addition, a stand-in or a stop, not by a change of form.

        A round settled by a change of form found that the residual was the shape of a
        family already in the model: its candidates were scored against a baseline the
        diagnosis then replaced, and their order says which family imitates that shape
        best, not which is missing. The superseded rounds stay in ``rounds`` and ``reshaped``.
        """
        return next((k + 1 for k, step in enumerate(self.steps) if step.candidates and step.reshaped is None), 1)

    @property
    def ranking(self) -> list:
        """The candidates of `ranking_round`, best score first."""
        return sorted(self.steps[self.ranking_round - 1].candidates, key=lambda c: c.score)

    @property
    def success(self) -> bool:
        """True only when the final residual is explained (white or at the noise floor)."""
        return bool(self.whiteness["explained"])

    def _chosen(self, k: int):
        """The candidate that made step ``k`` from step ``k - 1``."""
        prev = self.steps[k - 1]
        if prev.reshaped is not None:
            return next(c for c in prev.reshapes if c.family == prev.reshaped["family"]
                        and c.effect == prev.reshaped["to"])
        return next(c for c in prev.candidates if c.family in (prev.added, prev.provisional))

    def table(self) -> list[dict]:
        """Before/after table: one row per step (effects, rms, score, hold-out errors)."""
        rows = []
        for i, step in enumerate(self.steps):
            prev = self.steps[i - 1] if i else None
            row = {"step": i, "effects": list(step.effects),
                   "added": None if prev is None else prev.added,
                   "provisional": None if prev is None else prev.provisional,
                   "other_form": None if prev is None or prev.reshaped is None
                   else {prev.reshaped["family"]: prev.reshaped["to"]}}
            row.update(self.kind.fit_errors(step.fit))
            row["score"] = None if prev is None else self._chosen(i).score
            row.update(self.kind.step_figures(step))
            rows.append(row)
        return rows

    def verdict(self) -> str:
        return self.kind.verdict(self.whiteness)

    def report(self, directory, summary: dict | None = None, scale=None):
        """Write the report page (``index.html``, ``index.md``, the figures) into ``directory``
        (``summary``: the outcome and checks to show on top; ``scale``: the drive's datasheet
        numbers); returns the path of ``index.html``. InputError when ``directory`` is a file
        (`hdsim.identification.test_kinds.TestKind.report_folder`)."""
        return self.kind.write_report(self, self.kind.report_folder(directory), summary or {}, scale)

    def to_json(self) -> dict:
        key = self.kind.error_key
        base, final = self.baseline, self.final
        out = {
            "test": self.test,
            "baseline": {"effects": list(base.effects), **self.kind.fit_errors(base.fit)},
            "ranking": [c.to_json(key) for c in self.ranking],
            "ranking_round": self.ranking_round,
            "added": list(self.added),
            "final": {"effects": list(final.effects), **self.kind.fit_errors(final.fit),
                      **self.kind.fit_json(final.fit)},
            "ambiguous": list(self.ambiguous),
            "reshaped": list(self.reshaped),
            "rounds": [{"effects": list(s.effects), key: self.kind.fit_errors(s.fit)[key],
                        "candidates": [c.to_json(key) for c in sorted(s.candidates, key=lambda c: c.score)],
                        "other_forms": [c.to_json(key) for c in sorted(s.reshapes, key=lambda c: c.score)],
                        "added": s.added, "reshaped": s.reshaped, "provisional": s.provisional}
                       for s in self.steps],
            "table": self.table(),
            "holdout": self.fold_rule,
            "whiteness": json_finite(self.whiteness),
            "success": self.success,
            "verdict": self.verdict(),
            "findings": {"baseline": self.findings_before, "final": self.findings_after},
            "confidence": self.confidence,
            "seconds": round(self.seconds, 3),
            "passes": self.passes,
        }
        out.update(self.kind.diagnosis_json(self))
        return out


def _whiteness(kind, step: Step) -> dict:
    """The kind's judgement of a step's residual (`TestKind.residual_whiteness`), worked out
    once per step: each round's stop and proxy guard and the final verdict read it."""
    if "whiteness" not in step.memo:
        step.memo["whiteness"] = kind.residual_whiteness(step.fit)
    return step.memo["whiteness"]


def run_diagnosis(kind, session, pool: list, *, max_rounds: int | None = None, log=None) -> Diagnosis:
    """Greedy forward selection over ``pool`` on ``session``'s record, decided round by round
    by `decide_round` with ``kind``'s thresholds.

    ``session`` fits and scores (`hdsim.identification.test_kinds.TestKind.session`; the
    module text of `hdsim.identification.test_kinds` lists what the engine reads of it).
    """
    t0 = time.perf_counter()
    say = log or (lambda *_: None)
    step = session.baseline()
    current = dict(session.chosen)
    steps, added, ambiguous, reshaped = [step], [], [], []
    undecidable: set = set()  # a rate pair once one loading rate could not separate it
    unit, scale = kind.report_unit
    say(f"baseline {step.effects}: rms {kind.fit_errors(step.fit)[kind.error_key] * scale:.3g} {unit}")
    while True:
        todo = [f for f in pool if f not in current and f not in undecidable]
        if not todo or (max_rounds is not None and len(added) >= max_rounds):
            break
        residual = _whiteness(kind, step)  # the stop and the guard read it
        if kind.stop_when_white and residual["white"]:
            break
        state = RoundState(round_no=len(steps), current=dict(current), added=tuple(added),
                           reshaped=tuple(r["family"] for r in reshaped),
                           residual_explained=bool(residual["explained"]), one_rate=session.one_rate,
                           rate_partner=kind.rate_partner, separating=kind.separating)
        trials = [(family, form, {**current, family: form}) for family in todo
                  for form in session.entry_forms(family)]
        tried = session.try_models(step, trials, residual)
        for c in tried:  # a model holding the step's must fit at least as well: else a defect, not a finding
            if c.fit is not None:
                judge_nested(c, c.fit, step.fit.rss, f"{c.family}={c.effect} over {'+'.join(step.effects) or 'base'}")
        step.candidates = _best_form_per_family(tried)
        say(f"round {state.round_no}: " + ", ".join(f"{c.family} {_shown_score(c)}"
                                                    for c in sorted(step.candidates, key=lambda c: c.score)))
        forms = session.other_forms(current, set(state.reshaped))
        reshapes = None
        if wants_other_forms(step.candidates, bool(forms), state):
            step.reshapes = reshapes = session.try_models(step, forms, residual)
            say(f"round {state.round_no}, other forms: "
                + ", ".join(f"{c.family}={c.effect} {_shown_score(c)}" for c in reshapes))
        decision = decide_round(step.candidates, reshapes, state, kind.thresholds)
        ambiguous += [entry for entry in decision.ambiguous if kind.keeps_entry(entry, ambiguous)]
        chosen = decision.chosen
        if decision.action == "stop":
            break
        if decision.action == "reshape":
            step.reshaped = {"family": chosen.family, "from": current[chosen.family], "to": chosen.effect,
                             "score": chosen.score, "instead_of": _best_passing(step.candidates),
                             "round": state.round_no}
            reshaped.append(step.reshaped)
        elif decision.action == "stand_in":
            step.provisional = chosen.family
            undecidable |= set(decision.pair)
        else:
            step.added = chosen.family
            added.append(chosen.family)
        current[chosen.family] = chosen.effect
        step = Step(effects=kind.ordered(current), fit=chosen.fit, fold_fits=chosen.fold_fits)
        steps.append(step)
    steps, reshaped, ambiguous = _settle_stand_in(steps, reshaped, ambiguous)
    step = steps[-1]
    # one noise floor on the page: the final model's (its white residual), which the summary
    # states, is also the one both steps' findings are read against
    whiteness = _whiteness(kind, step)
    return Diagnosis(kind=kind, measurement=session.measurement, steps=steps, added=added, ambiguous=ambiguous,
                     reshaped=reshaped, fold_rule=session.fold_rule, whiteness=whiteness,
                     seconds=time.perf_counter() - t0, passes=session.passes,
                     confidence=session.confidence(steps),
                     findings_before=session.findings(steps[0], whiteness),
                     findings_after=session.findings(step, whiteness))


def _shown_score(candidate) -> str:
    """A candidate's score for the round log; a candidate whose fit failed (score inf, null
    in the JSON beside its ``why``) reads "failed"."""
    return f"{candidate.score:.1f}" if math.isfinite(candidate.score) else "failed"


def _settle_stand_in(steps: list, reshaped: list, ambiguous: list) -> tuple[list, list, list]:
    """A loss that stood in the model and after which nothing was added goes again.

    The record then said no more than the pair, and the model stays the one before it (a
    form changed against the stand-in goes too, judged as it was against the stand-in).
    A stand-in that stays is named in its pair's entry.
    """
    held = next((k for k, s in enumerate(steps) if s.provisional is not None), None)
    if held is not None and not any(s.added for s in steps[held:]):
        steps = steps[:held + 1]
        steps[held].provisional = None
        reshaped = [r for r in reshaped if r["round"] <= held]
        ambiguous = [a for a in ambiguous if a["round"] <= held + 1]
    elif held is not None:
        entry = next(a for a in ambiguous if a["round"] == held + 1 and a["added"] is False)
        entry["provisional"] = steps[held].provisional
    return steps, reshaped, ambiguous


def _best_form_per_family(scored: list) -> list:
    """One candidate per family: the best-scoring form among those that pass, else the
    best-scoring form (the rule that picks the round's addition, applied within a family)."""
    best = {}
    for c in scored:
        held = best.get(c.family)
        if held is None or (c.accepted, -c.score) > (held.accepted, -held.score):
            best[c.family] = c
    return list(best.values())


def _best_passing(candidates: list) -> str | None:
    """The family of the best candidate that passes (the one a change of form displaced)."""
    passing = sorted((c for c in candidates if c.accepted), key=lambda c: c.score)
    return passing[0].family if passing else None
