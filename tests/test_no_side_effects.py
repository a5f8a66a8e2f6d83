"""Importing hdsim or drawing its figures never changes the user's matplotlib backend.

A library that calls ``matplotlib.use`` or imports pyplot switches the backend of the
whole process (a notebook loses its inline figures). Each check runs in a fresh
interpreter with a backend chosen by ``MPLBACKEND``, so that nothing the test process
already imported can hide a side effect.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_python(code: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, MPLBACKEND="svg", PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests")]))
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc


def test_importing_every_module_that_draws_keeps_the_backend(tmp_path):
    run_python("""
        import sys
        import matplotlib
        before = matplotlib.get_backend()
        assert before == "svg", before
        import hdsim, hdsim.cli, hdsim.plotting, hdsim.plotting.locked, hdsim.plotting.driven
        import hdsim.plotting.sensitivity, hdsim.identification.report
        assert matplotlib.get_backend() == before, matplotlib.get_backend()
        assert "matplotlib.pyplot" not in sys.modules
        """, tmp_path)


def test_figures_are_drawn_and_saved_without_pyplot(tmp_path):
    run_python("""
        import sys
        from pathlib import Path

        import matplotlib
        import numpy as np
        from matplotlib.figure import Figure

        import truth
        from hdsim.identification.diagnosis import diagnose
        from hdsim.identification.report import FIGURES
        from hdsim.io.measurement import make_measurement
        from hdsim.model.catalog import load_unit
        from hdsim.plotting import save_figure
        from hdsim.plotting.locked import plot_loop, plot_time
        from hdsim.plotting.sensitivity import plot_convergence, plot_indices
        from hdsim.scenarios.run import run_scenario
        from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

        before = matplotlib.get_backend()
        written = []

        # the figures, not the physics, are checked: one load cycle of the elastic path (no
        # micro-slip, no dead zone) is a loop to draw in a tenth of a second
        scenario = load_scenario(builtin_scenario_path("lost_motion")).with_updates({"load.cycles": 1})
        run = run_scenario(load_unit("CSG-25-100").without("friction", "backlash"), scenario)
        written.append(save_figure(plot_loop(run), "loop.png"))
        written.append(save_figure(plot_time(run), "time.png"))
        fig = Figure()
        ax = fig.add_subplot()
        assert plot_loop(run, ax=ax) is fig and ax.lines, "plot_loop must draw into the given axes"

        names = ["a", "b"]
        one = {k: np.array([0.3, 0.6]) for k in ("S1", "ST")}
        one.update({f"{k}_conf{s}": np.array([0.05, 0.05]) for k in ("S1", "ST")
                    for s in ("", "_replicates")})
        written.append(plot_indices("indices.png", names, one, analytic=one))
        rows = [dict(one, n=n) for n in (64, 128, 256)]
        written.append(plot_convergence("convergence.png", names, rows, target_width=0.1))

        cols, tr = truth.make_stiffness_data({"hardening"}, {"friction"}, seed=1, n_rows=300)
        meas = make_measurement("stiffness", cols["time_s"], cols["torque_Nm"], cols["angle_rad"],
                                rated_torque=87.0)
        diagnose(meas, "friction", families=["hardening"], max_rounds=1).report("report")
        written += [Path("report") / name for name in FIGURES]

        for path in written:
            assert Path(path).read_bytes()[:8] == b"\\x89PNG\\r\\n\\x1a\\n", path
        assert matplotlib.get_backend() == before, matplotlib.get_backend()
        assert "matplotlib.pyplot" not in sys.modules
        """, tmp_path)
    assert not list(tmp_path.glob(".*.tmp")), "a temporary file of the atomic writer was left"
