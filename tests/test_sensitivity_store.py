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
from hdsim.sensitivity import Ishigami, ModelError, run_study
from hdsim.sensitivity.store import DONE, PENDING

F = Ishigami()

SLOW_MODEL = textwrap.dedent("""
    import os, time
    import numpy as np
    from hdsim.sensitivity.functions import Ishigami

    _f = Ishigami()

    def slow(X):
        time.sleep(float(os.environ.get("SLOW_SLEEP", "0.004")) * len(X))
        # One line per evaluated row, written only after it was evaluated.
        with open(os.environ["SLOW_LOG"], "a") as fh:
            fh.write("".join(row.tobytes().hex() + "\\n" for row in X))
        return _f(X)
""")

ARGS = ["--model", "slowmodel:slow", "--params", "x1,x2,x3",
        "--bounds", "x1=-3.141592653589793:3.141592653589793",
        "x2=-3.141592653589793:3.141592653589793", "x3=-3.141592653589793:3.141592653589793",
        "--n", "256", "--seed", "5", "--workers", "2", "--chunksize", "16", "--json"]


def _run(tmp_path, out, log, extra=(), wait=True, sleep=0.004):
    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
           "SLOW_LOG": str(log), "SLOW_SLEEP": str(sleep)}
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


@pytest.mark.slow(reason="14 s of wall time in four subprocesses; the in-process "
                  "test_interrupted_cli_study_resumes_without_redoing_rows covers resume in the default "
                  "run; to be rebuilt as a faster real-kill test")
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


