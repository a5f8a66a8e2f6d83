"""A test kind written outside the package is diagnosed end to end without editing hdsim.

The kind is a quasi-static torque-angle curve read as a polynomial: the base model is
``φ = c₀ + T/K``; its families are a cubic hardening term ``a·T³`` and a drift of the
angle in time ``d·t``, both linear in their amplitude, so the kind fits by least squares
and needs none of hdsim's fit machinery. It is registered with its columns, the file
reader takes its records, and `hdsim.diagnose` runs the shared engine and policy on it:
checks, outcome, next measurement and JSON.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hdsim
from hdsim.errors import InputError
from hdsim.identification.engine import Candidate, Step
from hdsim.identification.policy import Thresholds
from hdsim.identification.test_kinds import (FamilyKnowledge, TestKind, register_test_kind, test_kind,
                                             unregister_test_kind)
from hdsim.io.measurement import make_measurement


class Cubic(FamilyKnowledge):
    separated_by = {"drift": "the same curve loaded twice: a drift moves on in time, hardening repeats"}


class Drift(FamilyKnowledge):
    pass


COLUMNS = {"cubic": lambda m: np.asarray(m.torque) ** 3, "drift": lambda m: np.asarray(m.time)}


class LinearFit:
    """Least squares of the angle on the base columns and the named families' columns."""

    def __init__(self, meas, families, rows=None):
        rows = np.ones(len(meas), bool) if rows is None else rows
        T = np.asarray(meas.torque)
        X = np.column_stack([np.ones_like(T), T] + [COLUMNS[f](meas) for f in families])
        X = X / np.max(np.abs(X), axis=0)
        coef, *_ = np.linalg.lstsq(X[rows], np.asarray(meas.angle)[rows], rcond=None)
        self.families, self.rows, self.n_params = list(families), rows, X.shape[1]
        self.residual = np.asarray(meas.angle) - X @ coef
        self.rss = float(np.sum(self.residual[rows] ** 2))
        self.rmse_rad = math.sqrt(self.rss / rows.sum())

    def holdout_rss(self):
        return float(np.sum(self.residual[~self.rows] ** 2))


class CurveSession:
    one_rate, fold_rule, passes = False, "first and second half in time", 0

    def __init__(self, kind, meas, chosen):
        self.kind, self.measurement, self.chosen = kind, meas, dict(chosen)
        n = len(meas)
        self.masks = [np.arange(n) < n // 2, np.arange(n) >= n // 2]

    def _fits(self, families):
        return LinearFit(self.measurement, families), [LinearFit(self.measurement, families, m) for m in self.masks]

    def baseline(self):
        fit, folds = self._fits(list(self.chosen))
        return Step(list(self.chosen), fit, folds)

    def entry_forms(self, family):
        return (family,)

    def other_forms(self, current, done):
        return []

    def try_models(self, step, trials, residual):
        out = []
        for family, effect, structure in trials:
            fit, folds = self._fits(list(structure))
            n = len(self.measurement)
            score = n * math.log(fit.rss / step.fit.rss) + (fit.n_params - step.fit.n_params) * math.log(n)
            gains = [1.0 - math.sqrt(f.holdout_rss() / b.holdout_rss()) for f, b in zip(folds, step.fold_fits)]
            ok = score < self.kind.thresholds.score and min(gains) >= self.kind.thresholds.holdout_gain
            out.append(Candidate(family, effect, fit, folds, score=score, n_eff=float(n), holdout_gain=gains,
                                 accepted=ok, reason="passes" if ok else "too little",
                                 figures={"rmse_rad": fit.rmse_rad}))
        return out

    def confidence(self, steps):
        return {}

    def findings(self, step, whiteness):
        return []


class CurveTest(TestKind):
    name = "curve_plugin_test"
    thresholds = Thresholds(score=-10.0, holdout_gain=0.05)
    columns = ("time_s", "torque_Nm", "angle_rad")

    def families(self):
        return {"cubic": Cubic, "drift": Drift}

    def parse_effects(self, effects):
        return {f: f for f in (effects or [])}

    def session(self, meas, chosen, *, unit=None, candidates=None, max_steps=None):
        return CurveSession(self, meas, chosen)

    def fit_errors(self, fit):
        return {"rmse_rad": fit.rmse_rad}


@pytest.fixture
def curve_kind():
    kind = register_test_kind(CurveTest())
    yield kind
    unregister_test_kind(kind.name)


def _record(cubic: float, drift: float, seed: int = 0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 40.0, 2000)
    T = 80.0 * np.sin(2 * np.pi * t / 10.0)
    angle = T / 3e4 + cubic * (T / 80.0) ** 3 + drift * t + rng.normal(0.0, 2e-6, t.size)
    return make_measurement("curve_plugin_test", t, T, angle)


def test_a_kind_from_a_test_file_is_diagnosed_end_to_end(curve_kind):
    assert test_kind("curve_plugin_test") is curve_kind
    result = hdsim.diagnose(_record(cubic=2e-4, drift=0.0), effects=None)
    assert result.added == ["cubic"] and result.outcome == "found" and result.next_measurement == ""
    assert [c.family for c in result.ranking][0] == "cubic"
    j = result.to_json()
    assert j["test"] == "curve_plugin_test" and j["final"]["effects"] == ["cubic"]
    assert j["final"]["rmse_rad"] < 0.2 * j["baseline"]["rmse_rad"]
    assert j["outcome"] == "found" and isinstance(j["checks"], list) and j["data"]["rows"] == 2000


def test_a_plugin_kind_finds_nothing_in_a_plain_record_and_both_when_both_hide(curve_kind):
    plain = hdsim.diagnose(_record(cubic=0.0, drift=0.0, seed=1))
    assert plain.added == [] and plain.outcome == "nothing_missing"
    both = hdsim.diagnose(_record(cubic=2e-4, drift=3e-6, seed=2))
    assert sorted(both.added) == ["cubic", "drift"] and both.outcome == "found"


def test_an_unregistered_kind_is_refused_in_one_line(curve_kind):
    unregister_test_kind(curve_kind.name)
    with pytest.raises(InputError, match="curve_plugin"):
        _record(0.0, 0.0)
    register_test_kind(curve_kind)
