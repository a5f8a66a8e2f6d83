"""Run a whole Sobol' study: design, evaluation into the store, analysis, checks.

`run_study` is what ``hdsim sobol`` calls; it is also the Python entry point
for any picklable model ``f(X: (n, d)) -> (n,)``.
"""

from __future__ import annotations

import re
import sys
import time
from dataclasses import dataclass, field, replace

import numpy as np

from hdsim.errors import InputError
from hdsim.sensitivity.analysis import check_outputs, convergence, indices
from hdsim.sensitivity.checks import consistency_checks, dropped_flags, failed_messages, resolution_flags
from hdsim.sensitivity.design import check_sizes
from hdsim.sensitivity.evaluate import check_workers, evaluate
from hdsim.sensitivity.problem import PYTHON_WORDING, Wording
from hdsim.sensitivity.store import DONE, PENDING, open_store

MAX_LISTED_FAILURES = 20


@dataclass
class StudyResult:
    """Everything a study produced; `to_json` gives the ``hdsim sobol`` object."""

    problem: object
    n: int
    second_order: bool
    replicates: int
    analysis: dict
    checks: dict
    convergence: list
    failures: list
    evaluations: int            # model evaluations on record for the analysed N
    evaluated_now: int          # performed by this call (0 when all rows were on disk)
    seconds: float
    study: str | None = None
    extra: dict = field(default_factory=dict)

    def to_json(self, output: str | None = None) -> dict:
        """The ``hdsim sobol --json`` object (docs/cli.md); ``output`` names the metric
        (default: the one `hdsim.sensitivity.api.sobol` studied)."""
        output = output if output is not None else self.extra.get("output", "")
        names, a = list(self.problem.names), self.analysis
        per = lambda v: {nm: _num(x) for nm, x in zip(names, v)}  # noqa: E731
        out = {"output": output, "n": self.n, "evaluations": self.evaluations,
               "params": names, "S1": per(a["S1"]), "S1_conf": per(a["S1_conf"]),
               "ST": per(a["ST"]), "ST_conf": per(a["ST_conf"]),
               "seconds": round(self.seconds, 3), "study": self.study,
               "S1_conf_replicates": per(a["S1_conf_replicates"]),
               "ST_conf_replicates": per(a["ST_conf_replicates"]),
               "conf_level": self.extra.get("conf_level", 0.95),
               "replicates": self.replicates, "second_order": self.second_order,
               "evaluated_now": self.evaluated_now,
               "blocks_used": a["blocks_used"], "blocks_dropped": a["blocks_dropped"],
               "failures": self.failures, "failure_reasons": failure_reasons(self.failures),
               "checks": self.checks,
               "convergence": [_conv_json(row, names) for row in self.convergence]}
        if self.second_order:
            for key in ("S2", "S2_conf", "S2_conf_replicates"):
                out[key] = _pairs(a[key], names)
        return {**out, **{k: v for k, v in self.extra.items() if k not in out}}


