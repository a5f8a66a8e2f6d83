"""Resumable HDF5 studies: SIGKILL and resume, doubling N, definition checks."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.sensitivity import Ishigami, run_study
from hdsim.sensitivity.store import DONE, PENDING

F = Ishigami()

SLOW_MODEL = textwrap.dedent("""
    import os, time
    import numpy as np
    from hdsim.sensitivity.functions import Ishigami

    _f = Ishigami()

    def slow(X):
        time.sleep(0.004 * len(X))
        # One line per evaluated row, written only after it was evaluated.
        with open(os.environ["SLOW_LOG"], "a") as fh:
            fh.write("".join(row.tobytes().hex() + "\\n" for row in X))
        return _f(X)
""")

ARGS = ["--model", "slowmodel:slow", "--params", "x1,x2,x3",
        "--bounds", "x1=-3.141592653589793:3.141592653589793",
        "x2=-3.141592653589793:3.141592653589793", "x3=-3.141592653589793:3.141592653589793",
        "--n", "256", "--seed", "5", "--workers", "2", "--chunksize", "16", "--json"]


def _run(tmp_path, out, log, extra=(), wait=True):
    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
           "SLOW_LOG": str(log)}
    cmd = [sys.executable, "-m", "hdsim", "sobol", *ARGS, "--out", str(out), *extra]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    if wait:
        stdout, stderr = proc.communicate(timeout=120)
        assert proc.returncode == 0, stderr
        return json.loads(stdout)
    return proc


def _lines(log):
    return Path(log).read_text().split() if Path(log).exists() else []


def _rows_hex(out):
    with h5py.File(out, "r") as f:
        X, status = f["X"][()], f["status"][()]
    return [row.tobytes().hex() for row in X], status


def test_sigkill_then_resume_matches_uninterrupted(tmp_path):
    (tmp_path / "slowmodel.py").write_text(SLOW_MODEL)
    total = 256 * 5
    ref = _run(tmp_path, tmp_path / "ref.h5", tmp_path / "ref.log")

    out, log = tmp_path / "cut.h5", tmp_path / "cut.log"
    proc = _run(tmp_path, out, log, wait=False)
    deadline = time.time() + 60
    while len(_lines(log)) < total // 2 and time.time() < deadline and proc.poll() is None:
        time.sleep(0.02)
    assert proc.poll() is None, "study finished before it could be killed"
    os.killpg(proc.pid, signal.SIGKILL)  # the whole job, pool workers included
    proc.wait()
    time.sleep(0.2)

    rows, status = _rows_hex(out)  # the file survived the kill and opens cleanly
    done_at_kill = {rows[i] for i in np.flatnonzero(status == DONE)}
    pending_at_kill = {rows[i] for i in np.flatnonzero(status == PENDING)}
    assert 0 < len(done_at_kill) < total
    before = _lines(log)

    resumed = _run(tmp_path, out, log, extra=["--resume"])
    after = _lines(log)[len(before):]
    assert not set(after) & done_at_kill, "a finished row was evaluated again"
    assert set(after) == pending_at_kill and len(after) == len(set(after))
    assert set(before) | set(after) == set(rows)
    # Only rows in flight at the kill (evaluated, never written) ran twice.
    assert len(before) - len(done_at_kill) <= 2 * 16 * 5

    for key in ("S1", "ST", "S1_conf", "ST_conf", "S1_conf_replicates", "ST_conf_replicates"):
        assert resumed[key] == ref[key], key
    assert resumed["evaluations"] == ref["evaluations"] == total
    assert resumed["evaluated_now"] == len(after)


def test_doubling_n_reuses_rows_and_equals_fresh_study(tmp_path):
    out = tmp_path / "s.h5"
    small = run_study(F, F.problem(), 64, out=out, workers=1, progress=False)
    assert small.evaluated_now == 64 * 5
    big = run_study(F, F.problem(), 128, out=out, resume=True, workers=1, progress=False)
    assert big.evaluated_now == 64 * 5 and big.evaluations == 128 * 5
    fresh = run_study(F, F.problem(), 128, workers=1, progress=False)
    np.testing.assert_array_equal(big.analysis["S1"], fresh.analysis["S1"])
    again = run_study(F, F.problem(), 128, out=out, resume=True, workers=1, progress=False)
    assert again.evaluated_now == 0
    # Asking for less analyses the prefix of the bigger study, evaluating nothing.
    back = run_study(F, F.problem(), 64, out=out, resume=True, workers=1, progress=False)
    assert back.evaluated_now == 0 and back.n == 64
    np.testing.assert_array_equal(back.analysis["ST"], small.analysis["ST"])


def test_store_builds_big_designs_piece_by_piece(tmp_path, monkeypatch):
    import hdsim.sensitivity.layout as layout_mod
    from hdsim.sensitivity.design import replicate_seed, sample_replicate

    monkeypatch.setattr(layout_mod, "PIECE", 8)  # 64 base points per replicate: 8 pieces
    out = tmp_path / "s.h5"
    res = run_study(F, F.problem(), 256, out=out, workers=1, progress=False)
    with h5py.File(out, "r") as f:
        X = f["X"][()]
    whole = np.concatenate([sample_replicate(F.problem(), 64, replicate_seed(0, r), False)
                            for r in range(4)])
    np.testing.assert_array_equal(X, whole)
    mem = run_study(F, F.problem(), 256, workers=1, progress=False)
    np.testing.assert_array_equal(res.analysis["ST"], mem.analysis["ST"])
    bigger = run_study(F, F.problem(), 512, out=out, resume=True, workers=1, progress=False)
    assert bigger.evaluated_now == 256 * 5


def test_store_refuses_other_definitions_and_overwrites(tmp_path):
    out = tmp_path / "s.h5"
    run_study(F, F.problem(), 64, out=out, workers=1, progress=False)
    with pytest.raises(InputError, match="exists"):
        run_study(F, F.problem(), 64, out=out, workers=1, progress=False)
    for kw in (dict(seed=1), dict(second_order=True), dict(replicates=8),
               dict(model={"function": "other"})):
        with pytest.raises(InputError, match="different study"):
            run_study(F, F.problem(), 64, out=out, resume=True, workers=1, progress=False, **kw)


def test_failures_survive_in_the_store(tmp_path):
    out = tmp_path / "s.h5"

    def broken(X):  # NaN for x1 > 3: a narrow failing region
        return np.where(X[:, 0] > 3.0, np.nan, F(X))

    res = run_study(broken, F.problem(), 64, out=out, workers=1, progress=False)
    assert res.failures and res.analysis["blocks_dropped"] > 0
    again = run_study(broken, F.problem(), 64, out=out, resume=True, workers=1, progress=False)
    assert [f["row"] for f in again.failures] == [f["row"] for f in res.failures]
    assert again.failures[0]["message"].startswith("non-finite")


def test_target_width_stops_early():
    res = run_study(F, F.problem(), 4096, workers=1, progress=False, target_width=0.2,
                    log=lambda line: None)
    widths = 2 * np.r_[res.analysis["S1_conf_replicates"], res.analysis["ST_conf_replicates"]]
    assert res.n < 4096 and widths.max() < 0.2
    assert res.evaluations == res.n * 5