def _run_here(tmp_path, monkeypatch, capsys, out, log, extra=()):
    """`_run` in this process, one worker and no sleep: the reference study and the resume
    (the indices do not depend on the workers; a subprocess with its pool costs seconds)."""
    import importlib.util

    from hdsim.cli import main

    if "slowmodel" not in sys.modules:  # this test's copy, importable until the test ends
        spec = importlib.util.spec_from_file_location("slowmodel", tmp_path / "slowmodel.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        monkeypatch.setitem(sys.modules, "slowmodel", module)
    monkeypatch.setenv("SLOW_LOG", str(log))
    monkeypatch.setenv("SLOW_SLEEP", "0")
    capsys.readouterr()
    assert main(["sobol", *ARGS, "--out", str(out), *extra, "--workers", "1"]) == 0
    return json.loads(capsys.readouterr().out)


def test_main_process_killed_workers_die_and_study_resumes_at_once(tmp_path, monkeypatch, capsys):
    """What the OOM killer or a batch scheduler does: SIGKILL of the study process only.

    The two pool workers must not outlive it (they would hold the study file), and
    ``--resume`` one second later finishes with the indices of an uninterrupted study
    and no finished row evaluated twice. The killed study runs as a subprocess with its
    pool; the reference and the resume run in this process."""
    psutil = pytest.importorskip("psutil")
    (tmp_path / "slowmodel.py").write_text(SLOW_MODEL)
    small = ["--n", "128"]  # after ARGS' --n 256: argparse keeps the last
    total = 128 * 5
    ref = _run_here(tmp_path, monkeypatch, capsys, tmp_path / "ref.h5", tmp_path / "ref.log", extra=small)

    out, log = tmp_path / "cut.h5", tmp_path / "cut.log"
    proc = _run(tmp_path, out, log, extra=small, wait=False, sleep=0.006)
    deadline = time.time() + 60
    while len(_lines(log)) < total // 3 and time.time() < deadline and proc.poll() is None:
        time.sleep(0.02)
    assert proc.poll() is None, "study finished before it could be killed"
    workers = psutil.Process(proc.pid).children(recursive=True)
    assert len(workers) >= 2
    os.kill(proc.pid, signal.SIGKILL)  # the main process only, as the OOM killer does
    proc.wait()
    _, alive = psutil.wait_procs(workers, timeout=1.0)

    def running(p):  # a zombie has exited and holds no file; only its exit status is left
        try:
            return p.status() != psutil.STATUS_ZOMBIE
        except psutil.NoSuchProcess:
            return False

    alive = [p for p in alive if running(p)]
    assert not alive, f"pool workers outlived the study: {[p.pid for p in alive]}"

    rows, status = _rows_hex(out)
    done_at_kill = {rows[i] for i in np.flatnonzero(status == DONE)}
    before = _lines(log)
    resumed = _run_here(tmp_path, monkeypatch, capsys, out, log, extra=[*small, "--resume"])  # within the second
    after = _lines(log)[len(before):]
    assert not set(after) & done_at_kill, "a finished row was evaluated again"
    for key in ("S1", "ST", "S1_conf", "ST_conf"):
        assert resumed[key] == ref[key], key
    assert resumed["evaluations"] == total


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


@pytest.mark.parametrize("damage", ["definition", "status", "failures"])
def test_a_damaged_study_file_is_refused_as_bad_input(tmp_path, damage):
    """A study file edited or cut by hand had ended in a JSONDecodeError or a KeyError, reported
    as a bug in hdsim (exit 1)."""
    out = tmp_path / "s.h5"
    run_study(F, F.problem(), 64, out=out, workers=1, progress=False)
    with h5py.File(out, "r+") as f:
        if damage == "definition":
            f.attrs["definition"] = "{bad json"
        elif damage == "status":
            del f["status"]
        else:
            f.create_group("failures")  # the group without its row and message datasets
    with pytest.raises(InputError, match="is a damaged study file"):
        run_study(F, F.problem(), 64, out=out, resume=True, workers=1, progress=False)


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
    assert res.to_json()["target_width"] == {"target": 0.2, "widest": pytest.approx(widths.max()), "reached": True}


def test_a_target_width_not_reached_says_so_in_the_result():
    """It had been said on stderr only, beside checks that all passed."""
    res = run_study(F, F.problem(), 64, workers=1, progress=False, target_width=1e-4, log=lambda line: None)
    widths = 2 * np.r_[res.analysis["S1_conf_replicates"], res.analysis["ST_conf_replicates"]]
    assert res.to_json()["target_width"] == {"target": 1e-4, "widest": pytest.approx(widths.max()), "reached": False}


# --------------------------------------------------------------------------- in-process resume
STEP_MODEL = textwrap.dedent("""
    import os
    import numpy as np
    from hdsim.sensitivity.functions import Ishigami

    _f = Ishigami()
    calls = 0

    def model(X):
        # Ishigami, logging each evaluated row; Ctrl-C after STOP_AFTER calls; NaN where
        # x1 > FAIL_ABOVE (both switches read from the environment on every call)
        global calls
        calls += 1
        stop = int(os.environ.get("STOP_AFTER", "0"))
        if stop and calls > stop:
            raise KeyboardInterrupt
        with open(os.environ["ROW_LOG"], "a") as fh:
            fh.write("".join(row.tobytes().hex() + "\\n" for row in X))
        y = _f(X)
        if "FAIL_ABOVE" in os.environ:
            y = np.where(X[:, 0] > float(os.environ["FAIL_ABOVE"]), np.nan, y)
        return y
""")
PI = "3.141592653589793"
STEP_ARGS = ["--params", "x1,x2,x3", "--bounds", f"x1=-{PI}:{PI}", f"x2=-{PI}:{PI}", f"x3=-{PI}:{PI}",
             "--seed", "5", "--workers", "1", "--chunksize", "8", "--json"]


@pytest.fixture
def step_model(tmp_path, monkeypatch, request):
    """(module, run) — ``run(out, *extra) -> (code, json or None, stderr)`` through
    ``hdsim.cli.main`` with a fresh copy of STEP_MODEL importable as a unique module."""
    import importlib

    from hdsim.cli import main

    name = f"step_model_{request.node.name.split('[')[0]}"
    (tmp_path / f"{name}.py").write_text(STEP_MODEL)
    monkeypatch.syspath_prepend(str(tmp_path))
    module = importlib.import_module(name)
    monkeypatch.setenv("ROW_LOG", str(tmp_path / "rows.log"))
    capsys = request.getfixturevalue("capsys")

    def run(out, n, *extra):
        module.calls = 0
        capsys.readouterr()
        code = main(["sobol", "--model", f"{name}:model", *STEP_ARGS, "--n", str(n), "--out", str(out), *extra])
        captured = capsys.readouterr()
        return code, (json.loads(captured.out) if code == 0 else None), captured.err

    yield module, run
    sys.modules.pop(name, None)


KEYS = ("S1", "ST", "S1_conf", "ST_conf", "S1_conf_replicates", "ST_conf_replicates")


def test_interrupted_cli_study_resumes_without_redoing_rows(tmp_path, monkeypatch, step_model):
    """Ctrl-C after 30 of 80 chunks: the 240 finished rows are on disk, resume evaluates
    exactly the other 400, and the indices equal an uninterrupted study's bit for bit."""
    _, run = step_model
    log = tmp_path / "rows.log"
    code, ref, err = run(tmp_path / "ref.h5", 128)
    assert code == 0, err
    log.unlink()

    monkeypatch.setenv("STOP_AFTER", "30")
    code, _, err = run(tmp_path / "cut.h5", 128)
    assert code == 1 and "interrupted" in err
    rows, status = _rows_hex(tmp_path / "cut.h5")
    done = {rows[i] for i in np.flatnonzero(status == DONE)}
    assert len(done) == 30 * 8 and int((status == PENDING).sum()) == 128 * 5 - 240
    before = _lines(log)
    assert set(before) == done  # in-process, a chunk is written before the next one starts

    monkeypatch.delenv("STOP_AFTER")
    code, resumed, err = run(tmp_path / "cut.h5", 128, "--resume")
    assert code == 0, err
    after = _lines(log)[len(before):]
    assert not set(after) & done and len(after) == len(set(after)) == 128 * 5 - 240
    assert set(before) | set(after) == set(rows)
    assert resumed["evaluated_now"] == len(after) and resumed["evaluations"] == 128 * 5
    for key in KEYS:
        assert resumed[key] == ref[key], key


def test_resume_retry_failed_reruns_only_the_failed_rows(tmp_path, monkeypatch, step_model):
    """``hdsim sobol --resume --retry-failed``: rows that failed (NaN for x1 > 2.5) are
    kept as failed by a plain resume and re-evaluated, alone, with --retry-failed; once
    they succeed the study equals one that never failed."""
    _, run = step_model
    code, healthy, err = run(tmp_path / "healthy.h5", 64)
    assert code == 0, err

    monkeypatch.setenv("FAIL_ABOVE", "2.5")
    code, failing, err = run(tmp_path / "s.h5", 64)
    assert code == 0, err
    failed = [f["row"] for f in failing["failures"]]
    assert failed and failing["blocks_dropped"] > 0
    assert all(f["params"]["x1"] > 2.5 and f["message"].startswith("non-finite") for f in failing["failures"])
    assert "dropped" in err

    monkeypatch.delenv("FAIL_ABOVE")
    code, plain, _ = run(tmp_path / "s.h5", 64, "--resume")
    assert plain["evaluated_now"] == 0 and [f["row"] for f in plain["failures"]] == failed

    log_before = _lines(tmp_path / "rows.log")
    code, retried, err = run(tmp_path / "s.h5", 64, "--resume", "--retry-failed")
    assert code == 0, err
    rerun = _lines(tmp_path / "rows.log")[len(log_before):]
    rows, status = _rows_hex(tmp_path / "s.h5")
    assert sorted(rerun) == sorted(rows[g] for g in failed)  # the failed rows, nothing else
    assert retried["evaluated_now"] == len(failed)
    assert retried["failures"] == [] and retried["blocks_dropped"] == 0 and np.all(status == DONE)
    for key in KEYS:
        assert retried[key] == healthy[key], key


class _RefusesACorner:
    """Ishigami that refuses the rows with x1 > 2.5 as the simulator refuses a geometry:
    NaN with a reason, every time it is asked."""

    def __call__(self, X):
        return self.explained(X)[0]

    def explained(self, X):
        refused = np.flatnonzero(X[:, 0] > 2.5)
        return np.where(X[:, 0] > 2.5, np.nan, F(X)), {int(i): "refused: x1 above 2.5" for i in refused}


def test_retrying_rows_the_model_refuses_again_is_no_broken_model(tmp_path):
    """``--resume --retry-failed`` re-runs only the failed rows; that they fail again had been
    judged alone, as a model failing on every row, and stopped the study. A model that ran
    on no row of the study is still stopped."""
    f, out = _RefusesACorner(), tmp_path / "s.h5"
    first = run_study(f, F.problem(), 64, workers=1, out=out, progress=False, log=lambda line: None)
    assert 0 < len(first.failures) < 256 and first.failures[0]["message"] == "refused: x1 above 2.5"
    again = run_study(f, F.problem(), 64, workers=1, out=out, resume=True, retry_failed=True,
                      progress=False, log=lambda line: None)
    assert again.evaluated_now == len(first.failures) and again.failures == first.failures
    with pytest.raises(ModelError, match="failed on all"):
        run_study(lambda X: np.full(len(X), np.nan), F.problem(), 16, workers=1, progress=False,
                  log=lambda line: None)


# --------------------------------------------------------------------------- store I/O
def test_store_writes_and_reads_evaluated_rows(tmp_path):
    """The study store: outputs land at their rows (also scattered rows), the status and
    failure messages survive closing and reopening, and pending/failed rows are told apart."""
    from hdsim.sensitivity.design import fingerprint, replicate_seed, sample_replicate
    from hdsim.sensitivity.store import FAILED, open_store

    definition = {"problem": F.problem().to_dict(), "seed": 3, "second_order": False, "replicates": 4,
                  "model": {"function": "ishigami"}}
    path = tmp_path / "s.h5"
    store = open_store(definition, 64, path)
    all_rows = store.pending(64)
    assert len(all_rows) == 64 * 5 and store.counts() == {"done": 0, "failed": 0, "pending": 320}
    # the stored design is the replicate-major Saltelli design of the definition
    design = np.concatenate([sample_replicate(F.problem(), 16, replicate_seed(3, r), False) for r in range(4)])
    np.testing.assert_array_equal(store.read("X", all_rows), design)
    rows = np.array([5, 6, 7, 40, 41, 300])  # three runs of rows
    X = store.read("X", rows)
    y = F(X)
    store.write(rows, y, fingerprint(X), {4: "solver gave up"})
    store.save_failures()
    store.close()

    again = open_store(definition, 64, path, resume=True)
    try:
        np.testing.assert_array_equal(again.read("Y", rows), y)
        np.testing.assert_array_equal(again.read("key", rows), fingerprint(design[rows]))
        status = again.read("status", rows)
        assert status.tolist() == [DONE, DONE, DONE, DONE, FAILED, DONE]
        assert again.failures(64) == {41: "solver gave up"}
        assert again.counts() == {"done": 5, "failed": 1, "pending": 314}
        pending = again.pending(64)
        assert len(pending) == 314 and not set(rows) & set(pending.tolist())
        assert set(again.pending(64, retry_failed=True).tolist()) == set(pending.tolist()) | {41}
        untouched = np.setdiff1d(all_rows, rows)
        assert np.all(np.isnan(again.read("Y", untouched)))
        # the lazy reader hands out design rows by position
        reader = again.reader(pending)
        assert len(reader) == 314
        np.testing.assert_array_equal(reader[10:13], design[pending[10:13]])
    finally:
        again.close()
