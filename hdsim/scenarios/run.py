"""Run a scenario on a model, and keep the finished run: `Run`, `run_scenario`, `read_run`.

`run_scenario` finds the scenario's bench in `hdsim.scenarios.registry`, checks the
metric groups it asks for, and calls the bench's runner; `Run.save` and `read_run`
write and read the run file (`hdsim.scenarios.results`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hdsim._version import __version__
from hdsim.errors import unknown_name
from hdsim.model.catalog import as_drive
from hdsim.model.drive import HarmonicDrive
from hdsim.scenarios.evaluator import choose_evaluator
from hdsim.scenarios.registry import get_setup
from hdsim.scenarios.results import read_run_file, write_run_file
from hdsim.scenarios.scenario import Scenario, load_scenario
from hdsim.simulation.solver import SimulationResult, SolverOptions


@dataclass
class Run:
    """A finished scenario: the time series, the metrics and what produced them.

    Attributes
    ----------
    model : HarmonicDrive
        The model (single or batch of M).
    scenario : Scenario
        The scenario as run.
    result : SimulationResult
        Times [s], states and signals of shape (M, nt), solver statistics, metadata.
    metrics : dict
        ``{name: array of shape (M,)}`` in the units their names carry.
    """

    model: HarmonicDrive
    scenario: Scenario
    result: SimulationResult
    metrics: dict[str, np.ndarray]

    def metric(self, name: str, sample: int = 0) -> float:
        """One metric of one sample of the batch, as a float (units in its name)."""
        return float(np.asarray(self.metrics[name]).reshape(-1)[sample])

    def save(self, path) -> Path:
        """Write this run to an HDF5 run file, atomically.

        Parameters
        ----------
        path : str or os.PathLike
            Target file (layout in `hdsim.scenarios.results`); replaced if it exists.

        Returns
        -------
        pathlib.Path
            The written file; `read_run` reads it back.
        """
        return write_run_file(path, self)


def read_run(path) -> Run:
    """Read a run file written by `Run.save`.

    Parameters
    ----------
    path : str or os.PathLike
        The run file.

    Returns
    -------
    Run
        The model (the built-in unit of the stored name with the stored parameters and
        effects), the scenario, the result and the metrics, as saved.

    Raises
    ------
    InputError
        If the file is not a readable run file.
    """
    return Run(*read_run_file(path))


def solver_options(scenario: Scenario, base: SolverOptions | None = None) -> SolverOptions:
    """Solver options with the scenario's ``[solver]`` table applied.

    Parameters
    ----------
    scenario : Scenario
        The scenario; its ``[solver]`` table may set ``method``, ``rtol``, ``atol_scale``
        and ``max_step`` [s].
    base : SolverOptions, optional
        Options to start from (default `SolverOptions`).
    """
    options = base or SolverOptions()
    solver = scenario.data.get("solver", {})
    return options.replace(**solver) if solver else options


def run_scenario(model: HarmonicDrive | str | os.PathLike, scenario, *, samples_per_segment: int | None = None,
                 options: SolverOptions | None = None, evaluator: str = "dynamic") -> Run:
    """Simulate a scenario on a model (single or batch) and compute its metrics.

    Parameters
    ----------
    model : HarmonicDrive, str or os.PathLike
        A single model or a batch of M, or a built-in unit's name or a drive file's path
        (`hdsim.model.catalog.load_unit`), as `hdsim.sobol` takes.
    scenario : Scenario, str or os.PathLike
        A scenario, a scenario file or the name of a built-in scenario (`load_scenario`).
    samples_per_segment : int, optional
        Output sampling override: samples per ramp (locked bench) or per WG revolution
        (driven bench).
    options : SolverOptions, optional
        Solver options; the scenario's ``[solver]`` table is applied on top.
    evaluator : {"dynamic", "quasistatic", "auto"}
        The dynamic model (the reference), the quasi-static evaluator of a bench that
        has one, or the latter where the bench's criterion holds
        (`hdsim.scenarios.evaluator`).

    Returns
    -------
    Run
        The run; ``result.metadata`` holds ``unit``, ``scenario``, ``hdsim_version`` and
        ``evaluator`` (`EvaluatorChoice.as_dict`: what was asked, what ran and why).

    Raises
    ------
    InputError
        On an unknown unit, a model whose values contradict each other (a three-segment
        law's T1 at or above T2, in any sample of a batch: `HarmonicDrive.require_consistent`,
        the check ``--set`` makes), a bad scenario, a metric group its bench does not
        report, or an evaluator the bench does not have.
    """
    model = as_drive(model).require_consistent()
    scenario = load_scenario(scenario)
    setup = get_setup(scenario.setup)
    for name in scenario.metrics:
        if name not in setup.metrics:
            raise unknown_name(f"metric in scenario {scenario.name}", name, setup.metrics)
    choice = choose_evaluator(setup, model, scenario, evaluator)
    runner = setup.quasistatic_runner if choice.chosen == "quasistatic" else setup.runner
    scenario, result, metrics = runner(model, scenario, samples_per_segment=samples_per_segment,
                                       options=solver_options(scenario, options))
    result.metadata.update(unit=model.name, scenario=scenario.name, hdsim_version=__version__,
                           evaluator=choice.as_dict())
    return Run(model, scenario, result, metrics)
