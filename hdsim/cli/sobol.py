"""``hdsim sobol``: Sobol' sensitivity of a simulator output or a closed-form function.

Examples::

    hdsim sobol --unit CSG-25-100 --params h_pz,h_c,R_v,R_k,h_p --range 10% \\
                --output lost_motion_arcmin --n 1024 --second-order --out study.h5 --json
    hdsim sobol --unit fitted.toml --scenario my_test.toml --params h_pz,backlash.gap \\
                --range 10% --output lost_motion_arcmin --n 256 --json
    hdsim sobol --unit my_drive.toml --params h_pz,h_c --range 10% \\
                --output lost_motion_arcmin --n 256 --json
    hdsim sobol --function ishigami --n 4096 --json
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from hdsim.cli._guards import check_output_file, check_output_folder, path_argument
from hdsim.errors import InputError
from hdsim.scenarios.evaluator import EVALUATORS

HELP = "Sobol' sensitivity study (first, total, optional second order) with checks"


def register(subparsers) -> None:
    p = subparsers.add_parser("sobol", help=HELP, description=HELP + ".")
    what = p.add_mutually_exclusive_group()
    what.add_argument("--unit", metavar="UNIT|FILE.toml",
                      help="drive to study through the simulator: a built-in unit (see "
                           "'hdsim units'), a drive file ('hdsim units --template') or a "
                           "fitted-model file written by 'hdsim fit --out'")
    what.add_argument("--function", help="closed form: ishigami, gfunction or linear")
    what.add_argument("--model", metavar="MODULE:CALLABLE",
                      help="any picklable f(X) -> y importable from PYTHONPATH")
    p.add_argument("--params", default="", help="comma-separated parameter names")
    p.add_argument("--range", dest="range_", metavar="P%",
                   help="uniform within ±P %% of each nominal value")
    p.add_argument("--bounds", nargs="+", action="extend", default=[], metavar="NAME=LO:HI",
                   help="explicit bounds for one or more parameters")
    p.add_argument("--dist", nargs="+", action="extend", default=[],
                   metavar="NAME=unif|logunif|norm[:MEAN:SD]", help="input distribution")
    p.add_argument("--output", help="metric to study (required with --unit)")
    p.add_argument("--scenario", metavar="NAME|FILE.toml",
                   help="scenario the metric comes from (--unit): a built-in name or a "
                        "scenario file (default: the built-in scenario reporting --output)")
    p.add_argument("--evaluator", choices=EVALUATORS, default="auto",
                   help="--unit: 'auto' (default) runs a quasi-static scenario (the ±4 %% lost-motion "
                        "test, kinematic-error runs at constant speed) through the quasi-static evaluator, "
                        "anything else through solve_ivp; 'dynamic' forces solve_ivp")
    p.add_argument("--n", default="1024", help="base points N, a power of 2 (default 1024)")
    p.add_argument("--second-order", action="store_true", help="also estimate S2 (two parameters or more)")
    p.add_argument("--seed", default="0", help="scramble seed (default 0)")
    p.add_argument("--replicates", default="4",
                   help="independent scrambles of N/R base points each (default 4)")
    p.add_argument("--executor", default="local", help="local (default) or dask://HOST:PORT")
    p.add_argument("--workers", default="2", help="local processes (1 = in-process)")
    p.add_argument("--chunksize", default=None, help="rows per task (default: automatic)")
    p.add_argument("--out", type=path_argument,
                   help="HDF5 study file (its folder is created if missing); every finished sample is flushed to it")
    p.add_argument("--resume", action="store_true", help="continue (or extend N of) --out")
    p.add_argument("--retry-failed", action="store_true", help="with --resume (refused without): rerun failed rows")
    p.add_argument("--target-width", default=None,
                   help="double N up to --n until every 95 %% interval is narrower")
    p.add_argument("--report", type=path_argument, metavar="DIR", help="write figures and the summary here")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=run)


def run(args) -> int:
    from hdsim.sensitivity import models
    from hdsim.sensitivity.evaluate import open_executor
    from hdsim.sensitivity.problem import CLI_WORDING
    from hdsim.sensitivity.study import check_options, run_study

    t0 = time.perf_counter()
    n, seed = _int(args.n, "--n"), _int(args.seed, "--seed", minimum=0)
    reps, workers = _int(args.replicates, "--replicates"), _int(args.workers, "--workers")
    chunksize = _int(args.chunksize, "--chunksize", minimum=1) if args.chunksize else None
    target = _float(args.target_width, "--target-width") if args.target_width else None
    if args.resume and not args.out:  # before the study is built (`open_store` says it too, later)
        raise InputError("--resume needs --out STUDY.h5")
    # where the results go is checked before the study, not after its first chunk
    if args.out:
        check_output_file(args.out, "--out")
    where = _summary_folder(args)
    if where is not None:  # the summary and the figures, into --report or beside the study file
        check_output_folder(where[0], "--report" if args.report else "--out",
                            names=(*_summary_files(where[1]), _manifests(args, where[1])[0]))
    # a broken model is ModelError (bad input, exit 2); anything else that fails here, a
    # broken process pool included, is the program's failure and reaches main (exit 1)
    # a drive study's options are judged before its model is built (a named scenario runs the
    # nominal drive once); an analytic or imported model's names come with it
    options = (args.second_order, chunksize, args.resume, args.retry_failed, CLI_WORDING)
    if args.unit:
        check_options(_names(args), *options)
    func, problem, output, model, analytic = _resolve(args, models)
    if not args.unit:
        check_options(problem.names, *options)
    try:
        with open_executor(args.executor, workers, CLI_WORDING) as executor:
            result = run_study(func, problem, n, seed=seed, second_order=args.second_order,
                               replicates=reps, executor=executor, workers=workers,
                               chunksize=chunksize, out=args.out, resume=args.resume,
                               retry_failed=args.retry_failed, target_width=target,
                               model=model, wording=CLI_WORDING)
    except OSError as exc:
        from hdsim.cli import environment_error

        if not (args.out and environment_error(exc)):
            raise
        # every chunk is flushed as it finishes, so what was done before the disk filled is
        # in the study file: say so, and how to go on
        raise InputError(f"{args.out}: {exc.strerror or exc} while writing the study; the rows finished "
                         f"before are kept in it: free space (or copy the file elsewhere) and run the same "
                         f"command with --resume") from None
    summary = result.to_json(output)
    summary["seconds"] = round(time.perf_counter() - t0, 3)
    summary.update(_extras(args, model, analytic, problem.names, result))
    if getattr(func, "choice", None):  # a --unit study: which evaluator ran and why
        summary["evaluator"] = func.choice
    _write_outputs(args, summary, result, analytic, target)
    if args.json:
        from hdsim.cli import emit_json

        emit_json(summary)
    else:
        _print_table(summary)
    return 0


def _resolve(args, models):
    """(func, problem, output, model description, analytic indices or None).

    The options' text is parsed here, into the typed values the library takes (bounds as
    ``(low, high)``); the library's messages then name the options as this command does.
    """
    from hdsim.sensitivity.problem import parse_assignments, parse_bounds_options, parse_range

    names = _names(args)
    frac = parse_range(args.range_) if args.range_ else None
    bounds = parse_bounds_options(args.bounds)
    dists = parse_assignments(args.dist, "--dist")
    if args.function:
        if names or bounds or dists or frac is not None:
            raise InputError("--function has its own inputs: "
                             "drop --params, --range, --bounds and --dist")
        return models.from_function(args.function, args.output)
    if args.model:
        return models.from_import(args.model, names, args.output, frac, bounds, dists)
    if args.unit:
        if not names:
            raise InputError("--unit studies need --params NAME,NAME,...")
        return models.from_unit(_drive(args.unit), names, args.output, args.scenario, frac,
                                bounds, dists, evaluator=args.evaluator)
    raise InputError("say what to study: --unit U, --function NAME or --model MODULE:CALLABLE")


def _names(args) -> list[str]:
    """The parameters of ``--params``, in order."""
    return [s.strip() for s in args.params.split(",") if s.strip()]


def _drive(text: str):
    """A built-in unit name as it is; a fitted-model file or a drive file as the
    `HarmonicDrive` it describes."""
    from hdsim.model.catalog import load_unit
    from hdsim.model.datasheet import unit_names

    if text in unit_names():
        return text
    path = Path(text)
    if path.suffix.lower() == ".toml" or path.exists() or any(c in text for c in "/\\"):
        if _is_fit_file(path):
            from hdsim.identification.fit import load_fitted

            return load_fitted(path)  # a foreign fit file is one InputError line
        return load_unit(path)  # a drive file; a missing or bad file is one InputError line
    return text  # an unknown name: the catalog names the close matches


def _is_fit_file(path: Path) -> bool:
    """Whether ``path`` is a fitted-model file (``format = "hdsim-fit-1"``), not a drive file."""
    import tomllib

    try:
        return tomllib.loads(path.read_text(encoding="utf-8")).get("format") == "hdsim-fit-1"
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False  # the drive-file reader reports what is wrong with it


def _extras(args, model, analytic, names, result) -> dict:
    extra = {"model": model, "executor": args.executor}
    if analytic is not None:
        a = {k: {nm: float(v) for nm, v in zip(names, analytic[k])} for k in ("S1", "ST")}
        a["max_abs_error"] = {k: max(abs(result.analysis[k][i] - analytic[k][i])
                                     for i in range(len(names))) for k in ("S1", "ST")}
        extra["analytic"] = a
    return extra


def _summary_folder(args) -> tuple[Path, str] | None:
    """(folder, stem) of the JSON summary and the figures: ``--report DIR`` as ``sobol``, else
    beside ``--out`` under the study file's stem; None without either."""
    if args.report:
        return Path(args.report), "sobol"
    if args.out:
        return Path(args.out).parent, Path(args.out).stem
    return None


