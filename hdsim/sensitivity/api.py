"""`sobol`: a Sobol' study of any drive object through the simulator, from Python.

The command ``hdsim sobol --unit …`` and this function run the same study
(`hdsim.sensitivity.study.run_study` on `hdsim.sensitivity.scenario_outputs.model_function`);
here the drive is an object, so a built-in unit, one changed with
``with_updates``, or a fitted model all work. The method is described in
docs/sensitivity.md.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from concurrent.futures import Executor

from hdsim.errors import InputError
from hdsim.sensitivity.evaluate import open_executor
from hdsim.sensitivity.models import from_unit
from hdsim.sensitivity.problem import parse_range
from hdsim.sensitivity.study import StudyResult, run_study
from hdsim.typing import Bounds, PathLike

__all__ = ["sobol"]


def sobol(drive, params: str | Iterable[str], output: str, *, scenario=None, n: int = 1024,
          range: float | str | None = 0.1, bounds: Bounds | None = None,
          dists: Mapping[str, str] | None = None, second_order: bool = False,
          replicates: int = 4, seed: int = 0, executor: Executor | str | None = None,
          workers: int = 2, chunksize: int | None = None, out: PathLike | None = None,
          resume: bool = False, retry_failed: bool = False, target_width: float | None = None,
          progress: bool = True, log=None) -> StudyResult:
    """Sobol' indices of one simulator metric with respect to parameters of a drive.

    Parameters
    ----------
    drive : HarmonicDrive or str
        Any single model: a built-in unit (``hdsim.load_unit("CSG-25-100")``), one
        changed with ``with_updates`` or ``with_effects``, a fitted model
        (``hdsim.identification.fit.load_fitted(path)``); or a built-in unit name or the
        path of a drive file.
    params : str or iterable of str
        Parameters to vary: dotted names (``"friction.slip_torque"``) or bare
        flexspline dimensions (``"h_pz"``); a comma-separated string works too.
    output : str
        The metric studied, e.g. ``"lost_motion_arcmin"`` (units in its name).
    scenario : Scenario, str or os.PathLike, optional
        A `Scenario`, a built-in scenario name (``"stiffness"``) or a scenario file;
        default the built-in scenario that reports ``output``.
    n : int
        Base points N, a power of 2; the study evaluates N (D + 2) rows, or
        N (2D + 2) with ``second_order``.
    range : float or str, optional
        Each parameter uniform within ±``range`` of its value in ``drive`` [-]
        (``0.1`` or ``"10%"``); None to require ``bounds`` for every parameter.
    bounds : mapping, optional
        ``{name: (low, high)}`` [SI unit of the parameter] (or ``"LOW:HIGH"``); overrides
        ``range`` for that parameter.
    dists : mapping, optional
        ``{name: "unif" | "logunif" | "norm" | "norm:MEAN:SD"}``; default uniform.
    second_order : bool
        Also estimate the second-order indices S2.
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
        Rows per task (default: the simulator's batch size).
    out : str or os.PathLike, optional
        HDF5 study file; every finished chunk is flushed to it.
    resume : bool
        Continue ``out``; refused if it holds another drive, scenario or design.
    retry_failed : bool
        With ``resume``: evaluate the rows that failed before once more.
    target_width : float, optional
        Double N (up to ``n``) until every replicate interval of S1 and ST is
        narrower than this [-].
    progress : bool
        Progress bar on stderr when it is a terminal.
    log : callable, optional
        ``log(line)`` for warnings; default stderr.

    Returns
    -------
    StudyResult
        ``analysis["S1"]``, ``analysis["ST"]`` (arrays in the order of ``params``), both
        interval kinds, checks, convergence and failures; ``to_json()`` gives the
        object ``hdsim sobol --json`` prints (docs/cli.md).

    Raises
    ------
    InputError
        On an unknown parameter, output, unit or scenario, a bad file, range, bounds,
        N or R, or an existing ``out`` without ``resume``.
    hdsim.sensitivity.evaluate.ModelError
        When the simulation fails on every row tried.

    Examples
    --------
    >>> import hdsim
    >>> drive = hdsim.load_unit("CSG-25-100").with_updates({"backlash.gap": 2e-5})
    >>> result = hdsim.sobol(drive, ["h_pz", "h_c"], "lost_motion_arcmin", n=256)  # doctest: +SKIP
    >>> dict(zip(result.problem.names, result.analysis["ST"]))  # doctest: +SKIP
    """
    names = _names(params)
    if not names:
        raise InputError("sobol needs at least one parameter")
    frac = parse_range(range) if isinstance(range, str) else range
    if frac is not None and not 0 < frac < 10:
        raise InputError(f"range must be a fraction in (0, 10), got {frac}")
    func, problem, output, model, _ = from_unit(drive, names, output, scenario, frac,
                                                _bounds_text(bounds), dict(dists or {}))
    options = dict(seed=seed, second_order=second_order, replicates=replicates,
                   workers=workers, chunksize=chunksize, out=out, resume=resume,
                   retry_failed=retry_failed, target_width=target_width, model=model,
                   progress=progress, log=log)
    if executor is None or isinstance(executor, str):
        with open_executor(executor or "local", workers) as pool:
            result = run_study(func, problem, n, executor=pool, **options)
    else:
        result = run_study(func, problem, n, executor=executor, **options)
    result.extra.update(model=model, output=output)
    return result


def _names(params) -> list[str]:
    items = params.split(",") if isinstance(params, str) else list(params)
    return [str(p).strip() for p in items if str(p).strip()]


def _bounds_text(bounds) -> dict[str, str]:
    """``{name: (lo, hi)}`` as the ``LO:HI`` text `build_problem` reads (repr is exact)."""
    out = {}
    for name, value in dict(bounds or {}).items():
        if isinstance(value, str):
            out[name] = value
            continue
        try:
            lo, hi = (float(v) for v in value)
        except (TypeError, ValueError):
            raise InputError(f"bounds for '{name}' must be (low, high), got {value!r}") from None
        out[name] = f"{lo!r}:{hi!r}"
    return out