def run_study(func, problem, n, *, seed=0, second_order=False, replicates=4, executor=None,
              workers=2, chunksize=None, out=None, resume=False, retry_failed=False,
              target_width=None, model=None, conf_level=0.95, num_resamples=100,
              progress=True, log=None, wording: Wording = PYTHON_WORDING) -> StudyResult:
    """Sample, evaluate (resumably), check and analyse a Sobol' study.

    Parameters
    ----------
    func : callable
        Picklable ``f(X: (n, d)) -> (n,)``; NaN or an exception marks a failed row.
    problem : Problem
        The study inputs.
    n : int
        Base points N (power of 2), split into ``replicates`` scrambles of N/R.
        With ``target_width`` it is the most the study may grow to.
    seed : int
        Study seed; the scramble seed of each replicate and the bootstrap seed derive
        from it.
    second_order : bool
        Also estimate second-order indices (2D + 2 rows per base point, not D + 2).
    replicates : int
        Independently scrambled replicates R (power of 2, at least 2).
    executor : concurrent.futures.Executor, optional
        None: a local pool of ``workers`` processes (``workers == 1``: in-process).
    workers : int
        Processes of the local pool.
    chunksize : int, optional
        Rows per task; default ``func.chunksize`` if it has one, else from the design size.
    out : str or os.PathLike, optional
        HDF5 study file; every finished chunk is flushed to it.
    resume : bool
        Continue ``out`` (must hold the same definition; a larger N extends it).
    retry_failed : bool
        Evaluate rows that failed before once more.
    target_width : float, optional
        Stop doubling N once every replicate interval (full width) of S1 and ST is
        narrower than this [-].
    model : dict, optional
        Description of the model stored with the definition (resume refuses a
        different one), e.g. ``{"function": "ishigami"}``.
    conf_level : float
        Confidence level of both interval kinds [-].
    num_resamples : int
        Bootstrap resamples of the SALib interval.
    progress : bool
        Show a progress bar on stderr when it is a terminal.
    log : callable, optional
        ``log(line)`` for warnings and progress lines; default: stderr.
    wording : Wording
        How messages name the options: as these keywords (default), or as ``hdsim sobol``
        does (`hdsim.sensitivity.problem.CLI_WORDING`: ``--n``, ``--replicates``, …).

    Returns
    -------
    StudyResult
        Indices, both intervals, checks, convergence rows and failures.

    Raises
    ------
    InputError
        On a bad N, R, seed, chunk size or target width, second order with one parameter,
        ``retry_failed`` without ``resume``, an existing ``out`` without ``resume``, a study
        file of another definition, or too few successful blocks.
    hdsim.sensitivity.evaluate.ModelError
        When the model fails on every row of the first few hundred and on every row of the
        study before.
    """
    t0, log = time.perf_counter(), log or _stderr
    check_sizes(n, replicates, wording)
    if executor is None:
        check_workers(workers, wording)
    check_options(problem.names, second_order, chunksize, resume, retry_failed, wording)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed must be a whole number, 0 or more, got {seed!r}")
    if target_width is not None and not target_width > 0:
        raise InputError(f"{wording.target_width} must be > 0, got {target_width}")
    definition = {"problem": problem.to_dict(), "seed": int(seed),
                  "second_order": bool(second_order), "replicates": int(replicates),
                  "model": model or {}}
    store = open_store(definition, n, out, resume, wording)
    evaluated_now, n_stage = 0, None
    try:
        before = store.counts(n)
        for n_stage in _stages(n, replicates, target_width):
            rows = store.pending(n_stage, retry_failed)
            if len(rows):
                # the guard against a broken model judges the whole study, not the rows run now
                ev = evaluate(func, store.reader(rows), executor, workers=workers,
                              chunksize=chunksize, rows=rows, on_chunk=store.write,
                              progress=progress, succeeded_before=store.counts()["done"],
                              wording=wording if out else replace(wording, retry=""))
                evaluated_now += ev.evaluations
            res, width = _analyse_store(store, n_stage, conf_level, num_resamples, seed)
            if target_width is not None:
                log(f"N = {n_stage}: widest replicate interval {width:.4f} "
                    f"(target {target_width})")
                if width < target_width:
                    break
        failures = _failure_records(store, n_stage)
        prefix = store.prefix_rows(n_stage)
        outputs = store.read("Y", prefix)
        conv = convergence(problem, outputs, second_order=second_order,
                           replicates=replicates,
                           evaluated=store.read("status", prefix) != PENDING,
                           conf_level=conf_level, num_resamples=num_resamples, seed=seed)
        counts = store.counts(n_stage)
    except InputError:
        if n_stage is not None:  # too few blocks left: the failures that dropped them come first
            _report_failures(_failure_records(store, n_stage), store, log)
        raise
    finally:
        # Failure messages are metadata: written only here, with no chunk in flight
        # (also after Ctrl-C or a model that fails everywhere, to help the diagnosis).
        store.save_failures()
        store.close()
    _report_failures(failures, store, log)
    checks = consistency_checks(res["S1"], res["ST"], res["S1_conf_replicates"],
                                res["ST_conf_replicates"], problem.names)
    resolution = getattr(func, "resolution", None)  # a simulator says how finely it resolves its output
    flags = resolution_flags(outputs, resolution(outputs)) if callable(resolution) else []
    flags += dropped_flags(res["blocks_used"], res["blocks_dropped"])
    checks["flags"] += flags
    checks["ok"] = checks["ok"] and not flags
    for line in failed_messages(checks):
        log(line)
    extra = {"conf_level": conf_level, "seed": int(seed), "reused": int(before["done"] + before["failed"])}
    if target_width is not None:  # whether N sufficed is part of the result, not only of the log
        extra["target_width"] = {"target": float(target_width), "widest": float(width),
                                 "reached": bool(width < target_width)}
    return StudyResult(problem, n_stage, bool(second_order), int(replicates), res, checks,
                       conv, failures, counts["done"] + counts["failed"], evaluated_now,
                       time.perf_counter() - t0, str(out) if out else None, extra)


