"""Shared fixtures: expensive runs are made once per session and shared read-only.

Session fixtures (each built on first use, then reused by every test that asks):

- ``ke_run``: the shipped ``kinematic_error.toml`` on CSG-25-100 (the contract scenario,
  ~4 s); used by the checks of the contract scenario's numbers (test_driven_physics.py) and
  as the reference of the driven quasi-static evaluator (test_driven_quasistatic.py).
- ``default_lost_motion_run``, ``default_stiffness_run``: the shipped ±4 % T_N lost-motion
  and ±T_N stiffness scenarios on the default unit with its default effects.
- ``short_ke_run``: the contract scenario on CSG-25-100 shortened to 0.02 output
  revolutions each way (``SHORT_KE``); used by the brake check, the driven figure check
  and the driven ``simulate`` verb's output check.
- ``truth_stiffness``, ``truth_ke``: one independent truth measurement each
  (``tests/truth.py``, which shares no code with hdsim) as ``(columns, truth)``.

Tests must not modify what these fixtures return (runs hold numpy arrays: copy before
changing one). Under pytest-xdist the four runs are made once for all workers: the first
worker to ask makes the run, the others read its pickle (``_once_per_session``).

``cli`` runs the console verbs in-process (``hdsim.cli.main``) and returns
``(exit code, stdout, stderr)``; only ``tests/test_console.py`` runs the verbs as subprocesses.
"""

import fcntl
import os
import pickle

# Under pytest-xdist each worker gets its share of the cores for BLAS, OpenMP (numba's
# prange) and numba threads. With two workers on two cores, each worker's two OpenBLAS
# threads spin against the other worker's: a 4500 × 20 least-squares solve took 116 ms
# instead of 1.5 ms, and the running-torque diagnosis (~900 of them) half a minute.
# The variables reach numba (imported later) and the subprocesses the tests start;
# numpy's OpenBLAS is already loaded by pytest's plugins, so it is limited in place.
_WORKERS = os.environ.get("PYTEST_XDIST_WORKER_COUNT")
if _WORKERS:
    _THREADS = max(1, (os.cpu_count() or 1) // int(_WORKERS))
    for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(_name, str(_THREADS))
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=_THREADS)

import matplotlib  # noqa: E402

matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

import pytest  # noqa: E402


def _once_per_session(tmp_path_factory, name, make):
    """``make()`` once per test session, across pytest-xdist workers too.

    Each worker has its own session fixtures, so a run that tests on both workers ask for
    was made twice (the contract run: ~10 s each). Here the first worker to ask makes it
    and pickles it into the session's temporary folder, which all workers share (the
    recipe of the pytest-xdist documentation, locked with ``fcntl``); the others wait for
    it and read it. Without xdist it is simply ``make()``.
    """
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        return make()
    shared = tmp_path_factory.getbasetemp().parent
    path = shared / f"{name}.pickle"
    with open(shared / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if path.is_file():
            return pickle.loads(path.read_bytes())
        value = make()
        path.with_suffix(".tmp").write_bytes(pickle.dumps(value))
        path.with_suffix(".tmp").replace(path)
        return value


def _builtin_run(unit_name, scenario_name, updates=None):
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.run import run_scenario
    from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

    scenario = load_scenario(builtin_scenario_path(scenario_name))
    return run_scenario(load_unit(unit_name), scenario.with_updates(updates) if updates else scenario)


#: the contract scenario shortened (the same profile, less travel): ``short_ke_run``
SHORT_KE = {"input.output_revolutions": 0.02, "input.settle_revolutions": 0.01}


@pytest.fixture(scope="session")
def ke_run(tmp_path_factory):
    return _once_per_session(tmp_path_factory, "ke_run", lambda: _builtin_run("CSG-25-100", "kinematic_error"))


@pytest.fixture(scope="session")
def short_ke_run(tmp_path_factory):
    return _once_per_session(tmp_path_factory, "short_ke_run",
                             lambda: _builtin_run("CSG-25-100", "kinematic_error", SHORT_KE))


@pytest.fixture(scope="session")
def default_lost_motion_run(tmp_path_factory):
    return _once_per_session(tmp_path_factory, "default_lost_motion_run", lambda: _builtin_run(None, "lost_motion"))


@pytest.fixture(scope="session")
def default_stiffness_run(tmp_path_factory):
    return _once_per_session(tmp_path_factory, "default_stiffness_run", lambda: _builtin_run(None, "stiffness"))


@pytest.fixture(scope="session")
def truth_stiffness():
    """Truth stiffness test with hidden (Bouc–Wen) friction, 300 rows (seed 4)."""
    import truth

    return truth.make_stiffness_data({"friction"}, set(), seed=4, n_rows=300)


@pytest.fixture(scope="session")
def truth_ke():
    """Truth kinematic-error test with the (von-Mises) kinematic error hidden, 3000 rows (seed 2)."""
    import truth

    return truth.make_ke_data({"kinematic_error"}, set(), seed=2, n_rows=3000)


@pytest.fixture
def cli(capsys, monkeypatch):
    """``cli(*args, cwd=None) -> (code, out, err)``: ``hdsim ARGS`` in this process."""
    from hdsim.cli import main

    def run(*args, cwd=None):
        if cwd is not None:
            monkeypatch.chdir(cwd)
        capsys.readouterr()  # drop anything printed before
        code = main([str(a) for a in args])
        out = capsys.readouterr()
        return code, out.out, out.err

    return run


@pytest.fixture(scope="session")
def png_image():
    """``png_image(path) -> (height, width)``: asserts the file is a PNG that decodes to a
    drawn image (not one flat colour) and returns its size in pixels."""
    import numpy as np
    from matplotlib import image

    def check(path):
        with open(path, "rb") as handle:
            assert handle.read(8) == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
        pixels = image.imread(path)
        assert pixels.ndim == 3 and pixels.shape[0] > 100 and pixels.shape[1] > 100, pixels.shape
        assert np.ptp(pixels[..., :3]) > 0.5, f"{path} is blank"
        # something is drawn over more than a frame: many rows hold a dark pixel
        dark = (pixels[..., :3].mean(axis=2) < 0.5).any(axis=1)
        assert dark.mean() > 0.3, f"{path} holds almost nothing"
        return pixels.shape[:2]

    return check
