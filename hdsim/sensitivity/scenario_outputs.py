"""Evaluate a simulator metric for many parameter sets at once (the study interface).

``model_function(drive, names, output, scenario)`` returns a picklable callable
``f(X)`` that maps a matrix of parameter rows ``(n, d)`` to the metric ``(n,)``: the
rows become one *batch* model (array-valued parameters) integrated in a single
``solve_ivp`` call, so the Python and solver overhead is paid once per chunk, not per
row (under ``evaluator="auto"`` a scenario goes through its bench's quasi-static evaluator
instead where the bench's criterion holds: the locked bench's ±4 % lost-motion test,
`hdsim.scenarios.locked.quasistatic_criterion`, and the driven bench's kinematic-error
runs, `hdsim.simulation.driven_quasistatic.criterion`).
The drive is any `HarmonicDrive` (a built-in unit, a modified or a fitted one)
or the name of a built-in unit; the scenario is a built-in name, a scenario file or a
`Scenario`. Both travel to the workers inside the callable (they pickle). Rows whose
geometry is impossible, or on which the solver fails, come back NaN, with the reason
(`ScenarioMetric.explained`); the sensitivity layer then drops their block and names
them with it.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, fields, is_dataclass

import numpy as np

from hdsim.errors import InputError, SolverError, unknown_name
from hdsim.model.catalog import as_drive as catalog_drive
from hdsim.model.catalog import load_unit
from hdsim.model.drive import HarmonicDrive
from hdsim.model.geometry import FlexsplineGeometry
from hdsim.scenarios.evaluator import EvaluatorChoice, choose_evaluator
from hdsim.scenarios.registry import get_setup
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import Scenario, load_scenario
from hdsim.sensitivity.metric_scenarios import METRIC_SCENARIOS, default_scenario
from hdsim.sensitivity.problem import PYTHON_WORDING, Wording
from hdsim.simulation.solver import SolverOptions
from hdsim.typing import ArrayLike

#: metrics need only the turning points and branch samples, so a coarse output grid is
#: enough; rtol 1e-4 moves lost motion by < 1e-4 relative against rtol 1e-6
#: (tests/test_batch.py) and saves a quarter of the steps of 1e-5
STUDY_SOLVER = SolverOptions(rtol=1e-4, atol_scale=1e-4)
#: output samples per segment where a scenario's default is more than its metrics need;
#: the stiffness test keeps its own (400): its K1 and centre-line lost motion are read
#: between samples, and at 40 a study's K1 was 20 % below the one `hdsim simulate` reports
STUDY_SAMPLES = {"lost_motion": 1}

#: a task's run holds at most this many bytes per output sample and parameter set (the
#: signals, the solver's states and the intermediate arrays of the metrics; measured with
#: tracemalloc on the KE contract run: about 220 through solve_ivp, 110 quasi-static) …
BYTES_PER_SAMPLE_AND_ROW = 320
#: … and a task stays within this much: 120 rows of the driven contract run (26,000
#: samples). Not less: a batch through solve_ivp costs about the same for 8 rows as for
#: 60 (the steps are shared), so smaller tasks cost the dynamic evaluator per row
TASK_BYTES = 1e9


def as_drive(drive) -> HarmonicDrive:
    """The model to study: `hdsim.model.catalog.as_drive` (a `HarmonicDrive` as it is, a unit
    name or a drive file's path through `load_unit`), and None for the default unit."""
    return load_unit(None) if drive is None else catalog_drive(drive)


def drive_fingerprint(drive: HarmonicDrive, scenario: Scenario | None = None, evaluator: str = "dynamic") -> str:
    """A short hash of everything an evaluation depends on: parameters, effects, scenario.

    Two drives have the same fingerprint exactly when their names, effect classes and
    every field value agree (the ``provenance`` notes are left out); a study file keeps
    it so that resuming with another drive or scenario is refused.

    Parameters
    ----------
    drive : HarmonicDrive
        The model (single or batch).
    scenario : Scenario, optional
        Its table is hashed too.
    evaluator : str
        The evaluator the rows run on; a quasi-static study's fingerprint differs from a
        dynamic one's (their values agree within 1e-3, not to the last digit). The
        dynamic one hashes as before the evaluator existed.

    Returns
    -------
    str
        16 hexadecimal digits.
    """
    state = {"drive": _canonical(drive), "scenario": None if scenario is None else scenario.data}
    if evaluator != "dynamic":
        state["evaluator"] = evaluator
    text = json.dumps(state, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _canonical(value):
    """A JSON-able image of a parameter tree (class names included, provenance left out)."""
    if is_dataclass(value) and not isinstance(value, type):
        out = {"class": f"{type(value).__module__}.{type(value).__qualname__}"}
        out.update({f.name: _canonical(getattr(value, f.name))
                    for f in fields(value) if f.name != "provenance"})
        return out
    if isinstance(value, np.ndarray):
        return [_canonical(v) for v in value.tolist()] if value.ndim else _canonical(value.item())
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _canonical(v) for k, v in value.items()}
    if isinstance(value, (bool, np.bool_, str)) or value is None:
        return value if not isinstance(value, np.bool_) else bool(value)
    if isinstance(value, (int, float, np.number)):
        return repr(float(value))  # 100 and 100.0 alike; repr round-trips every bit
    return repr(value)


def resolve_names(drive, names) -> list[str]:
    """Dotted parameter names of ``drive``; a bare flexspline dimension (``h_pz``) is accepted too.

    Parameters
    ----------
    drive : HarmonicDrive, str or None
        The model, or a built-in unit name (`as_drive`).
    names : iterable of str
        ``"flexspline.h_c"``, ``"friction.slip_torque"``, or ``"h_c"`` for a flexspline
        dimension.

    Returns
    -------
    list of str
        The dotted names, in the given order.

    Raises
    ------
    InputError
        On a name the drive does not have, with the close matches.
    """
    known = as_drive(drive).params()
    design = set(FlexsplineGeometry.design_names())
    resolved = []
    for name in names:
        if name in known:
            resolved.append(name)
        elif name in design or f"flexspline.{name}" in known:
            resolved.append(f"flexspline.{name}")
        else:
            raise unknown_name("parameter", name, list(known) + sorted(design))
    _refuse_counts(as_drive(drive), resolved)
    twice = sorted({n for n in resolved if resolved.count(n) > 1})
    if twice:  # 'h_pz' and 'flexspline.h_pz': one input under two names, the second column overwrote the first
        given = ", ".join(repr(n) for n, r in zip(names, resolved) if r == twice[0])
        raise InputError(f"parameter {twice[0]} is named twice ({given}): a study varies each parameter once")
    return resolved


def _refuse_counts(model: HarmonicDrive, dotted) -> None:
    """InputError for a count (balls, teeth) among a study's inputs.

    A Sobol' design draws real values across each range, and a count takes whole numbers
    only: every row would be refused (20.5 balls is no bearing), and the study would end
    with all its blocks dropped. Rounding the rows instead would study a staircase whose
    steps carry weights set by where the range ends fall (a uniform 19.8-24.2, ±10 % of 22,
    puts 16 % of the rows on 20 and 23 % on 21), with values in the study file that are
    not the ones run. A count is compared at whole values: one run or one study per count.
    """
    for name in dotted:
        what = model.param_info(name).get("count")
        if what:
            raise InputError(f"{name} is a count of {what} (whole numbers only), which a Sobol' study cannot "
                             f"vary; compare whole counts instead (hdsim simulate --set {name}=VALUE, or a study per count of "
                             f"drive.with_updates)")


def refusal(drive, dotted, values) -> str | None:
    """Why the model refuses ``drive`` with the parameters ``dotted`` at ``values`` (None: it
    builds): its bounds, its geometry rules and its consistency (T1 below T2)."""
    try:
        as_drive(drive).with_updates({n: float(v) for n, v in zip(dotted, values)}).require_consistent()
    except InputError as exc:
        return str(exc)
    return None


def nominal_values(drive, names) -> dict[str, float]:
    """Value of each named parameter in ``drive`` [SI unit of the parameter], keys as given.

    Parameters
    ----------
    drive : HarmonicDrive, str or None
        A single model, or a built-in unit name.
    names : iterable of str
        Parameter names (see `resolve_names`).
    """
    names = list(names)
    params = as_drive(drive).params()
    return {name: float(np.asarray(params[dotted]).reshape(-1)[0])
            for name, dotted in zip(names, resolve_names(drive, names))}


@dataclass(frozen=True)
class ScenarioMetric:
    """Picklable ``f(X) -> y``: one metric of one scenario on one drive, rows batched.

    Attributes
    ----------
    drive : HarmonicDrive or str
        The model whose parameters the rows replace (a unit name is loaded in the worker).
    names : tuple of str
        Dotted parameter names, one per column of ``X``.
    output : str
        The metric, e.g. ``"lost_motion_arcmin"``.
    scenario : Scenario or str
        The scenario, or a built-in scenario name or file.
    chunksize : int
        Rows per task the study engine should send (larger chunks amortise overhead).
    evaluator : str
        ``"dynamic"`` or ``"quasistatic"``: the evaluator every row runs on, chosen once
        per study (`model_function`) so that no row depends on its chunk.
    choice : dict, optional
        Why (`hdsim.scenarios.evaluator.EvaluatorChoice.as_dict`), for the study file.
    """

    drive: HarmonicDrive | str
    names: tuple[str, ...]
    output: str
    scenario: Scenario | str
    chunksize: int = 1024
    evaluator: str = "dynamic"
    choice: dict | None = None

    def __call__(self, X: ArrayLike) -> np.ndarray:
        return self.explained(X)[0]

    def explained(self, X: ArrayLike) -> tuple[np.ndarray, dict[int, str]]:
        """``(y, {row: reason})``: the metric of each row, NaN for a row the model refuses
        or the solver cannot run, with the reason (the study's failure message,
        `hdsim.sensitivity.evaluate.run_chunk`)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        y = np.full(len(X), np.nan)
        reasons = {i: f"refused: {message}" for i, message in self._refusals(X).items()}
        valid = np.ones(len(X), dtype=bool)
        valid[list(reasons)] = False
        if valid.any():
            rows = np.flatnonzero(valid)
            y[valid], unsolved = self._evaluate(X[valid])
            reasons.update({int(rows[j]): f"solver failed: {message}" for j, message in unsolved.items()})
        return y, reasons

    def resolution(self, y) -> float:
        """The size of the simulator's own error on one output [unit of the output]: the
        solver's relative tolerance (`STUDY_SOLVER`) of the outputs' mean magnitude, or a
        millionth of it through the quasi-static evaluator (Newton to 1e-9 of the torque),
        and then at least the quasi-static evaluator's distance from an accurate dynamic run
        on the nominal drive (`_quasistatic_gap`, measured once, when the study is analysed, and
        kept in ``choice["figures"]["quasistatic_gap"]``): the inertia it leaves out moves
        across the box by as much. A study whose outputs vary less than ten times this says
        so (`resolution_flags`)."""
        finite = np.asarray(y, dtype=float)
        finite = finite[np.isfinite(finite)]
        relative = 1e-6 if self.evaluator == "quasistatic" else STUDY_SOLVER.rtol
        own = relative * float(np.mean(np.abs(finite))) if finite.size else 0.0
        if self.evaluator != "quasistatic":
            return own
        figures = dict((self.choice or {}).get("figures", {}))
        if "quasistatic_gap" not in figures:
            figures["quasistatic_gap"] = _quasistatic_gap(_single(as_drive(self.drive)), load_scenario(self.scenario),
                                                          self.output)
            if self.choice is not None:  # a choice of its own: the dict it was given stays as it was
                object.__setattr__(self, "choice", {**self.choice, "figures": figures})
        return max(own, figures["quasistatic_gap"])

    def _model(self, X):
        # a row whose values contradict each other (T1 above T2) is refused like one out of bounds
        return as_drive(self.drive).with_updates({n: X[:, j] for j, n in enumerate(self.names)}).require_consistent()

    def _refusal(self, row) -> str | None:
        """Why the model refuses one row's values (None: it builds). Built from floats, so
        the message names the values, not a sample of a batch of one."""
        return refusal(self.drive, self.names, row)

    def _refusals(self, X) -> dict[int, str]:
        """Row -> why the model refuses it. The bound and geometry checks refuse a batch
        when any row fails them, so one batch build clears a whole good chunk; only a
        refused chunk is checked row by row."""
        try:
            self._model(X)
        except InputError:
            refusals = {i: self._refusal(row) for i, row in enumerate(X)}
            return {i: message for i, message in refusals.items() if message is not None}
        return {}

    def _valid_rows(self, X) -> np.ndarray:
        """Rows whose parameters build a model."""
        valid = np.ones(len(X), dtype=bool)
        valid[list(self._refusals(X))] = False
        return valid

    def _evaluate(self, X) -> tuple[np.ndarray, dict[int, str]]:
        """``(metric of each row, {row: solver message})``, NaN where the solver failed."""
        scenario = load_scenario(self.scenario)
        try:
            run = _study_run(self._model(X), scenario, self.evaluator)
        except SolverError as exc:
            if len(X) == 1:
                return np.array([np.nan]), {0: str(exc)}
            # isolate the failing rows by halving; the others keep their values
            half = len(X) // 2
            (low, low_failed), (high, high_failed) = self._evaluate(X[:half]), self._evaluate(X[half:])
            return np.concatenate([low, high]), {**low_failed, **{half + j: m for j, m in high_failed.items()}}
        if self.output not in run.metrics:
            raise unknown_name(f"output metric of scenario {scenario.name}", self.output,
                               run.metrics)
        return np.asarray(run.metrics[self.output], dtype=float).reshape(-1), {}


@dataclass(frozen=True)
class ScenarioSeries:
    """Picklable ``f(X) -> Y (rows, T)``: one signal of a scenario on its output grid.

    For time-resolved indices (`hdsim.sensitivity.resolved.resolved_indices`);
    ``times()`` gives the grid [s].
    """

    drive: HarmonicDrive | str
    names: tuple[str, ...]
    signal: str
    scenario: Scenario | str
    samples_per_segment: int = 20
    chunksize: int = 1024

    def _scenario(self) -> Scenario:
        return load_scenario(self.scenario)

    def times(self) -> np.ndarray:
        """The output grid [s] of every row of ``f(X)``."""
        return self._scenario().sample_times(self.samples_per_segment)

    def __call__(self, X: ArrayLike) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, dtype=float))
        metric = ScenarioMetric(self.drive, self.names, "", self.scenario)
        scenario = self._scenario()
        Y = np.full((len(X), scenario.sample_times(self.samples_per_segment).size), np.nan)
        valid = metric._valid_rows(X)
        if valid.any():
            run = run_scenario(metric._model(X[valid]), scenario, options=STUDY_SOLVER,
                               samples_per_segment=self.samples_per_segment)
            Y[valid] = run.result.signals[self.signal]
        return Y


def _study_run(model: HarmonicDrive, scenario: Scenario, evaluator: str):
    """A run as a study makes it: the study's solver options and output grid (`STUDY_SOLVER`,
    `STUDY_SAMPLES`) through ``evaluator``."""
    return run_scenario(model, scenario, options=STUDY_SOLVER, samples_per_segment=STUDY_SAMPLES.get(scenario.name),
                        evaluator=evaluator)


def _single(drive) -> HarmonicDrive:
    model = as_drive(drive)
    if model.batch_size != 1:
        raise InputError(f"a study varies one drive; this one is a batch of {model.batch_size}")
    return model


def _check_output(model: HarmonicDrive, scenario: Scenario, output: str, evaluator: str = "dynamic") -> None:
    """Run the nominal drive once, through the study's evaluator: a metric the scenario does
    not report is refused here, not after every row of the study has failed on it."""
    run = _study_run(model, scenario, evaluator)
    if output not in run.metrics:
        raise unknown_name(f"output metric of scenario {scenario.name}", output, run.metrics)


def series_function(drive, names, signal: str, scenario) -> ScenarioSeries:
    """The resolved-study callable for ``signal`` (e.g. ``twist_rad``) of ``scenario``.

    Parameters
    ----------
    drive : HarmonicDrive, str or None
        The model, or a built-in unit name.
    names : iterable of str
        Parameters to vary (see `resolve_names`).
    signal : str
        A signal of the run, e.g. ``"twist_rad"``.
    scenario : Scenario, str or os.PathLike
        A scenario, a built-in scenario name or a scenario file.
    """
    model = _single(drive)
    return ScenarioSeries(drive if isinstance(drive, str) else model,
                          tuple(resolve_names(model, names)), signal, load_scenario(scenario))


def model_function(drive, names, output: str, scenario=None, evaluator: str = "auto",
                   wording: Wording = PYTHON_WORDING, range_ends=()) -> ScenarioMetric:
    """The study callable for ``output`` of ``scenario`` on ``drive``.

    Parameters
    ----------
    drive : HarmonicDrive, str or None
        Any single model (built-in, modified, fitted), or a built-in unit name.
    names : iterable of str
        Parameters to vary, one per column of ``X`` (see `resolve_names`).
    output : str
        The metric, e.g. ``"lost_motion_arcmin"``.
    scenario : Scenario, str or os.PathLike, optional
        A scenario, a built-in scenario name or a scenario file; default the built-in
        scenario producing ``output`` (`hdsim.sensitivity.metric_scenarios.default_scenario`).
    evaluator : {"auto", "dynamic", "quasistatic"}
        `hdsim.scenarios.evaluator`; "auto" decides once, on the nominal drive and on
        ``range_ends``.
    wording : Wording
        How a refusal names the options (``scenario=``, or the command line's ``--scenario``).
    range_ends : iterable of (str, float, HarmonicDrive)
        Single drives at the ends of the studied ranges (name, value, drive): "auto" keeps
        the dynamic model if the criterion fails at any of them.

    Returns
    -------
    ScenarioMetric
        Picklable ``f(X: (n, d)) -> (n,)``; NaN for rows that cannot be built or solved.
        Its ``choice`` says which evaluator runs and why.

    Raises
    ------
    InputError
        On an unknown unit, parameter, output (without a scenario: one no built-in scenario
        reports, or several do) or scenario, or an unreadable scenario file.
    """
    if scenario is None:
        scenario = default_scenario(output, wording)
    resolved = load_scenario(scenario)  # fails early with a clear message
    model = _single(drive)
    setup = get_setup(resolved.setup)
    choice = choose_evaluator(setup, model, resolved, evaluator)
    for name, value, end in range_ends if choice.requested == "auto" and choice.chosen == "quasistatic" else ():
        # the criterion can fail inside the box while the nominal drive passes it (a micro-slip
        # slider whose slip torque range reaches below the cycle's peak): the study is judged
        # at the ends of its ranges too, where such a limit is crossed first
        holds, reason, _ = setup.quasistatic_criterion(end, resolved)
        if not holds:
            choice = EvaluatorChoice("auto", "dynamic", f"at {name} = {value:g}, an end of its range: {reason}",
                                     choice.figures)
            break
    # a scenario named may not report the output, and a forced quasi-static evaluator may not
    # run the scenario (a motor loop, metric groups it has no signals for): either is refused
    # here, with run_scenario's reason, not after every row of the study has failed on it
    default = isinstance(scenario, str) and METRIC_SCENARIOS.get(output) == scenario
    if not default or choice.requested == "quasistatic":
        _check_output(model, resolved, output, choice.chosen)
    # a unit given by name travels by name: workers load it from their own cache
    return ScenarioMetric(drive if isinstance(drive, str) else model,
                          tuple(resolve_names(model, names)), output, resolved,
                          chunksize=task_rows(model, resolved), evaluator=choice.chosen, choice=choice.as_dict())


def _quasistatic_gap(model: HarmonicDrive, scenario: Scenario, output: str) -> float:
    """The quasi-static evaluator's distance from an accurate ``solve_ivp`` run of ``output``
    on the nominal drive [unit of the output] (docs/sensitivity.md §6, §11).

    The reference runs at `run_scenario`'s own tolerances (rtol 1e-6, or the scenario's
    ``[solver]`` table), the reference the docs compare every evaluator with, not the
    study's looser `STUDY_SOLVER`: a loose reference measures its own error. On a fitted
    drive whose Dahl friction sticks at 6600 times the spring's stiffness, undamped, rtol
    1e-4 gave a lost motion of 1.0055 arcmin, rtol 1e-6 1.2175049, rtol 5e-7 1.2175052
    and the quasi-static evaluator 1.21747, and a 0.21 arcmin "gap" flagged a study whose
    output spread 0.028. A second run at half the tolerance would bound the reference's own
    error too, but it moved this worst case by 3e-7 arcmin and would double the cost (two
    minutes on that drive, seconds on a kinematic-error run), so one run is made.
    NaN-free: 0 when either evaluator cannot give the output, which the study's own rows
    then show.
    """
    import warnings

    from hdsim.errors import SlowRunWarning

    values = []
    for evaluator in ("quasistatic", "dynamic"):
        try:
            with warnings.catch_warnings():  # a quasi-static study is the advice that warning gives
                warnings.simplefilter("ignore", SlowRunWarning)
                run = run_scenario(model, scenario, samples_per_segment=STUDY_SAMPLES.get(scenario.name),
                                   evaluator=evaluator)
        except SolverError:
            return 0.0
        values.append(float(np.asarray(run.metrics.get(output, np.nan)).reshape(-1)[0]))
    gap = abs(values[0] - values[1])
    return gap if np.isfinite(gap) else 0.0


def task_rows(model: HarmonicDrive, scenario: Scenario, limit: int = 1024) -> int:
    """Rows per study task: ``limit``, or fewer where one run is long, so that a task's
    memory stays within `TASK_BYTES` whatever the size of the design."""
    count = get_setup(scenario.setup).output_samples
    if count is None:
        return limit
    return int(np.clip(TASK_BYTES // (BYTES_PER_SAMPLE_AND_ROW * count(model, scenario)), 1, limit))
