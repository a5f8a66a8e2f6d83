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
   separate them (the family classes' ``separated_by``); the better one is still added. At one loading rate,
   damping and friction are not told apart by a guess: when one is best and the other
   is in the model, or explains the residual within max(20, 25 %) of it, neither is
   added and the pair is reported (`hdsim.identification.policy.rate_ambiguity`). The
   pair is reported too when nothing passes but one of it, beside its partner, explains
   part of what is left (`hdsim.identification.policy.rate_question_left`).
7. *How sure*: block-bootstrap inclusion probabilities and a ``loo_compare``-style table
   per round (`hdsim.identification.confidence`).

Whiteness of the final residual (`hdsim.identification.residuals.whiteness`) decides the verdict:
a residual that is neither white nor at the noise floor means the model still misses
something (a form the library lacks, or an effect outside it) and no success is claimed.

Steps 4 to 6 are `hdsim.identification.policy.decide_round`, a pure function of the
scored candidates; the loop that applies it is `hdsim.identification.engine`, shared by
every test kind. This module is the twist tests' part of it: the stiffness and the
kinematic-error test kinds and their session (how a candidate is fitted and scored).

The acceptance rule is tuned on the battery ``validation/diagnosis_battery.py`` (truth
data from ``tests/truth.py``, forms unlike the library's; the slow tests of
``tests/test_diagnosis.py`` run a part of it) and checked on held-out seeds of the truth
zoo (``validation/zoo_battery.py``): its rates are in the tutorial
``docs/tutorial-find-missing-effect.md``.
"""

from __future__ import annotations

import functools
from typing import ClassVar

from hdsim.errors import InputError, SolverError
from hdsim.identification import breakaway, running_diagnosis  # noqa: F401  (register their test kinds)
from hdsim.identification.confidence import diagnosis_confidence
from hdsim.identification.engine import Candidate, Diagnosis, Step
from hdsim.identification.fit import (Evaluator, build_model, fit, fit_many, make_problem, parse_effects,
                                      result_of)
from hdsim.identification.folds import folds, one_loading_rate
from hdsim.identification.optimizer import judge_nested
from hdsim.identification.outcome import plausibility, twist_limits
from hdsim.identification.problem import other_starts
from hdsim.identification.residuals import findings
from hdsim.identification.selection import TWIST_THRESHOLDS, score_candidate
from hdsim.identification.test_kinds import TestKind, register_test_kind, test_kind
from hdsim.io.data_checks import run_checks, torque_sign_convention
from hdsim.io.measurement import Measurement
from hdsim.model import effects as fx
from hdsim.model.drive import SLOTS
from hdsim.units import ARCSEC_PER_RAD

__all__ = ["Diagnosis", "Step", "diagnose", "folds", "TwistTest", "TwistSession", "MAX_ITERATIONS"]

#: iterations of every fit of a diagnosis at most. A round's lockstep takes as many passes
#: as its slowest fit, and stopping the slow ones early errs towards not adding (the score
#: only falls with iterations); validation/README.md §4 has the measurements behind 25
MAX_ITERATIONS = 25


def diagnose(meas: Measurement, effects=None, *, unit=None, families=None, candidates: dict | None = None,
             max_rounds: int | None = None, max_steps: int | None = None, log=None) -> Diagnosis:
    """Find the effect families a measurement needs beyond ``effects``.

    The engine alone: no data checks, outcome or report (`hdsim.diagnose`, in
    `hdsim.identification.workflow`, adds them).

    Parameters
    ----------
    meas : Measurement
        A record of any registered test kind (`hdsim.identification.test_kinds`).
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
    Diagnosis
        Every step with its fit and the candidates tried, what was added, the
        ambiguities, the whiteness of the final residual and the findings.
    """
    return test_kind(meas.test).diagnose(meas, effects, unit=unit, families=families, candidates=candidates,
                                         max_rounds=max_rounds, max_steps=max_steps, log=log)


# --------------------------------------------------------------------------- the twist tests


class TwistTest(TestKind):
    """A test whose error is the output angle [rad] against the model's (stiffness, kinematic error)."""

    thresholds = TWIST_THRESHOLDS
    report_unit = ("arcsec", ARCSEC_PER_RAD)
    compiled_fits = True
    #: a record at one loading rate leaves the rate pair's question open (a locked test's
    #: loop; a driven test's rate is the speed, and damping shows without reversals)
    asks_rate: ClassVar[bool] = False
    #: a locked loop shows friction and backlash only over torque reversals
    needs_reversals: ClassVar[bool] = True
    #: the families in the order they are tried
    family_order: ClassVar[tuple[str, ...]] = ()

    def families(self):
        return {f: fx.FAMILY_BASES[f] for f in self.family_order}

    def ordered(self, current):
        return [f for f in SLOTS if f in current]

    def parse_effects(self, effects):
        return parse_effects(effects)  # a dict too: its forms are checked as a text's are

    def fit(self, meas, effects=None, *, unit=None):
        return fit(meas, effects, unit=unit)

    def fit_summary(self, result, stem, scale) -> dict:
        summary = result.summary()
        summary["whiteness"] = self.residual_whiteness(result)
        summary["findings"] = findings(result.measurement, result.residual)
        return summary

    def session(self, meas, chosen, *, unit=None, candidates=None, max_steps=None):
        return TwistSession(self, meas, chosen, unit=unit, candidates=candidates, max_steps=max_steps)

    def fit_errors(self, fit_result) -> dict:
        return {"rmse_rad": fit_result.rmse_rad, "max_abs_error_rad": fit_result.max_abs_rad}

    def fit_json(self, fit_result) -> dict:
        summary = fit_result.summary()
        # fitted and derived too: the uncertainty is keyed by what was fitted (the stiffness K0
        # under a kinematic-error run's load), so each value stands beside its uncertainty
        return {key: summary[key] for key in ("effect_ids", "params", "fitted", "uncertainty", "derived",
                                              "offset_rad")}

    def step_figures(self, step) -> dict:
        return {"holdout_rmse_rad": [float(f.rmse(~f.rows)) for f in step.fold_fits]}

    def prepare(self, meas):
        return torque_sign_convention(meas)

    def checks(self, meas, scale):
        return run_checks(meas, scale)

    def plausibility(self, fit_result, scale):
        return plausibility(fit_result.summary(), scale)

    def limits(self, diagnosis_json, data, ranking):
        return twist_limits(self, diagnosis_json, data, ranking)

    def unexplained(self) -> str:
        return ("the residual keeps a structure that no family of the library explains on this record: look at "
                "the residual against time and torque in the report, and record the test at a second amplitude "
                "and loading rate")

    def report_figures(self, diagnosis, folder, scale):
        from hdsim.identification.report import twist_figures  # matplotlib only when asked

        return twist_figures(diagnosis, folder)

    def fit_figures(self, result, folder, scale):
        from hdsim.identification.report import twist_fit_figure

        return [twist_fit_figure(result, folder)]

    def predictions(self, result, scale):
        from hdsim.identification.predictions import catalog_predictions

        return catalog_predictions(result)


class StiffnessTest(TwistTest):
    """The torsional stiffness / hysteresis test: wave generator locked, circular spline fixed."""

    name = "stiffness"
    asks_rate = True
    family_order = ("hardening", "backlash", "friction", "damping")


class KinematicErrorTest(TwistTest):
    """Kinematic error with the wave generator driven (the output angle against the ideal)."""

    name = "kinematic_error"
    needs_reversals = False
    family_order = ("kinematic_error", "hardening", "backlash", "friction", "damping")


register_test_kind(StiffnessTest())
register_test_kind(KinematicErrorTest())


class TwistSession:
    """A twist test's fits for one record: all rows and two hold-out folds per model, in
    lockstep (`hdsim.identification.fit.fit_many`)."""

    def __init__(self, kind: TwistTest, meas: Measurement, chosen: dict, *, unit=None, candidates=None,
                 max_steps=None):
        self.kind, self.measurement, self.chosen, self.unit = kind, meas, dict(chosen), unit
        self.stand_in = {f: fx.default_effect(f) for f in SLOTS}
        for family, effect_id in (candidates or {}).items():
            fx.effect_class(family, effect_id)
            self.stand_in[family] = effect_id
        self.evaluator = Evaluator(meas, max_steps=max_steps)
        self.masks, self.fold_rule = folds(meas)
        self.one_rate = kind.asks_rate and one_loading_rate(meas)
        self.passes = 0
        self.unit_name = None

    def baseline(self) -> Step:
        model = build_model(self.unit, self.chosen, self.measurement)
        self.unit_name = model.name
        slots = self._slots(model, [None], [[None], [None]], "baseline")
        self.passes += fit_many(self.evaluator, [p for slot in slots for p in slot])
        try:
            fits = self._results(slots)
        except (InputError, SolverError) as exc:  # the user's own model: a refusal, naming the record
            source = self.measurement.source
            raise type(exc)(str(exc) if str(exc).startswith(source) else
                            f"{source}: the baseline ({', '.join(self.chosen) or 'the base model'}) cannot be "
                            f"fitted to this record: {exc}") from None
        return Step(effects=self.kind.ordered(self.chosen), fit=fits[0], fold_fits=fits[1:])

    def entry_forms(self, family: str) -> tuple:
        """The stand-in of ``family`` and its `Effect.entry_forms`."""
        effect_id = self.stand_in[family]
        return (effect_id,) + tuple(fx.effect_class(family, effect_id).entry_forms)

    def other_forms(self, current: dict, done: set) -> list:
        """Trials of the model with one family in another form (`Effect.other_forms`); a family
        changes form once at most (``done``), so the procedure cannot swing between two forms."""
        return [(family, other, {**current, family: other}) for family, effect_id in current.items()
                if family not in done for other in fx.effect_class(family, effect_id).other_forms]

    def try_models(self, step: Step, trials: list, residual: dict) -> list:
        """Fit every trial ``(family, effect id, {family: effect id})`` on all rows and on each
        fold in one lockstep, each from ``step``'s values and afresh, and score it against
        ``step``. A trial that cannot be built or fitted is a candidate rejected with the
        reason, never fatal."""
        built, scored = [], []
        for family, effect_id, structure in trials:
            try:
                model = build_model(self.unit, structure, self.measurement)
                slots = self._slots(model, [dict(step.fit.internal), None],
                                    [[dict(f.internal), None] for f in step.fold_fits], family)
            except (InputError, SolverError) as exc:
                scored.append(Candidate.failed(family, effect_id, str(exc)))
                continue
            built.append((family, effect_id, slots))
        if built:
            self.passes += fit_many(self.evaluator, [p for _, _, slots in built for slot in slots for p in slot])
        for family, effect_id, slots in built:
            try:
                res = self._results(slots)
            except (InputError, SolverError) as exc:
                scored.append(Candidate.failed(family, effect_id, str(exc)))
                continue
            candidate = score_candidate(family, effect_id, res, step, self.kind.thresholds)
            if family not in step.effects:  # an added family holds the step's model (another form does not)
                for cand_fit, base_fit in zip(res[1:], step.fold_fits):
                    if not judge_nested(candidate, cand_fit, base_fit.rss, f"{family}={effect_id} (hold-out fold fit)"):
                        break
            scored.append(candidate)
        return scored

    def confidence(self, steps: list) -> dict:
        return diagnosis_confidence(self.measurement, steps, self.masks, self.one_rate, self.kind.thresholds,
                                    self.kind.rate_partner)

    def findings(self, step: Step, whiteness: dict) -> list:
        return findings(self.measurement, step.fit.residual, floor=whiteness.get("noise_floor_rad"))

    def _slots(self, model, all_starts: list, fold_starts: list, label: str) -> list[list]:
        """The fits of one model: all rows and each fold, one problem per start (the effects'
        `other_starts` added to every slot); the lowest cost of a slot counts."""
        alts = other_starts(model, self.measurement)
        problem = functools.partial(make_problem, model, self.measurement, self.evaluator, max_iter=MAX_ITERATIONS)
        slots = [[problem(start=s, label=f"{label}:all") for s in all_starts + alts]]
        for i, mask in enumerate(self.masks):
            slots.append([problem(rows=mask, start=s, label=f"{label}:fold{i}") for s in fold_starts[i] + alts])
        return slots

    def _results(self, slots: list) -> list:
        out = []
        for slot in slots:
            result = result_of(self.evaluator, min(slot, key=lambda p: p.cost), unit=self.unit_name)
            result.contained_cost = next((p.nested.cost for p in slot if p.nested is not None
                                          and p.nested.r is not None), None)
            out.append(result)
        return out
