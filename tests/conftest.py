"""Shared fixtures: expensive runs are made once per session and shared read-only.

Session fixtures (each built on first use, then reused by every test that asks):

- ``ke_run``: the shipped ``kinematic_error.toml`` on CSG-25-100 (the contract scenario,
  ~5 s); used by the physics checks, the figure checks and the result-file checks.
- ``default_lost_motion_run``, ``default_stiffness_run``: the shipped ±4 % T_N lost-motion
  and ±T_N stiffness scenarios on the default unit with its default effects.
- ``truth_stiffness``, ``truth_ke``: one independent truth measurement each
  (``tests/truth.py``, which shares no code with hdsim) as ``(columns, truth)``.

Tests must not modify what these fixtures return (runs hold numpy arrays: copy before
changing one).

``cli`` runs the console verbs in-process (``hdsim.cli.main``) and returns
``(exit code, stdout, stderr)``; only ``tests/test_console.py`` runs the verbs as subprocesses.
"""

import os

import matplotlib

matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

import pytest  # noqa: E402


@pytest.fixture(scope="session")
def ke_run():
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.run import run_scenario
    from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

    return run_scenario(load_unit("CSG-25-100"), load_scenario(builtin_scenario_path("kinematic_error")))


@pytest.fixture(scope="session")
def default_lost_motion_run():
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.run import run_scenario
    from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

    return run_scenario(load_unit(), load_scenario(builtin_scenario_path("lost_motion")))


@pytest.fixture(scope="session")
def default_stiffness_run():
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.run import run_scenario
    from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

    return run_scenario(load_unit(), load_scenario(builtin_scenario_path("stiffness")))


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
