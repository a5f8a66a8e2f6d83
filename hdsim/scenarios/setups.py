"""What a bench set-up brings: `Setup`, one per bench.

A scenario file names its bench with ``setup = "..."``. Each bench module defines one
`Setup` (`hdsim.scenarios.locked.LOCKED`, `hdsim.scenarios.driven.DRIVEN`) and
`hdsim.scenarios.registry` registers them once: `hdsim.scenarios.scenario` validates
a scenario's tables against it and `hdsim.scenarios.run.run_scenario` runs it. The
figures of a bench belong to the plotting layer, not here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class Setup:
    """A bench set-up: its scenario tables, its runner and the metric groups it reports.

    Attributes
    ----------
    name : str
        The ``setup`` value of a scenario file.
    schema : dict
        Tables this bench adds to the common scenario schema: ``{table: {key: type}}``
        with ``float``, ``int``, ``str`` or ``list`` (docs/tutorial-first-simulation.md,
        docs/tutorial-kinematic-error.md).
    required : dict
        ``{table: (key, ...)}`` that every scenario of this bench must set.
    runner : callable
        ``runner(model, scenario, *, samples_per_segment=None, options=None)`` returns
        ``(scenario, result, metrics)``: the scenario as run (sampling overrides
        applied), the `hdsim.simulation.solver.SimulationResult` and the metrics
        ``{name: array of shape (M,)}``. ``options`` already hold the scenario's
        ``[solver]`` table (`hdsim.scenarios.run.solver_options`).
    metrics : tuple of str
        The metric groups a scenario of this bench may list.
    check : callable, optional
        ``check(data, source)`` raises `hdsim.errors.InputError` on values out of range
        after the types are checked.
    quasistatic_runner : callable, optional
        A runner with the signature of ``runner`` that drops the output inertia; None
        when the bench has no quasi-static evaluator (`hdsim.scenarios.evaluator`).
    quasistatic_criterion : callable, optional
        ``criterion(model, scenario) -> (holds, reason, figures)``: whether the
        quasi-static runner reproduces the dynamic one on this scenario, one sentence
        why, and the numbers compared.
    output_samples : callable, optional
        ``output_samples(model, scenario) -> int``: the samples of one parameter set's run,
        for a bench whose runs are long (a study then sends fewer rows per task, so its
        memory stays bounded); None for a bench whose runs are short.
    """

    name: str
    schema: dict
    required: dict
    runner: Callable
    metrics: tuple[str, ...]
    check: Callable | None = None
    quasistatic_runner: Callable | None = None
    quasistatic_criterion: Callable | None = None
    output_samples: Callable | None = None
