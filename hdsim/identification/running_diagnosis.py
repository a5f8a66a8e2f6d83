"""The running-torque test kind: which families a sweep needs beyond the Coulomb level.

The loop is the engine every test kind shares (`hdsim.identification.engine`): fit the
base model and the given families, try every other family of a running-torque test
(`hdsim.model.running_terms.RUNNING_FAMILIES`), rank them, add the best if it passes,
refit, repeat. The error is a torque (``rmse_Nm``); the noise floor (``noise_floor_Nm``)
is the record's own, measured without a model. The thresholds are `RUNNING_THRESHOLDS`.

A candidate passes only if all of these hold:

1. **Information criterion:** its BIC, with the residual's effective sample count,
   improves by more than ``-score``, or its hold-out gain (2.) exceeds
   ``strong_holdout_gain`` on both halves: a model far from the record leaves a residual
   correlated over many rows, whose few effective samples make the BIC timid.
2. **Hold-out:** fitted on the first half of every plateau (and the ramps) it predicts
   the second half better than the model without it by ``holdout_gain``, and the other
   way round. Each half holds every speed and direction, so the hold-out stays valid
   however unequal the dwell times are. When the model's rms is already within
   `EXPLAINED_RATIO` of the record's noise floor the bar is ``floor_holdout_gain``: an
   effect under the noise must still predict unseen data clearly better.
3. **A real share of what is missing:** it removes at least ``min_share`` of the residual
   variance above the noise floor. An effect that only patches the imperfect form of
   another family removes a few per cent; a missing family removes most of it.
4. **Not a proxy:** the families already in the model are allowed other shapes of their
   own (`hdsim.model.running_terms.RunningTerm.other_shapes`: a churning loss growing as
   √ω and ω², Stribeck curves of other shapes, higher ripple orders); on top of that
   widened model the candidate must still predict both held-out halves better by
   ``proxy_holdout_gain``. A Stribeck rise that only bends a viscous line into the power
   law of the drive's real churning is then not credited as friction.

Two candidates that pass and explain the residual within ``tie_share`` of each other are
reported as ``ambiguous``, with the measurement that would separate them.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import MappingProxyType

import numpy as np

from hdsim.errors import InputError
from hdsim.identification.engine import Candidate, Diagnosis, Step
from hdsim.identification.policy import Thresholds
from hdsim.identification.residuals import EXPLAINED_RATIO, whiteness
from hdsim.identification.running_fit import SweepRecord, fit_running
from hdsim.identification.running_plausibility import running_plausibility
from hdsim.identification.test_kinds import TestKind, register_test_kind, test_kind
from hdsim.io.measurement import Measurement
from hdsim.model.running_terms import BASE_TERM, RUNNING_FAMILIES, RUNNING_FORMS, parse_running_forms

__all__ = ["RunningTorqueTest", "RunningSession", "diagnose_running", "running_limits", "RUNNING_THRESHOLDS"]

#: the thresholds of a running-torque test: a family must lower the BIC by more than 10, or
#: predict both held-out halves better by 10 %; predict them better by 2 % (10 % once the rms
#: is at the noise floor); remove 20 % of the residual variance above the noise floor; still
#: predict them 5 % better when the families in the model take other shapes; two passing
#: candidates whose shares differ by less than 5 % are a near tie
RUNNING_THRESHOLDS = Thresholds(score=-10.0, holdout_gain=0.02, floor_holdout_gain=0.10, strong_holdout_gain=0.10,
                                min_share=0.2, proxy_holdout_gain=0.05, tie_share=0.05)


class TorqueTest(TestKind):
    """What the torque tests share (a sweep, and a breakaway ramp `hdsim.identification.breakaway`):
    an error in N·m, the running-torque thresholds, a residual judged against the record's noise floor."""

    error_unit = "N·m"
    error_key = "rmse_Nm"
    report_unit = ("N·m", 1.0)
    thresholds = RUNNING_THRESHOLDS
    stop_when_white = False
    #: what the verdict calls a record of this kind
    record_word = "sweep"

    def ordered(self, current):
        return list(current)  # the order the families entered the law

    def keeps_entry(self, entry, kept):
        # the same pair may come up again in a later round
        return all(set(a["families"]) != set(entry["families"]) for a in kept)

    def fit_errors(self, fit) -> dict:
        return {"rmse_Nm": fit.rmse_Nm}

    def diagnosis_json(self, diagnosis) -> dict:
        summary = diagnosis.final.fit.summary()
        return {"metrics": summary["metrics"], "noise_floor_Nm": summary["noise_floor_Nm"]}

    def verdict(self, w: dict) -> str:
        if w["explained"]:
            return super().verdict(w)
        return (f"the residual keeps structure (rms {w['rms_over_noise']:.1f}× the noise floor): the "
                f"{self.record_word} holds an effect that no {self.name.replace('_', '-')} family explains, or "
                "explains only in part")

    def residual_whiteness(self, fit) -> dict:
        return _explained(fit)

    #: units of the fitted figures that are no term's torque amplitude (the breakaway
    #: fit's bare ``viscous`` included)
    OTHER_UNITS = MappingProxyType({"inertia": "kg·m²", "stribeck_speed": "rad/s", "viscous": "N·m·s/rad"})

    def parameter_unit(self, result, name):
        family, _, column = name.rpartition(".")
        terms = [BASE_TERM, *RUNNING_FAMILIES.values(), *(t for forms in RUNNING_FORMS.values() for t in forms)]
        own = {c: u for t in terms if t.family == family for c, u in t.column_units.items()}
        return own.get(column) or self.OTHER_UNITS.get(column, "N·m")