def _summary_files(stem: str) -> tuple[str, str, str]:
    """The summary's and the figures' file names (checked before the study, written after it)."""
    return f"{stem}.json", f"{stem}_indices.png", f"{stem}_convergence.png"


def _manifests(args, stem: str) -> tuple[str, str]:
    """(the manifest that lists the files a study's summary wrote, the other that may list them
    from before) (`hdsim.io.report_files`). Under --report the folder's own: a report written
    there later removes them, as they replace an earlier report's. Else one named for the
    stem: a study written again under that stem removes its own figure that it does not write
    again (a convergence figure of a larger N), and never the files of a study of another
    stem in the same folder."""
    from hdsim.io.report_files import MANIFEST

    stems = f".hdsim-sobol-{stem}.json"
    return (MANIFEST, stems) if args.report else (stems, MANIFEST)


def _write_outputs(args, summary, result, analytic, target) -> None:
    """Figures and the JSON summary: into ``--report DIR`` or next to ``--out``."""
    where = _summary_folder(args)
    if where is None:
        return
    folder, stem = where
    summary_name, indices_name, convergence_name = _summary_files(stem)
    from hdsim.atomic import write_text_atomic
    from hdsim.io.report_files import replace_report_files
    from hdsim.plotting.sensitivity import plot_convergence, plot_indices

    names = list(result.problem.names)
    figs = [plot_indices(folder / indices_name, names, result.analysis, analytic,
                         title=f"{summary['output']}: N = {result.n}")]
    if len(result.convergence) > 1:
        figs.append(plot_convergence(folder / convergence_name, names,
                                     result.convergence, target, analytic))
    summary["figures"] = [str(f) for f in figs]
    write_text_atomic(folder / summary_name, json.dumps(summary, indent=1, allow_nan=False))
    # the files of the last report or study of this stem here, not written again, are stale
    replace_report_files(folder, [folder / summary_name, *figs], *_manifests(args, stem),
                         claimed=_summary_files(stem))
    # as `hdsim simulate` says what it wrote (on stderr: stdout may be the JSON)
    written = ([args.out] if args.out else []) + [str(folder / summary_name)] + summary["figures"]
    print(f"wrote {', '.join(written)}", file=sys.stderr)


