"""Evaluate a model on many input rows, locally or on any executor, by row index.

``func`` is any picklable callable ``f(X: (n, d)) -> (n,)``; one that returns NaN for a row
it cannot evaluate may say why through a method ``func.explained(X) -> (y, {row: reason})``
(the simulator's refused geometry or solver failure), which the study keeps as the row's
failure message in place of "non-finite output". Rows go out in chunks;
each finished chunk comes back with its row positions, a fingerprint of the inputs
the worker saw, and the per-row failures, and is written into preallocated arrays
*by index* — never concatenated in completion order, which silently breaks Sobol'
estimators (ΣS ≈ 0, ΣST ≈ D).
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import sys
from dataclasses import dataclass, field

import numpy as np

from hdsim.errors import InputError
from hdsim.sensitivity.design import fingerprint
from hdsim.sensitivity.problem import PYTHON_WORDING, Wording


class ModelError(InputError):
    """The model is broken, not the physics: it raised a programming error, or failed on
    every row tried so far of a study where it ran on none. It is the user's model that
    fails, so the command line reports it as bad input (exit status 2) with the first failure."""


#: exceptions that mean the model's code is wrong, whatever the row: abort at once instead
#: of filling the study with failed rows
PROGRAMMING_ERRORS = ("TypeError", "AttributeError", "NameError", "ImportError", "SyntaxError",
                      "NotImplementedError")


@dataclass
class Evaluation:
    """Outputs of `evaluate`, aligned with the rows of ``X``."""

    y: np.ndarray                 # (n,) output, NaN where failed
    key: np.ndarray               # (n,) uint64 fingerprint of the inputs each output saw
    ok: np.ndarray                # (n,) bool
    failures: dict = field(default_factory=dict)   # position -> message
    evaluations: int = 0          # model row evaluations performed (incl. isolation re-runs)
    completed: int = 0            # rows whose chunk has come back


def run_chunk(func, x):
    """Worker side: evaluate one chunk; isolate failing rows if the chunk call raises.

    Parameters
    ----------
    func : callable
        The model ``f(X: (n, d)) -> (n,)``.
    x : array_like
        The chunk's rows ``(n, d)``.

    Returns
    -------
    tuple
        ``(y, key, errors, evaluations)``: outputs (NaN where failed), input
        fingerprints, local row -> error text, and model row evaluations performed.
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    key, errors, n = fingerprint(x), {}, len(x)
    try:
        y, reasons = _call(func, x)
        count = n
    except Exception:  # noqa: BLE001 - any model failure is data, not a crash
        # One bad row must not take its neighbours down: retry row by row.
        y, reasons, count = np.full(n, np.nan), {}, n
        for i in range(n):
            count += 1
            try:
                row, reason = _call(func, x[i:i + 1])
                y[i] = row[0]
                if 0 in reason:
                    reasons[i] = reason[0]
            except Exception as exc:  # noqa: BLE001
                errors[i] = _one_line(f"{_error_name(exc)}: {exc}")
    for i in np.flatnonzero(~np.isfinite(y)):
        i = int(i)
        errors.setdefault(i, _one_line(reasons[i]) if i in reasons else f"non-finite output ({y[i]})")
    return y, key, errors, count


def _one_line(text: str) -> str:
    """A failure's message as a study stores it: its first line, at most 300 characters."""
    return str(text).splitlines()[0][:300] if str(text) else ""


def _error_name(exc: BaseException) -> str:
    """The exception's class name, or the programming-error base it derives from (numpy's
    ``UFuncNoLoopError`` is a ``TypeError``), so the parent process can tell a bug in the
    model from a row whose physics failed."""
    for base in (TypeError, AttributeError, NameError, ImportError, SyntaxError, NotImplementedError):
        if isinstance(exc, base):
            return base.__name__
    return type(exc).__name__


def _call(func, x):
    """``(y, {row: reason})``: the model's outputs, and why a row came back NaN where the
    model can say (`explained`)."""
    explained = getattr(func, "explained", None)
    y, reasons = explained(x) if callable(explained) else (func(x), {})
    y = np.asarray(y, dtype=np.float64).reshape(-1)
    if y.shape != (len(x),):
        raise ValueError(f"model returned {y.size} values for {len(x)} rows")
    return y, reasons


