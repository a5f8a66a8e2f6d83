"""Resolve what a study evaluates: a simulator unit, a closed form, or a user callable.

Each resolver returns ``(func, problem, output, model_description, analytic)``;
``model_description`` is stored in the study file so ``--resume`` refuses to
continue a study with another model.
"""

from __future__ import annotations

import importlib

import numpy as np

from hdsim.errors import InputError
from hdsim.sensitivity.functions import get_function
from hdsim.sensitivity.metric_scenarios import FIRST_DEFAULTS, METRIC_SCENARIOS
from hdsim.sensitivity.problem import CLI_WORDING, build_problem


def from_unit(unit, names, output, scenario=None, range_frac=None, bounds=None, dists=None, wording=None,
              evaluator="auto"):
    """Study of a drive through the simulator: parameters by dotted name, ``output`` a metric.

    Parameters
    ----------
    unit : HarmonicDrive, str or None
        Any single model (built-in, modified, fitted) or a built-in unit name or the path
        of a drive file (`hdsim.model.catalog.load_unit`).
    names : list of str
        Parameters to vary (``h_pz`` or dotted, ``friction.slip_torque``).
    output : str
        The metric, e.g. ``lost_motion_arcmin``.
    scenario : Scenario, str or os.PathLike, optional
        A scenario, a built-in scenario name or a scenario file; default the built-in
        scenario producing ``output``.
    range_frac, bounds, dists, wording
        As `hdsim.sensitivity.problem.build_problem` (``bounds`` typed, ``(low, high)``;
        ``wording`` default the command line's); nominal values come from the drive.
    evaluator : {"auto", "dynamic", "quasistatic"}
        Which evaluator the rows run on (`hdsim.scenarios.evaluator`).

    Returns
    -------
    tuple
        ``(func, problem, output, model, None)``; ``model`` is
        ``{"unit", "output", "scenario", "fingerprint", "evaluator"}``: the drive's name,
        the scenario's name (None for the default one of the outputs that had one first,
        `_recorded_scenario`),
        `hdsim.sensitivity.scenario_outputs.drive_fingerprint` of drive, scenario and
        evaluator, so resuming a study with another drive, scenario or evaluator is
        refused, and the evaluator that runs (``func.choice`` says why).

    Notes
    -----
    The simulator interface (`hdsim.sensitivity.scenario_outputs`) is imported here,
    not at the top: analytic-function studies do not need scipy's solvers or the catalog.
    """
    wording = wording or CLI_WORDING
    if not output:
        raise InputError(f"a study of a drive needs the metric it studies, e.g. "
                         f"{wording.output_of.format(name='lost_motion_arcmin')}")
    batch = _batch()
    drive = batch.as_drive(unit)
    dotted = batch.resolve_names(drive, names)  # once, first: an unknown name is refused before anything else
    # nominal values only matter for --range
    nominal = {} if range_frac is None else batch.nominal_values(drive, list(names))
    bounds, dists = (_keyed_as_names(batch, drive, dict(zip(dotted, names)), given, option)
                     for given, option in ((bounds, wording.bounds), (dists, wording.dists)))
    problem = build_problem(names, nominal, range_frac, bounds, dists, wording)
    spans, start = _spans_and_start(drive, problem, dotted)
    _refuse_unbuildable_ends(drive, problem, dotted, spans, start)
    # a built-in name travels as a name; anything else (a drive file too) as the model read
    # here, so the workers neither re-read a file nor depend on the working folder
    by_name = isinstance(unit, str) and "drive_file" not in drive.provenance
    func = batch.model_function(unit if by_name else drive, list(names), output, scenario, evaluator, wording,
                                range_ends=_range_end_drives(drive, problem, dotted, spans, start))
    model = {"unit": drive.name, "output": output, "scenario": _recorded_scenario(output, scenario, func.scenario),
             "fingerprint": batch.drive_fingerprint(drive, func.scenario, func.evaluator),
             "evaluator": func.evaluator}
    return func, problem, output, model, None


def _keyed_as_names(batch, drive, as_given, options, option: str):
    """``options`` (bounds or distributions by parameter, given as ``option``) keyed as the
    study's names are (``as_given``: each by its dotted name): ``h_c`` and ``flexspline.h_c``
    are one parameter, so either may name it in either place, but not both (the last had
    won without a word). A key that is no parameter of the drive stays as written, for
    `build_problem` to name."""
    out, written = {}, {}
    for key, value in (options or {}).items():
        given = key
        try:
            key = as_given.get(batch.resolve_names(drive, [key])[0], key)
        except InputError:
            pass
        if key in out:
            raise InputError(f"{option} names {key} twice (as {written[key]} and {given}); give it once")
        out[key], written[key] = value, given
    return out


def _recorded_scenario(output: str, given, resolved) -> str | None:
    """The scenario a study file records: its name, the same whether the default was named
    or not (a study started without ``scenario`` and resumed with its default named was
    refused as another). The outputs that had a default first record it as None, as their
    files always have (`hdsim.sensitivity.metric_scenarios.FIRST_DEFAULTS`)."""
    if output in FIRST_DEFAULTS and _is_default_scenario(output, given, resolved):
        return None
    return resolved.name


def _is_default_scenario(output: str, given, resolved) -> bool:
    """Whether the study runs the built-in scenario of ``output``, named or not."""
    if given is None:
        return True
    from hdsim.scenarios.scenario import load_scenario

    default = METRIC_SCENARIOS.get(output)
    return default is not None and load_scenario(default).data == resolved.data