def check_options(names, second_order, chunksize, resume, retry_failed, wording: Wording = PYTHON_WORDING) -> None:
    """InputError for options of a study of the parameters ``names`` that cannot mean what
    they say (`run_study`'s keywords, named as ``wording`` does): second order with one parameter
    (S2 is an index of a pair; it had run 2D + 2 rows a point for nothing), a chunk of no rows
    (0 had been taken as the default), and failed rows retried in a study that is not resumed
    (a new study has none: the option had been dropped without a word)."""
    if second_order and len(names) < 2:
        raise InputError(f"{wording.second_order} needs two parameters or more (S2 is an index of a pair); "
                         f"the study varies only {', '.join(names)}")
    if chunksize is not None and (isinstance(chunksize, bool) or not isinstance(chunksize, (int, np.integer))
                                  or chunksize < 1):
        raise InputError(f"{wording.chunksize} must be a whole number, at least 1, got {chunksize!r}")
    if retry_failed and not resume:
        raise InputError(f"{wording.retry_failed} reruns the failed rows of a study file continued with "
                         f"{wording.resume}; a new study has none: add {wording.resume}, or leave it out")


def _stages(n, replicates, target_width):
    if target_width is None:
        return [n]
    stage, stages = min(n, 16 * replicates), []
    while stage <= n:
        stages.append(stage)
        stage *= 2
    return stages


def _analyse_store(store, n, conf_level, num_resamples, seed):
    """Check the stored design piece by piece, then estimate from the outputs."""
    d = store.definition
    for _, X, Y, key, status in store.blocks(n):
        if (status == PENDING).any():
            raise RuntimeError(f"{int((status == PENDING).sum())} rows still pending")
        check_outputs(store.problem, X, Y, d["second_order"], key, status != PENDING)
    rows = store.prefix_rows(n)
    Y, status = store.read("Y", rows), store.read("status", rows)
    res = indices(store.problem, Y, (status == DONE) & np.isfinite(Y),
                  second_order=d["second_order"], replicates=d["replicates"],
                  conf_level=conf_level, num_resamples=num_resamples, seed=seed)
    width = 2 * max(res["S1_conf_replicates"].max(), res["ST_conf_replicates"].max())
    return res, float(width)


def _failure_records(store, n) -> list[dict]:
    failures = store.failures(n)
    names = store.problem.names
    records = []
    for g, msg in sorted(failures.items()):
        r, j = divmod(g, store.rows_per_replicate)
        x = store.read("X", np.array([g]))[0]
        records.append({"row": g, "replicate": r, "index": j, "block": j // store.k,
                        "params": {nm: float(v) for nm, v in zip(names, x)}, "message": msg})
    return records


def failure_reasons(failures: list[dict]) -> list[dict]:
    """Why rows failed, once per kind of message: ``{"reason", "rows", "first_row"}`` in the
    order of each kind's first row (the study's JSON: a refused geometry or a solver
    failure, without reading every row of ``failures``). Messages that differ only in their
    numbers are one kind (a refusal names the row's own values); ``reason`` is the first
    row's message."""
    grouped: dict[str, dict] = {}
    for record in failures:  # sorted by row (`_failure_records`)
        kind = _NUMBER.sub("#", record["message"])
        entry = grouped.setdefault(kind, {"reason": record["message"], "rows": 0, "first_row": record["row"]})
        entry["rows"] += 1
    return list(grouped.values())


#: a number in a message (signed, decimal, exponent), not the digits of a name (``hardening.e2``, ``x1``)
_NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _report_failures(failures, store, log):
    for rec in failures[:MAX_LISTED_FAILURES]:
        params = ", ".join(f"{k}={v:.6g}" for k, v in rec["params"].items())
        log(f"warning: sample {rec['row']} ({store.sample_label(rec['row'])}) failed: "
            f"{rec['message']} [{params}]; its block of {store.k} rows is dropped")
    if len(failures) > MAX_LISTED_FAILURES:
        log(f"warning: ... and {len(failures) - MAX_LISTED_FAILURES} more failed samples")


def _stderr(line: str) -> None:
    print(f"hdsim sobol: {line}", file=sys.stderr)


def _num(x):
    x = float(x)
    return x if np.isfinite(x) else None


def _pairs(M, names) -> dict:
    return {a: {b: _num(M[i, j]) for j, b in enumerate(names) if j > i}
            for i, a in enumerate(names[:-1])}


def _conv_json(row, names) -> dict:
    return {"n": row["n"], **{k: [_num(x) for x in row[k]] for k in row if k != "n"}}