def default_chunksize(n_rows: int) -> int:
    """Rows per task. Depends only on the design size, never on the executor."""
    return int(np.clip(n_rows // 64, 8, 512))


def _die_with_parent(parent: int | None) -> None:
    """Worker initializer: end this worker as soon as the study process is gone.

    A study killed with SIGKILL (the OOM killer, a batch scheduler) cannot shut its pool
    down; orphaned workers would live on and hold the study file through the descriptor
    they inherited at fork, so ``--resume`` would find it open. On Linux the kernel sends
    the worker SIGKILL when its parent dies (``PR_SET_PDEATHSIG``); elsewhere a daemon
    thread checks the parent every 0.2 s. ``parent`` None: the worker's parent is a fork
    server (`local_pool`), which exits when the study process does.
    """
    import os
    import threading

    if sys.platform.startswith("linux"):
        try:
            import ctypes
            import signal

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG = 1
        except (OSError, AttributeError):  # pragma: no cover - no prctl: the thread below covers it
            pass
    if parent is None:  # forked by a fork server, which ends when the study process does
        parent = os.getppid()
    if os.getppid() != parent:  # the parent died between fork and prctl
        os._exit(1)

    def watch():
        import time

        while os.getppid() == parent:
            time.sleep(0.2)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="hdsim-parent-watch").start()


def local_pool(workers: int):
    """A process pool of ``workers`` whose workers die with the study process.

    The platform's default start method is kept (fork on Linux up to Python 3.13, so
    models defined in a notebook or a script read from stdin still reach the workers),
    except after this process has run a parallel region of numba on GNU OpenMP (the
    compiled quasi-static evaluator, `hdsim.simulation.quasistatic_compiled`): GNU
    OpenMP is not fork-safe and its forked children abort ("fork() called from a process
    already using GNU OpenMP"), so the workers then start from a fork server.
    `_die_with_parent` ends every worker when the study process is killed.
    """
    import multiprocessing
    import os

    if _gnu_openmp_started():
        return cf.ProcessPoolExecutor(max_workers=workers, initializer=_die_with_parent, initargs=(None,),
                                      mp_context=multiprocessing.get_context("forkserver"))
    return cf.ProcessPoolExecutor(max_workers=workers, initializer=_die_with_parent, initargs=(os.getpid(),))


def _gnu_openmp_started() -> bool:
    """True when numba has started its OpenMP threading layer in this process."""
    numba = sys.modules.get("numba")
    if numba is None or not hasattr(numba, "threading_layer"):
        return False
    try:
        return numba.threading_layer() == "omp"
    except ValueError:  # no parallel region has run in this process yet
        return False


def check_workers(workers, wording: Wording = PYTHON_WORDING) -> None:
    """InputError unless ``workers`` is a whole number of processes, at least 1."""
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise InputError(f"{wording.workers} must be a whole number, at least 1, got {workers!r}")


@contextlib.contextmanager
def open_executor(spec: str | None = "local", workers: int = 2, wording: Wording = PYTHON_WORDING):
    """Yield an executor for ``'local'`` (None when ``workers == 1``) or ``'dask://HOST:PORT'``.

    The Dask client is imported lazily (``dask[distributed]`` is optional) and
    closed on exit; ``get_executor(pure=False)`` because identical rows must still
    run (dask would otherwise deduplicate calls it deems pure).

    Parameters
    ----------
    spec : str, optional
        ``'local'`` (default) or ``'dask://HOST:PORT'``.
    workers : int
        Processes of the local pool; 1 evaluates in-process.
    wording : Wording
        How the messages name the options (``workers``; `CLI_WORDING`: ``--workers``).

    Yields
    ------
    concurrent.futures.Executor or None
        The executor; None for in-process evaluation.

    Raises
    ------
    InputError
        On a bad spec or worker count, a missing ``distributed`` package or an
        unreachable scheduler.
    """
    check_workers(workers, wording)
    spec = (spec or "local").strip()
    if spec == "local":
        if workers == 1:
            yield None
            return
        with local_pool(workers) as pool:
            yield pool
        return
    if not spec.startswith("dask://") or len(spec) <= len("dask://"):
        raise InputError(f"{wording.executor} must be 'local' or 'dask://HOST:PORT', got '{spec}'")
    address = spec[len("dask://"):]
    if "://" not in address:
        address = "tcp://" + address
    try:
        from distributed import Client
    except ImportError:
        raise InputError(f"{wording.executor} dask:// needs dask[distributed]: "
                         "pip install 'hdsim[dask]'") from None
    try:
        client = Client(address, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise InputError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    try:
        _wait_for_a_worker(client, address)
        yield client.get_executor(pure=False)
    finally:
        client.close()


#: how long a study waits for the first worker of a Dask scheduler that has none [s]: a
#: batch system may start workers a little after the scheduler, but a scheduler without
#: any would otherwise hold the study silently for ever
DASK_WORKER_WAIT_S = 60.0


def _wait_for_a_worker(client, address: str) -> None:
    """Return once the scheduler has a worker; say that the study waits, and give up (InputError)
    after `DASK_WORKER_WAIT_S`."""
    if client.scheduler_info().get("workers"):
        return
    print(f"hdsim: the Dask scheduler at {address} has no worker yet; waiting up to "
          f"{DASK_WORKER_WAIT_S:g} s for one", file=sys.stderr)
    try:
        client.wait_for_workers(1, timeout=DASK_WORKER_WAIT_S)
    except TimeoutError:
        raise InputError(f"the Dask scheduler at {address} has no worker after {DASK_WORKER_WAIT_S:g} s: "
                         "start one (dask worker ADDRESS) or check that they reach this scheduler") from None


def evaluate(func, X, executor=None, *, workers=2, chunksize=None, rows=None,
             on_chunk=None, progress=True, max_in_flight=None, succeeded_before=0,
             wording: Wording = PYTHON_WORDING) -> Evaluation:
    """Evaluate ``func`` on the rows of ``X``; outputs land at their row positions.

    Parameters
    ----------
    func : callable
        Picklable ``f(X: (n, d)) -> (n,)``.
    X : array-like, shape (n, d)
        Anything with ``len()`` and row slicing: an ndarray, an h5py dataset, or the
        study store's lazy reader (rows are then read one chunk at a time).
    executor : concurrent.futures.Executor, optional
        Anything with ``submit(fn, *args) -> Future`` (process/thread pools, Dask's
        ``Client.get_executor()``, MPIPoolExecutor). None: a local process pool of
        ``workers`` processes, or in-process serial evaluation when ``workers == 1``.
    workers : int
        Processes of the local pool.
    chunksize : int, optional
        Rows per task; default ``func.chunksize`` if it has one, else
        `default_chunksize`.
    rows : ndarray, optional
        Labels of the rows (e.g. global indices in a study) handed to ``on_chunk``.
    on_chunk : callable, optional
        ``on_chunk(labels, y, key, errors)`` in the calling process as each chunk
        finishes (the study store writes and flushes it to disk here).
    progress : bool
        Show a progress bar on stderr when it is a terminal.
    max_in_flight : int, optional
        Most chunks submitted to ``executor`` at once (default 64), which keeps memory
        flat for huge designs.
    succeeded_before : int
        Rows of the same study that the model ran before this call (a study resumed):
        a model that ran on any row does not fail everywhere, so failing again on rows
        it had refused (``--resume --retry-failed``) does not stop the study.
    wording : Wording
        How a `ModelError` says to resume (``resume=True, retry_failed=True``; `CLI_WORDING`:
        ``--resume --retry-failed``; empty: a study without a file, which cannot resume).

    Returns
    -------
    Evaluation
        Outputs, fingerprints and failures aligned with the rows of ``X``.

    Raises
    ------
    ModelError
        When the model raises a programming error, or fails on every row of the first few
        hundred and ran on no row of the study before (``succeeded_before``).
    """
    n = len(X)
    rows = np.arange(n) if rows is None else np.asarray(rows)
    out = Evaluation(np.full(n, np.nan), np.zeros(n, np.uint64), np.zeros(n, bool))

    def collected(labels, y, key, errors):  # each chunk is written before the model is judged
        if on_chunk is not None:
            on_chunk(labels, y, key, errors)
        _abort_if_broken(out, rows, labels, errors, succeeded_before, wording.retry)

    # a model may say what chunk suits it (the simulator batches rows inside one solve)
    size = int(chunksize or getattr(func, "chunksize", None) or default_chunksize(n))
    if executor is None and workers > 1:  # a small design still reaches every local worker
        size = min(size, max(1, -(-n // workers)))
    spans = [(s, min(s + size, n)) for s in range(0, n, size)]
    bar = _progress(n, progress)
    try:
        if executor is None and workers == 1:
            for s, e in spans:
                _collect(out, s, e, run_chunk(func, _rows(X, s, e)), rows, collected, bar)
        elif executor is None:
            with local_pool(workers) as pool:
                _run_pool(pool, func, X, spans, rows, out, collected, bar, 4 * workers)
        else:
            _run_pool(executor, func, X, spans, rows, out, collected, bar, max_in_flight or 64)
    finally:
        bar.close()
    return out


#: times a chunk the executor lost is submitted again before the study gives up. Dask
#: cancels a task when the worker holding it leaves under some races, and under others the
#: task errs with an error of Dask's own (``ValueError: too many values to unpack`` when an
#: in-process worker closed under it). `run_chunk` never raises for the model (a failing row
#: is data), so an error out of a chunk is the executor's, and running the chunk again is safe
CANCELLED_CHUNK_RETRIES = 3


def _run_pool(pool, func, X, spans, rows, out, on_chunk, bar, window):
    todo, pending, cancelled = iter(spans), {}, {}

    def submit(span):
        pending[pool.submit(run_chunk, func, _rows(X, *span))] = span

    def submit_next():
        span = next(todo, None)
        if span is not None:
            submit(span)

    for _ in range(window):  # a bounded window keeps memory flat for huge designs
        submit_next()
    try:
        while pending:
            done, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for fut in done:
                span = pending.pop(fut)
                error = None if fut.cancelled() else fut.exception()
                if fut.cancelled() or error is not None:
                    # Nobody here cancelled it and the model does not raise: the executor lost
                    # it (a worker that left). Rows are pure and addressed by index, so running
                    # the chunk again is safe.
                    cancelled[span] = cancelled.get(span, 0) + 1
                    if cancelled[span] > CANCELLED_CHUNK_RETRIES:
                        if error is not None:
                            raise error
                        raise RuntimeError(
                            f"the executor cancelled the chunk of rows {rows[span[0]]}-{rows[span[1] - 1]} "
                            f"{cancelled[span]} times (workers lost?); what finished is kept, "
                            "rerun with --resume")
                    submit(span)
                    continue
                _collect(out, *span, fut.result(), rows, on_chunk, bar)
                submit_next()
    except BaseException:
        for fut in pending:
            fut.cancel()
        raise


def _rows(X, s, e) -> np.ndarray:
    return np.ascontiguousarray(X[s:e], dtype=np.float64)


def _collect(out, s, e, result, rows, on_chunk, bar):
    y, key, errors, count = result
    out.y[s:e], out.key[s:e] = y, key
    out.ok[s:e] = True
    for i, msg in errors.items():
        out.ok[s + i] = False
        out.failures[s + i] = msg
    out.evaluations += count
    out.completed += e - s
    on_chunk(rows[s:e], y, key, errors)
    bar.update(e - s)


def _abort_if_broken(out, rows, labels, errors, succeeded_before: int = 0,
                     retry: str = PYTHON_WORDING.retry):
    """ModelError for a model that is broken, not one whose physics refuses some rows (its
    advice names ``retry``, how to resume, unless that is empty): a
    programming error on any row, or every row failing, judged over the whole study. A
    resumed study that re-runs only its failed rows (``--retry-failed``) sees nothing but
    rows the model had refused; judged on those alone, a drive refusing a corner of its box
    looked like a model failing everywhere. Called after each chunk (``labels``, ``errors``
    by position in it): only the new chunk's failures are read, each once."""
    rerun = f"rerun with {retry}" if retry else "rerun"
    for i, message in errors.items():
        if message.split(":", 1)[0] in PROGRAMMING_ERRORS:
            raise ModelError(f"the model raised {message} (row {labels[i]}): a bug in the model, "
                             f"not its physics; fix it, then {rerun}")
    done = out.completed
    # Judge only once a few hundred rows are in; a whole failing region is possible.
    if not succeeded_before and done >= min(len(out.y), 256) and len(out.failures) >= done:
        first = min(out.failures)
        raise ModelError(f"the model failed on all {done} rows evaluated so far "
                         f"(first: row {rows[first]}: {out.failures[first]}); "
                         f"fix the model, then {rerun}")


def _progress(total, enabled):
    """A progress bar on a terminal, log lines elsewhere (a batch job's log, CI, a pipe)."""
    from tqdm import tqdm

    if enabled and not sys.stderr.isatty():
        return LogProgress(total)
    return tqdm(total=total, file=sys.stderr, unit="run", desc="sobol", disable=not enabled,
                dynamic_ncols=True)


class LogProgress:
    """Progress for a log without a terminal: a line per finished chunk, with the time left.

    A bar redrawn with carriage returns is unreadable in a log file, and a silent study
    of an hour looks hung. Lines come at most every ``every`` seconds (a study of many
    small chunks would otherwise flood its log), and always for the last chunk; the time
    left is the rows left at the mean rate so far.
    """

    def __init__(self, total: int, every: float = 10.0, stream=None, clock=None):
        import time

        self.total, self.done, self.every = int(total), 0, float(every)
        self.stream = stream or sys.stderr
        self.clock = clock or time.monotonic
        self.start = self.last = self.clock()

    def update(self, n: int) -> None:
        self.done += int(n)
        now = self.clock()
        if now - self.last < self.every and self.done < self.total:
            return
        self.last = now
        elapsed = now - self.start
        left = elapsed / self.done * (self.total - self.done) if self.done else float("nan")
        print(f"sobol: {self.done}/{self.total} runs ({100.0 * self.done / max(self.total, 1):.0f} %), "
              f"{elapsed:.0f} s elapsed, about {left:.0f} s left", file=self.stream, flush=True)

    def close(self) -> None:
        """Nothing to tear down (the tqdm bar's interface)."""
