"""Run a scenario on a model: build the bench system, integrate, compute metrics."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hdsim import __version__
from hdsim.simulation.path import locked_wave_generator
from hdsim.errors import InputError, unknown_name
from hdsim.scenarios.locked_metrics import METRIC_GROUPS, locked_metrics
from hdsim.model.drive import HarmonicDrive
from hdsim.scenarios.scenario import Scenario
from hdsim.simulation.solver import SimulationResult, SolverOptions, integrate


@dataclass
class Run:
    """A finished scenario: the time series, the metrics and what produced them."""

    model: HarmonicDrive
    scenario: Scenario
    result: SimulationResult
    metrics: dict[str, np.ndarray]

    def metric(self, name: str, sample: int = 0) -> float:
        """One metric of one sample of the batch, as a float (units in its name)."""
        return float(np.asarray(self.metrics[name]).reshape(-1)[sample])


def breakpoints(model: HarmonicDrive):
    """(T1, T2) of the unit: catalog values if known, else the hardening law's."""
    catalog = model.provenance.get("catalog")
    if catalog:
        return catalog["T1"], catalog["T2"]
    hardening = model.hardening
    if hasattr(hardening, "T1"):
        return hardening.T1, hardening.T2
    raise InputError("stiffness metrics need breakpoints T1, T2: use a catalog unit or "
                     "a three_segment hardening effect")


def solver_options(scenario: Scenario, base: SolverOptions | None = None) -> SolverOptions:
    """Solver options with the scenario's ``[solver]`` table applied."""
    options = base or SolverOptions()
    solver = scenario.data.get("solver", {})
    return options.replace(**solver) if solver else options


def run_scenario(model: HarmonicDrive, scenario: Scenario, *, samples_per_segment: int | None = None,
                 options: SolverOptions | None = None) -> Run:
    """Simulate ``scenario`` on ``model`` (single or batch) and compute its metrics."""
    runner = RUNNERS[scenario.setup]
    run = runner(model, scenario, samples_per_segment=samples_per_segment, options=options)
    run.result.metadata.update(unit=model.name, scenario=scenario.name, hdsim_version=__version__)
    return run


def _run_locked(model: HarmonicDrive, scenario: Scenario, *, samples_per_segment: int | None = None,
                options: SolverOptions | None = None) -> Run:
    for name in scenario.metrics:
        if name not in METRIC_GROUPS:
            raise unknown_name(f"metric in scenario {scenario.name}", name, METRIC_GROUPS)
    n = samples_per_segment or scenario.samples_per_segment
    rated = model.drive.rated_torque
    system = locked_wave_generator(model, scenario.torque_profile(rated))
    t_eval = scenario.sample_times(n)
    result = integrate(system, (t_eval[0], t_eval[-1]), t_eval, solver_options(scenario, options))
    T1, T2 = breakpoints(model) if "stiffness" in scenario.metrics else (np.nan, np.nan)
    metrics = locked_metrics(scenario.metrics, result.signals["torque_Nm"], result.signals["twist_rad"],
                             scenario.levels(), n, T1, T2, rated)
    return Run(model, scenario, result, metrics)


def _run_driven(model, scenario, **kw) -> Run:
    from hdsim.simulation.driven import run_driven  # imported on use: hdsim.simulation.driven imports this module

    return run_driven(model, scenario, **kw)


#: one runner per bench set-up (hdsim.scenarios.scenario.SETUP_SCHEMAS lists their tables)
RUNNERS = {"locked_wave_generator": _run_locked, "driven_wave_generator": _run_driven}