def _print_table(s) -> None:
    print(f"{s['output']}: N = {s['n']}, {s['evaluations']} evaluations, {s['seconds']} s")
    print(f"{'param':>12} {'S1':>8} {'±boot':>7} {'±rep':>7} {'ST':>8} {'±boot':>7} {'±rep':>7}")
    for nm in s["params"]:
        vals = (s["S1"][nm], s["S1_conf"][nm], s["S1_conf_replicates"][nm],
                s["ST"][nm], s["ST_conf"][nm], s["ST_conf_replicates"][nm])
        print(f"{nm:>12} " + " ".join("     nan" if v is None else f"{v:8.4f}" for v in vals))
    print("checks: " + ("all pass" if s["checks"]["ok"] else "FAILED (see stderr)"))
    reasons = s.get("failure_reasons")
    if reasons:
        failed = sum(r["rows"] for r in reasons)
        more = f"; {len(reasons)} distinct reasons (failure_reasons in --json)" if len(reasons) > 1 else ""
        print(f"failed rows: {failed}, blocks dropped: {s['blocks_dropped']}; first (sample {reasons[0]['first_row']}): "
              f"{reasons[0]['reason']}{more}")
    choice = s.get("evaluator")
    if choice:
        print(f"evaluator: {choice['chosen']} ({choice['reason']})")


def _int(text, option, minimum=None) -> int:
    try:
        value = int(str(text).strip())
    except ValueError:
        raise InputError(f"{option} expects an integer, got '{text}'") from None
    if minimum is not None and value < minimum:
        raise InputError(f"{option} must be {minimum} or more, got {value}")
    return value


def _float(text, option) -> float:
    try:
        return float(str(text).strip())
    except ValueError:
        raise InputError(f"{option} expects a number, got '{text}'") from None
