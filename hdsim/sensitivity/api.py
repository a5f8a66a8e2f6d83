"""`sobol`: a Sobol' study of any drive object through the simulator, from Python.

The command ``hdsim sobol --unit …`` and this function run the same study
(`hdsim.sensitivity.study.run_study` on `hdsim.sensitivity.scenario_outputs.model_function`);
here the drive is an object, so a built-in unit, one changed with
``with_updates``, or a fitted model all work. Its inputs are typed, bounds are
``(low, high)`` pairs, and its messages name them as Python spells them; the command
line parses its text into the same values first. The method is described in
docs/sensitivity.md.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable, Mapping
from concurrent.futures import Executor

from hdsim.errors import InputError
from hdsim.sensitivity.evaluate import open_executor
from hdsim.sensitivity.models import from_unit
from hdsim.sensitivity.problem import PYTHON_WORDING, bounds_pair, parse_range
from hdsim.sensitivity.study import StudyResult, check_options, run_study
from hdsim.typing import PathLike

#: explicit bounds of a study: parameter name -> (low, high) [SI unit of the parameter]
TypedBounds = Mapping[str, tuple[float, float]]

__all__ = ["sobol"]


def sobol(drive, params: str | Iterable[str] | TypedBounds, output: str, *, scenario=None, n: int = 1024,
          range: float | str | None = 0.1, bounds: TypedBounds | None = None,
          dists: Mapping[str, str] | None = None, second_order: bool = False,
          replicates: int = 4, seed: int = 0, executor: Executor | str | None = None,
          workers: int = 2, chunksize: int | None = None, out: PathLike | None = None,
          resume: bool = False, retry_failed: bool = False, target_width: float | None = None,
          progress: bool = True, log=None, evaluator: str = "auto") -> StudyResult:
    """Sobol' indices of one simulator metric with respect to parameters of a drive.

    Parameters
    ----------
    drive : HarmonicDrive or str
        Any single model: a built-in unit (``hdsim.load_unit("CSG-25-100")``), one
        changed with ``with_updates`` or ``with_effects``, a fitted model
        (``hdsim.identification.fit.load_fitted(path)``); or a built-in unit name or the
        path of a drive file.
    params : mapping, str or iterable of str
        Parameters to vary: dotted names (``"friction.slip_torque"``,
        ``"input_friction.coulomb_torque"``) or bare flexspline dimensions (``"h_pz"``);
        a comma-separated string works too. A mapping ``{name: (low, high)}`` gives each
        its bounds [SI unit of the parameter] (``None`` for a value: within ``range``).
    output : str
        The metric studied, e.g. ``"lost_motion_arcmin"`` (units in its name).
    scenario : Scenario, str or os.PathLike, optional
        A `Scenario`, a built-in scenario name (``"stiffness"``) or a scenario file;
        default the built-in scenario that reports ``output``.
    n : int
        Base points N, a power of 2; the study evaluates N (D + 2) rows, or
        N (2D + 2) with ``second_order``.
    range : float or str, optional
        Each parameter without bounds uniform within ±``range`` of its value in ``drive``
        [-] (``0.1`` or ``"10%"``); None to require bounds for every parameter.
    bounds : mapping, optional
        ``{name: (low, high)}`` [SI unit of the parameter], two finite numbers with
        low < high, for parameters named in ``params``; overrides ``range`` for them.
    dists : mapping, optional
        ``{name: "unif" | "logunif" | "norm" | "norm:MEAN:SD"}``; default uniform.
    second_order : bool
        Also estimate the second-order indices S2 (two parameters or more).
    replicates : int
        Independently scrambled replicates R of N/R base points (power of 2, ≥ 2).
    seed : int
        Study seed (scrambles and bootstrap).
    executor : concurrent.futures.Executor or str, optional
        An executor (process pool, ``distributed.Client.get_executor()``), or
        ``"local"`` / ``"dask://HOST:PORT"``; None is ``"local"``.
    workers : int
        Processes of the local pool; 1 evaluates in this process.
    chunksize : int, optional
        Rows per task, at least 1 (default: the simulator's batch size).
    out : str or os.PathLike, optional
        HDF5 study file; every finished chunk is flushed to it.
    resume : bool
        Continue ``out``; refused if it holds another drive, scenario or design.
    retry_failed : bool
        With ``resume`` (refused without): evaluate the rows that failed before once more.
    target_width : float, optional
        Double N (up to ``n``) until every replicate interval of S1 and ST is
        narrower than this [-].
    progress : bool
        Progress bar on stderr when it is a terminal.
    log : callable, optional
        ``log(line)`` for warnings; default stderr.
    evaluator : {"auto", "dynamic", "quasistatic"}
        "auto" runs the rows through the quasi-static evaluator where the scenario is
        quasi-static by its bench's criterion (the ±4 % lost-motion test, a kinematic-error
        run at constant speed), else through
        ``solve_ivp``; "dynamic" forces the reference (docs/sensitivity.md, "Which
        evaluator"). The choice, its reason and the figures of the criterion are in
        ``result.extra["evaluator"]``.

    Returns
    -------
    StudyResult
        ``analysis["S1"]``, ``analysis["ST"]`` (arrays in the order of ``params``), both
        interval kinds, checks, convergence and failures; ``to_json()`` gives the
        object ``hdsim sobol --json`` prints (docs/cli.md).

    Raises
    ------
    InputError
        On an unknown parameter (``unknown parameter 'x'``, naming the drive's close
        matches), output, unit or scenario; bounds that are not ``(low, high)`` with
        low < high or name a parameter not studied; a bad file, range, N, R or chunk size,
        ``second_order`` with one parameter, ``retry_failed`` without ``resume``, an existing
        ``out`` without ``resume``, or ``evaluator="quasistatic"`` on a scenario that
        evaluator cannot run (`hdsim.scenarios.run.run_scenario`'s reason).
    hdsim.sensitivity.evaluate.ModelError
        When the simulation fails on every row tried.

    Examples
    --------
    >>> import hdsim
    >>> drive = hdsim.load_unit("CSG-25-100").with_updates({"backlash.gap": 2e-5})
    >>> result = hdsim.sobol(drive, ["h_pz", "h_c"], "lost_motion_arcmin", n=256)  # doctest: +SKIP
    >>> dict(zip(result.problem.names, result.analysis["ST"]))  # doctest: +SKIP
    >>> hdsim.sobol(drive, {"h_c": (0.55e-3, 0.7e-3)}, "lost_motion_arcmin", n=256)  # doctest: +SKIP
    """
    names, given = study_bounds(params, bounds)
    # before the drive is built and run: these need no simulation to be refused
    check_options(names, second_order, chunksize, resume, retry_failed)
    frac = _fraction(range)
    func, problem, output, model, _ = from_unit(drive, names, output, scenario, frac, given,
                                                dict(dists or {}), wording=PYTHON_WORDING, evaluator=evaluator)
    options = dict(seed=seed, second_order=second_order, replicates=replicates,
                   workers=workers, chunksize=chunksize, out=out, resume=resume,
                   retry_failed=retry_failed, target_width=target_width, model=model,
                   progress=progress, log=log)
    if executor is None or isinstance(executor, str):
        with open_executor(executor or "local", workers) as pool:
            result = run_study(func, problem, n, executor=pool, **options)
    else:
        result = run_study(func, problem, n, executor=executor, **options)
    result.extra.update(model=model, output=output, evaluator=func.choice)
    return result


def study_bounds(params, bounds=None) -> tuple[list[str], dict[str, tuple[float, float]]]:
    """The parameters of a study and their explicit bounds, checked.

    Parameters
    ----------
    params : mapping, str or iterable of str
        As `sobol`: names, or ``{name: (low, high) or None}``.
    bounds : mapping, optional
        ``{name: (low, high)}`` for names among ``params``.

    Returns
    -------
    tuple
        (names in study order, ``{name: (low, high)}`` [SI]).

    Raises
    ------
    InputError
        No parameter; bounds given twice, for a name not studied, or not ``(low, high)``
        with low < high.
    """
    if isinstance(params, Mapping):
        names = [str(name).strip() for name in params]
        given = {str(name).strip(): value for name, value in params.items() if value is not None}
    else:
        items = params.split(",") if isinstance(params, str) else list(params)
        names, given = [str(p).strip() for p in items if str(p).strip()], {}
    if not names:
        raise InputError("sobol needs at least one parameter")
    for name, value in dict(bounds or {}).items():
        if name not in names:
            raise InputError(f"unknown parameter '{name}' in bounds: the study varies {', '.join(names)}")
        if name in given:
            raise InputError(f"bounds for '{name}' are given twice, in params and in bounds")
        given[name] = value
    return names, {name: bounds_pair(name, value) for name, value in given.items()}


def _fraction(range) -> float | None:
    """``range`` as a fraction in (0, 10): a number, or a percentage ``"10%"``; None as it is."""
    if range is None:
        return None
    bad = InputError(f"range must be a fraction in (0, 10) such as 0.1, or a percentage such as '10%', "
                     f"got {range!r}")
    if isinstance(range, str):
        try:
            return parse_range(range)
        except InputError:
            raise bad from None
    if isinstance(range, bool) or not isinstance(range, numbers.Real) or not 0 < range < 10:
        raise bad  # NaN fails the comparison too
    return float(range)