class RunningTorqueTest(TorqueTest):
    """The running-torque (friction sweep) test: the torque to turn the drive at steady speeds."""

    name = "running_torque"
    parameters_heading = "Fitted parameters (on the wave-generator shaft)"

    def families(self):
        return {family: type(term) for family, term in RUNNING_FAMILIES.items()}

    def parse_effects(self, effects):
        return parse_running_forms(effects)

    def fit(self, meas, effects=None, *, unit=None):
        return fit_running(meas, list(parse_running_forms(effects).values()), unit=unit)

    def fit_summary(self, result, stem, scale) -> dict:
        from hdsim.identification.running_report import fit_figures

        summary = result.summary()
        summary["figures"] = [str(f) for f in fit_figures(result, stem, scale.running_torque or None)]
        return summary

    def session(self, meas, chosen, *, unit=None, candidates=None, max_steps=None):
        return RunningSession(meas, chosen, unit)

    def diagnose(self, meas, effects=None, *, unit=None, families=None, candidates=None, max_rounds=None,
                 max_steps=None, log=None):
        diagnosis = super().diagnose(meas, effects, unit=unit, families=families, max_rounds=max_rounds, log=log)
        entry = one_way_ripple(diagnosis)
        if entry is not None and self.keeps_entry(entry, diagnosis.ambiguous):
            diagnosis.ambiguous.append(entry)
        return diagnosis

    def fit_json(self, fit) -> dict:
        summary = fit.summary()
        # derived: the inertia and the starting torque (each way, with its basis), as `hdsim fit` gives them
        return {"fitted": summary["fitted"], "uncertainty": summary["uncertainty"], "law": summary["law"],
                "derived": summary["derived"], "not_determined": summary["not_determined"]}

    def prepare(self, meas):
        from hdsim.io.running_checks import sweep_torque_sign

        return sweep_torque_sign(meas)

    def checks(self, meas, scale):
        # imported here: running_checks loads scipy.signal (about a second)
        from hdsim.io.running_checks import running_checks

        return running_checks(meas, scale)

    def plausibility(self, fit, scale):
        return running_plausibility(fit, scale)

    def limits(self, diagnosis_json, data, ranking):
        return running_limits(diagnosis_json, data, ranking)

    def unexplained(self) -> str:
        return ("the residual keeps a structure that no running-torque family explains: look at the residual "
                "against time and wave-generator angle in the report (a motor's cogging, a temperature drift, "
                "a load that changes)")

    def report_figures(self, diagnosis, folder, scale):
        from hdsim.identification.running_report import running_figures  # matplotlib only when asked

        return running_figures(diagnosis, folder, (scale.running_torque or None) if scale else None)

    def fit_figures(self, result, folder, scale):
        from hdsim.identification.running_report import fit_figures

        paths = fit_figures(result, Path(folder) / "fit", (scale.running_torque or None) if scale else None)
        return list(zip(paths, ("Plateau running torques against speed, with the fitted law and the catalog point.",
                                "What the law without its ripple leaves, against the wave-generator angle.")))

    def predictions(self, result, scale):
        from hdsim.identification.predictions import sweep_predictions

        return sweep_predictions(result, scale)

    def report_sections(self, diagnosis, diagnosis_json):
        from hdsim.identification.running_report import running_sections

        return running_sections(diagnosis_json)


