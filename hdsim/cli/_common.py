"""Helpers shared by the simulation verbs: ``--set`` parsing, running, writing."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from hdsim.atomic import atomic_group
from hdsim.cli._guards import require_finite
from hdsim.errors import InputError, unknown_name
from hdsim.model.drive import HarmonicDrive
from hdsim.model.effects import FAMILIES, NO_EFFECT
from hdsim.plotting import save_figure

if TYPE_CHECKING:  # the scenarios pull in the dynamic solvers, which `fit` and `diagnose` never use
    from hdsim.scenarios.scenario import Scenario


def add_set_argument(parser, help: str | None = None) -> None:
    """Add the repeatable ``--set NAME=VALUE`` option to a verb's parser (``help`` for a
    verb that runs no scenario)."""
    parser.add_argument(
        "--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
        help=help or "change a parameter (SI units), e.g. flexspline.h_c=0.6e-3; switch an effect off "
                     "with FAMILY=none, e.g. backlash=none; change the scenario with scenario.load.rate=0.1")


def parse_sets(items) -> dict[str, str]:
    """``["NAME=VALUE", ...]`` as ``{NAME: VALUE}`` (strings); InputError on a malformed item
    or a name given twice (`hdsim.sensitivity.problem.parse_assignments`)."""
    from hdsim.sensitivity.problem import parse_assignments

    return parse_assignments(items, "--set")


def _number(name, text) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"--set {name}: '{text}' is not a number") from None
    if not math.isfinite(value):
        raise InputError(f"--set {name}: value must be finite")
    return value


def apply_sets(model: HarmonicDrive, scenario: Scenario | None, sets: dict[str, str]):
    """The model and scenario with the ``--set`` changes applied; every name is checked first.

    Parameters
    ----------
    model : HarmonicDrive
        The unit.
    scenario : Scenario or None
        The scenario (None for a command that runs none: a ``scenario.`` name is refused).
    sets : dict
        ``{name: text}``: a dotted parameter (SI), an effect family set to ``none``, or
        ``scenario.TABLE.KEY``.

    Returns
    -------
    tuple
        (model, scenario).
    """
    scenario_updates, effect_switches, params = {}, {}, {}
    for name, text in sets.items():
        if name.startswith("scenario."):
            if scenario is None:
                raise InputError(f"--set {name}: this command runs no scenario")
            scenario_updates[name[len("scenario."):]] = text
        elif name in FAMILIES:
            if text != "none":
                raise InputError(f"--set {name}={text}: only 'none' can be set on a family from the "
                                 f"command line (switches the {name} effect off)")
            effect_switches[name] = NO_EFFECT[name]
    # the switches first, so that a parameter is set on the effect that runs: one of an effect
    # switched off had been set on the old effect, then dropped with it without a word
    model = model.with_effects(**effect_switches) if effect_switches else model
    known = model.params()
    for name, text in sets.items():
        if name.startswith("scenario.") or name in FAMILIES:
            continue
        family, _, rest = name.partition(".")
        if name not in known and family in effect_switches:
            raise InputError(f"--set {name}: the same command switches {family} to none, which has no "
                             f"parameter {rest}")
        if name not in known:
            raise unknown_name("parameter", name, list(known) + list(FAMILIES))
        params[name] = _number(name, text)
    scenario = scenario.with_updates(scenario_updates) if scenario_updates else scenario
    model = model.with_updates(params).require_consistent() if params else model
    return model, scenario


#: what to change when a run gives a non-finite metric (`hdsim.cli._guards.require_finite`)
NONFINITE_HINT = ("the values of the unit or the scenario are outside what the model can compute "
                  "(look at each --set and the scenario's load rate and amplitude)")


def metrics_as_floats(metrics: dict) -> dict[str, float]:
    """The first sample of each metric, as a float."""
    return {name: float(np.asarray(value).reshape(-1)[0]) for name, value in metrics.items()}


def finite_metrics(run) -> dict[str, float]:
    """The run's metrics as floats (`metrics_as_floats`); SolverError, one line naming each
    metric that is not finite, for a run that overflowed: it is no result to write or print."""
    metrics = metrics_as_floats(run.metrics)
    require_finite(metrics, f"the run of {run.scenario.name} on {run.model.name}", NONFINITE_HINT)
    return metrics


def print_metrics(title: str, metrics: dict[str, float], stream=None) -> None:
    """Print a title and one aligned ``name  value`` line per metric (on ``stream``, default
    the ``sys.stdout`` of the moment: a default bound at import would keep a stream that a
    caller has since replaced, or closed)."""
    stream = sys.stdout if stream is None else stream
    print(title, file=stream)
    width = max(len(k) for k in metrics) if metrics else 0
    for name, value in metrics.items():
        print(f"  {name:<{width}}  {value:.6g}", file=stream)


def _figures(setup: str) -> dict:
    """The figures a person looks at for a bench set-up (the set-ups are in
    `hdsim.scenarios.registry`): kind -> plot function; the file is ``SCENARIO_KIND.png``."""
    # matplotlib is imported when figures are drawn, not at the start-up of every verb (~0.3 s)
    from hdsim.plotting import driven as driven_plots, locked as locked_plots

    figures = {
        "locked_wave_generator": {"loop": locked_plots.plot_loop, "time": locked_plots.plot_time},
        "driven_wave_generator": {"deviation": driven_plots.plot_deviation, "time": driven_plots.plot_driven_time,
                                  "running_torque": driven_plots.plot_running_torque},
    }
    return figures[setup]


def _figure_name(scenario: Scenario, kind: str) -> str:
    return f"{scenario.name}_{kind}.png"


def output_names(scenario: Scenario, figures: bool = True) -> list[str]:
    """The names of the files `write_outputs` may write for a run of ``scenario`` (checked
    before the run: none of them may be a folder)."""
    names = [f"{scenario.name}.h5"]
    if figures:
        names += [_figure_name(scenario, kind) for kind in _figures(scenario.setup)]
    return names


def write_outputs(run, out_dir: Path, figures: bool = True) -> dict[str, str]:
    """Run file and figures for a finished run.

    Parameters
    ----------
    run : hdsim.scenarios.run.Run
        The finished run.
    out_dir : pathlib.Path
        Output folder, created if missing: ``SCENARIO.h5`` and ``SCENARIO_KIND.png``.
    figures : bool
        Draw the bench's figures.

    Raises
    ------
    hdsim.errors.SolverError
        A metric of the run is not finite; nothing is written.

    Returns
    -------
    dict
        ``result`` and ``KIND_figure`` → the path written (a kind with nothing to draw for
        this run is left out).
    """
    finite_metrics(run)  # a run that overflowed leaves no file behind, whoever writes it
    out_dir = Path(out_dir)
    with atomic_group():  # the result file and its figures appear together, or none does
        paths = {"result": str(run.save(out_dir / f"{run.scenario.name}.h5"))}
        if figures:
            for kind, draw in _figures(run.result.setup).items():
                figure = draw(run)
                if figure is None:  # a figure this run has nothing for (a sweep's, on another profile)
                    continue
                path = out_dir / _figure_name(run.scenario, kind)
                save_figure(figure, path)
                paths[f"{kind}_figure"] = str(path)
    return paths
