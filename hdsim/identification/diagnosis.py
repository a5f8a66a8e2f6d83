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
   and refit all rows and both folds, starting from the baseline's values. All these fits
   run in lockstep in one batched pass per iteration (`hdsim.identification.fit.fit_many`).
3. Score each candidate by the change of an information criterion, BIC computed with an
   *effective* sample size::

       score = ΔBIC = n_eff · ln(RSS_candidate / RSS_baseline) + Δk · ln(n_eff),
       n_eff = n (1 − ρ₁)/(1 + ρ₁)

   with ``ρ₁`` the lag-one autocorrelation of the candidate's residual. A model that
   leaves a smooth, structured residual has far fewer independent samples than rows; an
   ordinary BIC would then reward any extra flexibility that soaks up some of the
   structure. Lower is better; the ranking is by score.
4. Accept the best candidate only if **all** of: ``score < −10`` (Kass–Raftery "very
   strong" evidence); its hold-out prediction error, the two folds pooled, is at least
   5 % below the baseline's; and the fit on all rows lowers the rms error by at least
   5 %. (Pooled, not fold by fold: when the folds are the two loading rates, a fit on
   the slow rate alone cannot tell damping from friction, so its prediction of the fast
   rate is poor for baseline and candidate alike and the gain there says nothing about
   the candidate; judged fold by fold, the battery misses a third of its true findings.) Then it
   becomes the baseline and the next round starts; the procedure stops when nothing
   passes, or when the residual is explained (white, or at the noise floor).
5. *Ambiguity*: when the runner-up also passes and its score is within
   ``max(10, 10 %)`` of the best, the pair is reported with the measurement that would
   separate them (`SEPARATING`); the better one is still added.

Whiteness of the final residual (`hdsim.identification.residuals.whiteness`) decides the verdict:
a residual that is neither white nor at the noise floor means the model still misses
something (a form the library lacks, or an effect outside it) and no success is claimed.

The acceptance rule is tuned on the battery ``validation/diagnosis_battery.py`` (truth
data from ``tests/truth.py``, forms unlike the library's; the slow tests of
``tests/test_diagnosis.py`` run a part of it): its rates are in the tutorial
``docs/tutorial-find-missing-effect.md``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from hdsim.errors import InputError, SolverError
from hdsim.identification.fit import (Evaluator, FitResult, build_model, effective_n, fit_many, make_problem,
                                      parse_effects, result_of)
from hdsim.model import effects as fx
from hdsim.io.measurement import Measurement
from hdsim.io.data_checks import loading_rates, turning_points
from hdsim.model.drive import SLOTS
from hdsim.identification.residuals import findings, whiteness

__all__ = ["Diagnosis", "diagnose", "folds", "SEPARATING", "SCORE_THRESHOLD",
           "HOLDOUT_GAIN", "MIN_GAIN"]

#: accept only below this score (ΔBIC with the effective sample size)
SCORE_THRESHOLD = -10.0
#: hold-out prediction error, both folds pooled, must fall by at least this fraction
HOLDOUT_GAIN = 0.05
#: rms error on all rows must fall by at least this fraction
MIN_GAIN = 0.05
#: near-tie: runner-up within max(10, this fraction of |best score|)
TIE_FRACTION = 0.10

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

#: families a test can show (the stiffness test locks the wave generator: no kinematic error)
FAMILIES_BY_TEST = {
    "stiffness": ("hardening", "backlash", "friction", "damping"),
    "kinematic_error": ("kinematic_error", "hardening", "backlash", "friction", "damping"),
    "running_torque": ("friction", "damping", "ripple"),
}


def _separating(a: str, b: str) -> str:
    if "kinematic_error" in (a, b):
        return ("a kinematic-error test over several output revolutions at constant load: the "
                "kinematic error repeats with the wave-generator angle, the other does not")
    return SEPARATING.get(frozenset({a, b}), "a test at another loading rate and amplitude")


# --------------------------------------------------------------------------- folds


def _legs(meas: Measurement):
    """(start, stop) index pairs of monotone torque legs and their mean |dT/dt|.

    The folds keep their own rule, a moving average over n/200 samples and a dead band of
    5 % of the swing: the battery's hold-out rates were measured with it (the noise-set
    band of `hdsim.io.data_checks.torque_legs` moved one backlash case of five).
    """
    T = np.asarray(meas.torque, dtype=float)
    k = max(int(T.size // 200), 1)
    smooth = np.convolve(T, np.ones(2 * k + 1) / (2 * k + 1), mode="same")
    turns = turning_points(smooth, 0.05 * max(float(np.ptp(smooth)), 1e-12))
    legs = [(a, b) for a, b in zip(turns[:-1], turns[1:]) if b - a > 2]
    return legs, loading_rates(meas.time, smooth, turns)  # one rate per leg (the same b - a > 2 rule)


def folds(meas: Measurement) -> tuple[list[np.ndarray], str]:
    """Two disjoint row masks that cover the record, and how they were chosen.

    By loading rate when the legs of the torque profile have rates differing by more
    than 1.5× (the slow and the fast legs); otherwise the first and the second half of
    the legs (or of the time, when there are fewer than two legs).
    """
    n = len(meas)
    if meas.test == "kinematic_error":
        # both folds need both load directions (else the twist under load is not
        # identified): alternate blocks of ten wave-generator revolutions
        wg = np.asarray(meas.wg_angle, dtype=float)
        travel = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(wg)))])
        block = (travel // (10 * 2 * np.pi)).astype(int)
        if block.max() >= 3:
            masks = [block % 2 == 0, block % 2 == 1]
            return masks, "alternate blocks of ten wave-generator revolutions"
    legs, rates = _legs(meas)
    masks = [np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)]
    if len(legs) >= 2 and np.min(rates) > 0 and np.max(rates) / np.min(rates) > 1.5:
        cut = math.sqrt(np.min(rates) * np.max(rates))
        for (a, b), rate in zip(legs, rates):
            masks[int(rate > cut)][a:b] = True
        how = "loading rate"
    elif len(legs) >= 2:
        half = len(legs) // 2
        for i, (a, b) in enumerate(legs):
            masks[int(i >= half)][a:b] = True
        how = "first and second half of the loading legs"
    else:
        masks[0][: n // 2] = True
        masks[1][n // 2:] = True
        how = "first and second half of the time"
    # rows outside any leg go to the nearer fold in time
    rest = ~(masks[0] | masks[1])
    if np.any(rest):
        idx = np.flatnonzero(rest)
        owner0 = np.flatnonzero(masks[0])
        owner1 = np.flatnonzero(masks[1])
        for i in idx:
            d0 = np.min(np.abs(owner0 - i)) if owner0.size else np.inf
            d1 = np.min(np.abs(owner1 - i)) if owner1.size else np.inf
            masks[int(d1 < d0)][i] = True
    if min(m.sum() for m in masks) < 10:
        masks = [np.arange(n) < n // 2, np.arange(n) >= n // 2]
        how = "first and second half of the time"
    return masks, how


# --------------------------------------------------------------------------- results


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
            "seconds": round(self.seconds, 3),
            "passes": self.passes,
        }


# --------------------------------------------------------------------------- procedure


def _problems(model, meas, ev, masks, starts, label):
    probs = [make_problem(model, meas, ev, rows=None, start=starts[0], label=f"{label}:all")]
    for i, mask in enumerate(masks):
        probs.append(make_problem(model, meas, ev, rows=mask, start=starts[i + 1], label=f"{label}:fold{i}"))
    return probs


def _results(ev, probs, unit):
    return [result_of(ev, p, unit=unit) for p in probs]


def diagnose(meas: Measurement, effects=None, *, unit=None, families=None, candidates: dict | None = None,
             max_rounds: int | None = None, max_steps: int = 4000, log=None) -> Diagnosis:
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
    max_steps : int
        Quasi-static steps at most per evaluation.
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
    passes = 0
    say = log or (lambda *_: None)

    model = build_model(unit, chosen, meas)
    unit_name = model.name
    probs = _problems(model, meas, ev, masks, [None, None, None], "baseline")
    passes += fit_many(ev, probs)
    fits = _results(ev, probs, unit_name)
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
        # phase A: every candidate on all rows, from the baseline's values and afresh
        cands = []
        phase_a = []
        failed = []  # candidates that could not be built: rejected with the reason, never fatal
        for family in todo:
            trial = dict(current)
            trial[family] = stand_in[family]
            try:
                cmodel = build_model(unit, trial, meas)
                warm = make_problem(cmodel, meas, ev, start=dict(step.fit.internal), label=f"{family}:all")
                cold = make_problem(cmodel, meas, ev, start=None, label=f"{family}:all-fresh")
            except (InputError, SolverError) as exc:
                failed.append(Candidate.failed(family, stand_in[family], str(exc)))
                continue
            cands.append([family, cmodel, warm, cold])
            phase_a += [warm, cold]
        passes += fit_many(ev, phase_a)
        # phase B: the hold-out folds, from the baseline's fold values and from the
        # candidate's all-rows optimum (whichever ends lower)
        phase_b = []
        for entry in cands:
            family, cmodel, warm, cold = entry
            best_all = warm if warm.cost <= cold.cost else cold
            optimum = dict(zip(best_all.names, (float(v[0]) for v in best_all.phys(best_all.u).values())))
            pairs = []
            for i, mask in enumerate(masks):
                a = make_problem(cmodel, meas, ev, rows=mask, start=dict(step.fold_fits[i].internal),
                                 label=f"{family}:fold{i}")
                b = make_problem(cmodel, meas, ev, rows=mask, start=optimum, label=f"{family}:fold{i}-opt")
                pairs.append((a, b))
                phase_b += [a, b]
            entry.append((best_all, pairs))
        passes += fit_many(ev, phase_b)
        scored = list(failed)
        for family, cmodel, warm, cold, (best_all, pairs) in cands:
            probs = [best_all] + [a if a.cost <= b.cost else b for a, b in pairs]
            try:
                res = _results(ev, probs, unit_name)
            except (InputError, SolverError) as exc:
                scored.append(Candidate.failed(family, stand_in[family], str(exc)))
                continue
            scored.append(_score(family, stand_in[family], res, step))
        step.candidates = scored
        ranked = sorted(scored, key=lambda c: c.score)
        say("round %d: " % (rounds + 1) + ", ".join(f"{c.family} {c.score:.1f}" for c in ranked))
        best = ranked[0]
        if not best.accepted:
            break
        if len(ranked) > 1:
            second = ranked[1]
            tie = max(10.0, TIE_FRACTION * abs(best.score))
            if second.accepted and second.score - best.score < tie:
                ambiguous.append({"families": [best.family, second.family],
                                  "scores": [best.score, second.score],
                                  "round": rounds + 1,
                                  "measurement": _separating(best.family, second.family)})
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
                     seconds=time.perf_counter() - t0, passes=passes)


def _score(family: str, effect_id: str, res: list, base: Step) -> Candidate:
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
    reasons = []
    if not score < SCORE_THRESHOLD:
        reasons.append(f"score {score:.1f} not below {SCORE_THRESHOLD:g}")
    if pooled < HOLDOUT_GAIN:
        reasons.append(f"hold-out error falls by only {100 * pooled:.1f} %")
    if gain < MIN_GAIN:
        reasons.append(f"rms error falls by only {100 * gain:.1f} %")
    ok = not reasons
    return Candidate(family=family, effect=effect_id, fit=fit_all, fold_fits=fold_fits,
                     score=float(score), n_eff=float(n_eff), holdout_rmse=hold, holdout_gain=gains,
                     pooled_holdout_gain=float(pooled),
                     gain=float(gain), accepted=ok, reason="passes" if ok else "; ".join(reasons))