register_test_kind(RunningTorqueTest())


class RunningSession:
    """A running-torque test's fits for one sweep: the law is linear in its amplitudes once
    the non-linear parameters are fixed, so every candidate is fitted afresh
    (`hdsim.identification.running_fit.fit_running`).

    A kind whose model is fitted the same way (a least-squares torque law on the rows a
    record moves) derives from it and gives its own `fit_model`, `entry_forms`, record and
    folds (`hdsim.identification.breakaway`)."""

    one_rate = False
    fold_rule = "first and second half of every plateau"
    #: the families in the model may take other shapes of their own (the proxy test)
    widens = True

    def __init__(self, meas, chosen: dict, unit=None):
        self.record = self.record_of(meas)
        self.unit = unit  # the drive each fit's ``.drive`` starts from
        self.measurement = self.record.measurement
        self.chosen = dict(chosen)
        self.folds = self.folds_of(self.record)
        self.passes = 0

    #: the kind's record of a measurement (speed, plateaus, moving rows)
    record_of = staticmethod(SweepRecord.of)

    @staticmethod
    def folds_of(record) -> tuple[list, list]:
        """(training rows, held-out rows) of the two hold-out folds: the first and the second
        half of every plateau; ramps train both, test neither."""
        first = np.zeros(record.speed.size, dtype=bool)
        second = np.zeros_like(first)
        for s in record.segments:
            mid = (s.start + s.stop) // 2
            first[s.start:mid] = True
            second[mid:s.stop] = True
        ramps = ~(first | second)
        return [first | ramps, second | ramps], [second, first]

    def fit_model(self, families, rows=None, widened=()):
        """The law with ``families`` fitted on ``rows`` (default every moving row). A hold-out
        fold's fit keeps the Stribeck grid's best point: it is judged only by its prediction of
        the other half, and the refinement would cost it half again."""
        return fit_running(self.record, families, rows=rows, widened=widened, refine=rows is None, unit=self.unit)

    def entry_forms(self, family: str) -> tuple:
        """The ids of the forms of ``family`` a candidate enters in (the best passing one stands
        for the family). A sweep in one direction cannot tell the ripple's forms apart (a
        torque that reverses with the motion and one that does not are the same there): it
        enters in its default form, and the outcome says what would tell them apart."""
        forms = RUNNING_FORMS[family]
        return tuple(term.id for term in (forms if len(self.record.directions) > 1 else forms[:1]))

    def baseline(self) -> Step:
        ids = list(self.chosen.values())
        return Step(list(self.chosen), self.fit_model(ids), self._holdout_rss(ids))

    def other_forms(self, current, done) -> list:
        return []  # the families' other shapes enter the acceptance rule instead (its proxy test)

    def try_models(self, step: Step, trials: list, residual: dict) -> list:
        at_floor = residual["rms_over_noise"] <= EXPLAINED_RATIO
        out = []
        for family, effect_id, model in trials:
            try:
                out.append(self._try(step, family, effect_id, list(model.values()), at_floor))
            except InputError as exc:  # a candidate that cannot be fitted is rejected, never the end
                out.append(Candidate.failed(family, effect_id, str(exc)))
        return out

    def confidence(self, steps) -> dict:
        return {}

    def findings(self, step, whiteness) -> list:
        return []

    def _holdout_rss(self, families, widened=()) -> list[float] | None:
        """Held-out RSS of each fold; None when a half is too short to fit."""
        out = []
        for fit_rows, test_rows in zip(*self.folds):
            try:
                fit = self.fit_model(families, rows=fit_rows, widened=widened)
            except InputError:
                return None
            r = fit.residual[test_rows & fit.record.moving]
            out.append(float(r @ r))
        return out

    def _share(self, before, after) -> float:
        """Share of the residual variance above the noise floor that ``after`` removes from ``before``."""
        missing = before.rss - _floor(self.record) ** 2 * before.n
        return min(max((before.rss - after.rss) / missing, 0.0), 1.0) if missing > 0 else 0.0

    def _proxy_gains(self, current: Step, ids: list) -> list[float] | None:
        """Held-out gains of the model ``ids`` over the model of ``current`` when its families
        may take their other shapes (None when the model has no family to widen)."""
        if not current.effects or not self.widens:
            return None
        if "widened" not in current.memo:  # the same for every candidate of the round: computed once
            current.memo["widened"] = self._holdout_rss(list(current.fit.forms.values()), widened=current.effects)
        both = self._holdout_rss(ids, widened=current.effects)
        return _gains(both, current.memo["widened"]) or [0.0]

    def _try(self, current: Step, family: str, effect_id: str, ids: list, at_floor: bool,
             thresholds: Thresholds = RUNNING_THRESHOLDS):
        """Fit the model ``ids`` (``current``'s forms plus ``family`` as ``effect_id``) and apply
        the acceptance rule."""
        fit = self.fit_model(ids)
        base = current.fit
        n_eff = fit.n_eff
        score = float(fit.bic(n_eff) - base.bic(n_eff))
        share = float(self._share(base, fit))
        held = self._holdout_rss(ids)  # the next step's folds if it is added
        gains = _gains(held, current.fold_fits)
        cand = Candidate(family, effect_id, fit, fold_fits=held, score=score, n_eff=n_eff,
                         holdout_gain=gains, share=share,
                         figures={"rmse_Nm": fit.rmse_Nm, "share_explained": share})
        bar = thresholds.floor_holdout_gain if at_floor else thresholds.holdout_gain
        if not gains:
            cand.reason = "the record is too short to hold half of each part out: nothing is added unvalidated"
        elif score >= thresholds.score and min(gains) < thresholds.strong_holdout_gain:
            cand.reason = f"the BIC changes by {score:+.3g}; it must fall by more than {-thresholds.score:g}"
        elif min(gains) < bar:
            worst = min(gains)
            told = f"better by only {100 * worst:.1f} %" if worst > 0 else f"worse by {100 * -worst:.3g} %"
            cand.reason = (f"it predicts the held-out halves {told}; {100 * bar:.0f} % better is needed"
                           + (" (the rms is at the noise floor already)" if at_floor else ""))
        elif share < thresholds.min_share:
            cand.reason = (f"it removes {100 * share:.0f} % of the residual above the noise floor, less than "
                           f"{100 * thresholds.min_share:.0f} %: a patch for another family's form, not a missing "
                           "family")
        else:
            proxy = self._proxy_gains(current, ids)
            if proxy is not None and min(proxy) < thresholds.proxy_holdout_gain:
                cand.reason = (f"a proxy: once {', '.join(current.effects)} may take other shapes of their own, "
                               f"it predicts held-out halves better by {100 * min(proxy):.1f} % only (less than "
                               f"{100 * thresholds.proxy_holdout_gain:.0f} %)")
            else:
                cand.accepted = True
                cand.reason = f"removes {100 * share:.0f} % of the residual above the noise floor"
        return cand


