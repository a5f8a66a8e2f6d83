"""Chunks that an executor loses (a Dask worker leaving cancels the tasks it held, or under
some races makes them err) run again; rows land at their index whatever the order."""

import concurrent.futures as cf

import numpy as np
import pytest

from hdsim.sensitivity import Ishigami, evaluate


class CancellingExecutor(cf.Executor):
    """Runs tasks at once, but hands back a cancelled future (or, with ``error``, one that
    raised it) for the first ``times`` submissions of the chunk that starts with row ``row``
    (compared by value)."""

    def __init__(self, X, row, times, error=None):
        self.first_row, self.times, self.submitted, self.error = X[row], times, 0, error

    def submit(self, fn, *args):
        self.submitted += 1
        fut = cf.Future()
        chunk = args[1]
        if self.times and np.array_equal(chunk[0], self.first_row):
            self.times -= 1
            if self.error is not None:
                fut.set_running_or_notify_cancel()
                fut.set_exception(self.error)
                return fut
            fut.cancel()
            fut.set_running_or_notify_cancel()  # as Dask's wrapper does, so wait() wakes
            return fut
        fut.set_result(fn(*args))
        return fut


def test_a_chunk_the_executor_cancelled_runs_again_and_lands_at_its_rows():
    model = Ishigami()
    X = np.random.default_rng(0).uniform(-np.pi, np.pi, (40, 3))
    pool = CancellingExecutor(X, row=16, times=2)
    out = evaluate(model, X, pool, chunksize=8, progress=False)
    np.testing.assert_array_equal(out.y, model(X))
    assert out.ok.all() and out.completed == 40
    assert pool.submitted == 5 + 2  # five chunks, one of them submitted twice more


def test_a_chunk_cancelled_again_and_again_stops_the_study_with_a_message():
    X = np.random.default_rng(0).uniform(-np.pi, np.pi, (40, 3))
    with pytest.raises(RuntimeError, match="cancelled the chunk of rows 16-23 4 times"):
        evaluate(Ishigami(), X, CancellingExecutor(X, row=16, times=10), chunksize=8, progress=False)


def test_a_chunk_the_executor_failed_runs_again_and_a_failure_that_stays_is_raised():
    model = Ishigami()
    X = np.random.default_rng(0).uniform(-np.pi, np.pi, (40, 3))
    lost = ValueError("too many values to unpack (expected 3)")  # Dask's, from a worker closed under it
    pool = CancellingExecutor(X, row=16, times=2, error=lost)
    out = evaluate(model, X, pool, chunksize=8, progress=False)
    np.testing.assert_array_equal(out.y, model(X))
    assert pool.submitted == 5 + 2
    with pytest.raises(ValueError, match="too many values"):
        evaluate(model, X, CancellingExecutor(X, row=16, times=10, error=lost), chunksize=8, progress=False)


def test_a_log_without_a_terminal_gets_a_line_per_chunk_with_the_time_left():
    import io

    from hdsim.sensitivity.evaluate import LogProgress

    ticks = iter([0.0, 2.0, 4.0, 30.0, 31.0])  # start, then one clock reading per chunk
    log = io.StringIO()
    progress = LogProgress(400, every=10.0, stream=log, clock=lambda: next(ticks))
    for _ in range(4):
        progress.update(100)
    lines = log.getvalue().splitlines()
    # 2 s and 4 s: under the 10 s spacing, silent; 30 s: a line; the last chunk: always
    assert lines == ["sobol: 300/400 runs (75 %), 30 s elapsed, about 10 s left",
                     "sobol: 400/400 runs (100 %), 31 s elapsed, about 0 s left"]
