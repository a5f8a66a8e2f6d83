"""Evaluate a simulator metric for many parameter sets at once (the study interface).

``model_function(unit, names, output)`` returns a picklable callable ``f(X)`` that
maps a matrix of parameter rows ``(n, d)`` to the metric ``(n,)``: the rows become
one *batch* model (array-valued parameters) integrated in a single ``solve_ivp``
call, so the Python and solver overhead is paid once per chunk, not per row.
Rows whose geometry is impossible, or on which the solver fails, come back NaN;
the sensitivity layer then drops their block and names them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hdsim.model.catalog import load_unit
from hdsim.errors import InputError, SolverError, unknown_name
from hdsim.model.geometry import FlexsplineGeometry
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario
from hdsim.simulation.solver import SolverOptions

#: which built-in scenario produces each metric
METRIC_SCENARIOS = {
    "lost_motion_arcmin": "lost_motion",
    "torsion_at_rated_arcmin": "stiffness", "torsion_at_rated_tip_arcmin": "stiffness",
    "hysteresis_loss_arcmin": "stiffness", "lost_motion_centre_line_arcmin": "stiffness",
    "K1_Nm_per_rad": "stiffness", "K2_Nm_per_rad": "stiffness", "K3_Nm_per_rad": "stiffness",
    "transmission_accuracy_arcsec": "kinematic_error", "lost_motion_on_reversal_arcsec": "kinematic_error",
}

#: metrics need only the turning points and branch samples, so a coarse output grid is
#: enough; rtol 1e-4 moves lost motion by < 1e-4 relative against rtol 1e-6
#: (tests/test_batch.py) and saves a quarter of the steps of 1e-5
STUDY_SOLVER = SolverOptions(rtol=1e-4, atol_scale=1e-4)
STUDY_SAMPLES = {"lost_motion": 1, "stiffness": 40}


def resolve_names(unit: str, names) -> list[str]:
    """Dotted parameter names; a bare flexspline dimension (``h_pz``) is accepted too."""
    known = load_unit(unit).params()
    design = set(FlexsplineGeometry.design_names())
    resolved = []
    for name in names:
        if name in known:
            resolved.append(name)
        elif name in design or f"flexspline.{name}" in known:
            resolved.append(f"flexspline.{name}")
        else:
            raise unknown_name("parameter", name, list(known) + sorted(design))
    return resolved


def nominal_values(unit: str, names) -> dict[str, float]:
    """Nominal value of each parameter of the built-in ``unit`` (keys as given)."""
    params = load_unit(unit).params()
    return {name: float(params[dotted]) for name, dotted in zip(names, resolve_names(unit, names))}


@dataclass(frozen=True)
class ScenarioMetric:
    """Picklable ``f(X) -> y``: one metric of one scenario on one unit, rows batched."""

    unit: str
    names: tuple[str, ...]
    output: str
    scenario: str
    #: rows per task the study engine should send (larger chunks amortise overhead)
    chunksize: int = 1024

    def __call__(self, X) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, dtype=float))
        y = np.full(len(X), np.nan)
        valid = self._valid_rows(X)
        if valid.any():
            y[valid] = self._evaluate(X[valid])
        return y

    def _model(self, X):
        return load_unit(self.unit).with_updates({n: X[:, j] for j, n in enumerate(self.names)})

    def _valid(self, row) -> bool:
        try:
            self._model(row[None, :])
        except InputError:
            return False
        return True

    def _valid_rows(self, X) -> np.ndarray:
        """Rows whose parameters build a model. The bound and geometry checks refuse a
        batch when any row fails them, so one batch build clears a whole good chunk;
        only a refused chunk is checked row by row."""
        try:
            self._model(X)
        except InputError:
            return np.array([self._valid(row) for row in X], dtype=bool)
        return np.ones(len(X), dtype=bool)

    def _evaluate(self, X) -> np.ndarray:
        scenario = load_scenario(builtin_scenario_path(self.scenario))
        try:
            run = run_scenario(self._model(X), scenario, options=STUDY_SOLVER,
                               samples_per_segment=STUDY_SAMPLES.get(self.scenario))
            return np.asarray(run.metrics[self.output], dtype=float).reshape(-1)
        except SolverError:
            if len(X) == 1:
                return np.array([np.nan])
            # isolate the failing rows by halving; the others keep their values
            half = len(X) // 2
            return np.concatenate([self._evaluate(X[:half]), self._evaluate(X[half:])])


@dataclass(frozen=True)
class ScenarioSeries:
    """Picklable ``f(X) -> Y (rows, T)``: one signal of a scenario on its output grid.

    For time-resolved indices (`hdsim.sensitivity.resolved.resolved_indices`);
    ``times()`` gives the grid [s].
    """

    unit: str
    names: tuple[str, ...]
    signal: str
    scenario: str
    samples_per_segment: int = 20
    chunksize: int = 1024

    def _scenario(self):
        return load_scenario(builtin_scenario_path(self.scenario))

    def times(self) -> np.ndarray:
        return self._scenario().sample_times(self.samples_per_segment)

    def __call__(self, X) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, dtype=float))
        metric = ScenarioMetric(self.unit, self.names, "", self.scenario)
        scenario = self._scenario()
        Y = np.full((len(X), scenario.sample_times(self.samples_per_segment).size), np.nan)
        valid = metric._valid_rows(X)
        if valid.any():
            run = run_scenario(metric._model(X[valid]), scenario, options=STUDY_SOLVER,
                               samples_per_segment=self.samples_per_segment)
            Y[valid] = run.result.signals[self.signal]
        return Y


def series_function(unit: str, names, signal: str, scenario: str) -> ScenarioSeries:
    """The resolved-study callable for ``signal`` (e.g. ``twist_rad``) of ``scenario``."""
    builtin_scenario_path(scenario)
    return ScenarioSeries(unit, tuple(resolve_names(unit, names)), signal, scenario)


def model_function(unit: str, names, output: str, scenario: str | None = None) -> ScenarioMetric:
    """The study callable for ``output`` of ``scenario`` (default: the scenario producing it)."""
    if scenario is None:
        if output not in METRIC_SCENARIOS:
            raise unknown_name("output metric", output, METRIC_SCENARIOS)
        scenario = METRIC_SCENARIOS[output]
    builtin_scenario_path(scenario)  # fails early with a clear message
    load_unit(unit)
    return ScenarioMetric(unit, tuple(resolve_names(unit, names)), output, scenario)