def _floor(record) -> float:
    """A sweep's model-free torque noise on the file's side [N·m]: what its verdict is judged against."""
    return record.noise_floor * abs(record.side_factor)


def _explained(fit) -> dict:
    """Whiteness of the residual, judged against the record's model-free noise floor (`_floor`)."""
    floor = _floor(fit.record)
    r = fit.residual[fit.rows]
    w = whiteness(r)
    # the rms about zero, not about the mean: a torque model has no offset, and a level that
    # differs between directions shows as a mean
    rms = fit.rmse_Nm
    ratio = rms / floor if floor > 0 else math.inf
    white = w["white"] and abs(float(np.mean(r))) < 3.0 * floor / math.sqrt(max(fit.n_eff, 1.0))
    return {"ljung_box_q": w["ljung_box_q"], "p_value": w["p_value"], "white": bool(white),
            "noise_floor_Nm": floor, "rmse_Nm": rms, "rms_over_noise": ratio,
            "explained": bool(white or ratio <= EXPLAINED_RATIO)}


def _gains(held, before) -> list[float]:
    """Relative fall of the held-out RSS per fold ([] when either could not be held out)."""
    if held is None or before is None:
        return []
    return [1.0 - h / b if b > 0 else 0.0 for h, b in zip(held, before)]


