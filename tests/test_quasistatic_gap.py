"""A quasi-static study's resolution is its distance from an accurate ``solve_ivp`` run
(docs/sensitivity.md §6, §11), not from one at the study's loose tolerance.

On a drive fitted to a stiffness record (Dahl friction sticking at 6600 times the spring's
stiffness, no damping) the lost motion was 1.0055 arcmin through ``solve_ivp`` at rtol 1e-4,
1.2175 at 1e-6 and 1.21747 quasi-static: the study measured a "gap" of 0.21 arcmin and
flagged itself for an output spread of 0.028. A stand-in for ``run_scenario`` gives those
numbers here, so the test takes milliseconds instead of minutes.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from hdsim.model.catalog import load_unit
from hdsim.scenarios.run import solver_options
from hdsim.scenarios.scenario import load_scenario
from hdsim.sensitivity import scenario_outputs
from hdsim.sensitivity.checks import resolution_flags

OUTPUT = "lost_motion_arcmin"


def _runs(monkeypatch, dynamic):
    """Replace the runs of `scenario_outputs` by ``dynamic(rtol)`` (1.21747 quasi-static);
    returns the effective tolerances of the dynamic runs asked for."""
    asked = []

    def run(model, scenario, *, samples_per_segment=None, options=None, evaluator="dynamic"):
        rtol = solver_options(scenario, options).rtol
        if evaluator != "quasistatic":
            asked.append(rtol)
        value = 1.21747 if evaluator == "quasistatic" else dynamic(rtol)
        return SimpleNamespace(metrics={OUTPUT: np.array([value])})

    monkeypatch.setattr(scenario_outputs, "run_scenario", run)
    return asked


def test_the_gap_is_measured_against_a_converged_reference_not_the_studys_tolerance(monkeypatch):
    asked = _runs(monkeypatch, lambda rtol: 1.0055 if rtol >= 1e-5 else 1.21750)
    gap = scenario_outputs._quasistatic_gap(load_unit("CSG-25-100"), load_scenario("lost_motion"), OUTPUT)
    assert gap == pytest.approx(3e-5, rel=1e-3)  # not 0.212
    assert asked == [1e-6]  # run_scenario's own tolerance
    y = 1.2175 + 0.028 * np.random.default_rng(0).standard_normal(256)
    assert not resolution_flags(y, gap)  # the study of the report is not flagged


def test_a_scenario_with_its_own_tolerances_is_referenced_at_them(monkeypatch):
    asked = _runs(monkeypatch, lambda rtol: 42.5)
    scenario = load_scenario("lost_motion").with_updates({"solver.rtol": 1e-5, "solver.atol_scale": 1e-3})
    scenario_outputs._quasistatic_gap(load_unit("CSG-25-100"), scenario, OUTPUT)
    assert asked == [1e-5]