def _refuse_unbuildable_ends(drive, problem, dotted: list, spans: list, start: list) -> None:
    """Refuse a uniform range whose end no row of the study can build: every row with that
    end, the other parameters anywhere in their own ranges (`_trial_rows`), is a drive the
    model refuses. A range reaching a negative wall thickness had left three blocks in four
    of the design to fail, and the indices described the corner that ran, not the range
    asked for. The others are not held at their nominal values: a nominal outside its own
    studied range (an undercut range below the nominal undercut) is no row of the study,
    and had refused a box whose every corner builds. (A combination of ends may still fail;
    those blocks are counted.) ``spans`` and ``start``: `_spans_and_start`."""
    for i, (name, (low, high), dist) in enumerate(zip(problem.names, problem.bounds, problem.dists)):
        if dist != "unif":
            continue
        for value in (low, high):
            reason = _refused_everywhere(drive, dotted, _trial_rows(spans, start, i, value))
            if reason is not None:
                raise InputError(f"the range of {name} reaches {value:g}, a drive the model refuses: {reason}")


def _range_end_drives(drive, problem, dotted: list, spans: list, start: list):
    """(name, value, drive) at each end of each input's span, the others at their nominal
    values brought into their own ranges (the first of `_trial_rows`); an end the model
    refuses there is passed over (`_refuse_unbuildable_ends` has judged it)."""
    for i, name in enumerate(problem.names):
        for value in spans[i]:
            row = next(_trial_rows(spans, start, i, value))
            try:
                yield name, value, drive.with_updates(dict(zip(dotted, row))).require_consistent()
            except InputError:
                continue


def _spans_and_start(drive, problem, dotted: list) -> tuple[list, list]:
    """Each input's span (`_span`) and its nominal value brought into it."""
    spans = [_span(low, high, dist) for (low, high), dist in zip(problem.bounds, problem.dists)]
    nominal = _batch().nominal_values(drive, dotted)
    return spans, [min(max(nominal[key], lo), hi) for key, (lo, hi) in zip(dotted, spans)]


#: rows tried for one range end at most: every corner of the other ranges up to ten
#: parameters, a fixed sample of the corners past that (each try is a fraction of a millisecond)
MAX_TRIAL_ROWS = 512

#: a normal input's reach, in standard deviations either side of its mean, for the rows tried
NORMAL_REACH = 3.0


def _span(a: float, b: float, dist: str) -> tuple[float, float]:
    """The values an input's rows take: its bounds, or a normal's mean ± `NORMAL_REACH` SD."""
    return (a - NORMAL_REACH * b, a + NORMAL_REACH * b) if dist == "norm" else (a, b)


def _trial_rows(spans, start, i: int, value: float):
    """Rows with input ``i`` at ``value``: first ``start`` (each nominal value brought into its
    own range), then the corners of the other inputs' ranges. A model's bounds and geometry
    rules compare parameters with limits and with each other, so a range end that builds with
    any of the others' values builds at one of their corners."""
    yield [*start[:i], value, *start[i + 1:]]
    others = [j for j in range(len(spans)) if j != i]
    if 2 ** len(others) <= MAX_TRIAL_ROWS:
        corners = ((c >> np.arange(len(others))) & 1 for c in range(2 ** len(others)))
    else:
        corners = np.random.default_rng(0).integers(0, 2, size=(MAX_TRIAL_ROWS, len(others)))
    for ends in corners:
        row = list(start)
        row[i] = value
        for j, end in zip(others, ends):
            row[j] = spans[j][int(end)]
        yield row


def _refused_everywhere(drive, dotted: list, rows) -> str | None:
    """Why the model refuses the first of ``rows``, if it refuses every one; None once one builds."""
    refusal, first = _batch().refusal, None
    for row in rows:
        reason = refusal(drive, dotted, row)
        if reason is None:
            return None
        first = first or reason
    return first


def from_function(name, output=None):
    """A closed-form test function and its own input distributions."""
    f = get_function(name)
    return f, f.problem(), output or name, {"function": name}, f.analytic()


def from_import(spec, names, output=None, range_frac=None, bounds=None, dists=None):
    """``MODULE:ATTR`` naming a picklable ``f(X) -> y`` (a class is instantiated).

    Its inputs come from ``--params`` with ``--bounds`` (or ``--dist norm:MEAN:SD``);
    a ``nominal`` dict attribute on the callable enables ``--range``.
    """
    module_name, _, attr = spec.partition(":")
    if not module_name or not attr:
        raise InputError(f"--model expects MODULE:CALLABLE, got '{spec}'")
    try:
        obj = getattr(importlib.import_module(module_name), attr)
    except (ImportError, AttributeError) as exc:
        raise InputError(f"--model {spec}: {exc}") from None
    func = obj() if isinstance(obj, type) else obj
    if not callable(func):
        raise InputError(f"--model {spec} is not callable")
    if not names:
        raise InputError("--model needs --params NAME,NAME,...")
    nominal = dict(getattr(func, "nominal", {}) or {})
    problem = build_problem(names, nominal, range_frac, bounds, dists)
    return func, problem, output or attr, {"model": spec, "output": output}, None


def _batch():
    """The simulator's batch interface, imported only for --unit studies (it loads scipy
    solvers and the unit catalog, which analytic-function studies do not need)."""
    return importlib.import_module("hdsim.sensitivity.scenario_outputs")