#: what tells the ripple's two forms apart (docs/physics.md, "Running torque")
RIPPLE_FORMS_SEPARATED_BY = ("the same sweep in the other direction: in one direction a ripple that reverses "
                             "with the motion (the friction level modulated with angle) and a position torque "
                             "that does not (a motor's cogging, an unbalance, gravity on the output) are the "
                             "same torque")


def one_way_ripple(diagnosis) -> dict | None:
    """The ``ambiguous`` entry of a ripple in the final model of a sweep in one direction, else
    None: there its forms are the same torque (`RunningSession.entry_forms` enters the default
    one), so the form in the model is named beside the other, as a form that ties with an
    addition is (`hdsim.identification.policy.decide_round`), with the sweep both ways that
    separates them. Scores: the ripple's when it was added, and the other form's against the
    same model; a ripple of the baseline was not added (``added`` False, scores None), and
    the form it was given stays open as a pair the record cannot tell apart."""
    fit = diagnosis.final.fit
    form = fit.forms.get("ripple")
    if form is None or len(fit.record.directions) > 1:
        return None
    other = next(term.id for term in RUNNING_FORMS["ripple"] if term.id != form)
    k = next((i for i, step in enumerate(diagnosis.steps) if step.added == "ripple"), None)
    scores = [None, None]
    if k is not None:
        step = diagnosis.steps[k]
        chosen = next(c for c in step.candidates if c.family == "ripple")
        try:
            rival = fit_running(fit.record, [*step.fit.forms.values(), other], unit=fit.unit)
            scores = [chosen.score, float(rival.bic(chosen.n_eff) - step.fit.bic(chosen.n_eff))]
        except InputError:
            scores = [chosen.score, None]
    return {"families": ["ripple", "ripple"], "scores": scores, "round": 0 if k is None else k + 1,
            "measurement": RIPPLE_FORMS_SEPARATED_BY, "added": k is not None, "other_form": {"ripple": other}}


def diagnose_running(meas: Measurement | SweepRecord, effects=None, *, families=None,
                     max_rounds: int | None = None, log=None) -> Diagnosis:
    """Find the running-torque families a sweep needs beyond ``effects`` (the running-torque
    kind's `TestKind.diagnose`).

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
    hdsim.identification.engine.Diagnosis
    """
    return test_kind("running_torque").diagnose(meas, effects, families=families, max_rounds=max_rounds, log=log)


def running_limits(diagnosis_json: dict, data: dict, ranking: list) -> list[str]:
    """What kept a sweep from deciding, each as the measurement that would (for `outcome.assess`)."""
    out = []
    speeds = data.get("speeds_rpm", [])
    if len(speeds) < 2:
        out.append("a sweep at three or more speeds, a decade apart: with one speed a loss that grows with speed "
                   "cannot be told from a constant friction level")
    if data.get("reversals", 0) < 1:
        out.append("the same sweep in the other direction: a level that differs between directions needs both"
                   + (", and so does telling a ripple that reverses with the motion (the friction level "
                      "modulated) from a position torque that does not (cogging, an unbalance)"
                      if "ripple" in diagnosis_json.get("added", []) else ""))
    out += [pair["measurement"] for pair in diagnosis_json.get("ambiguous", []) if pair.get("measurement")]
    return out
