"""One subprocess smoke test per verb: the installed ``hdsim`` console script and
``python -m hdsim`` really start, dispatch, print one JSON object and exit with the
contract's status. Everything else about the verbs is tested in-process
(``hdsim.cli.main``) in the other files, which is ~1 s cheaper per call. The demo's, which
makes its two default-unit runs itself, is in the ``-m slow`` set.
"""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from demo_checks import check_demo
from hdsim.model.catalog import load_unit
from hdsim.units import rad_to_arcmin

ROOT = Path(__file__).resolve().parents[1]


def console(*args, cwd=None, module=False):
    """Run ``hdsim ARGS`` (the console script; ``python -m hdsim`` with ``module``)."""
    script = shutil.which("hdsim")
    if module or script is None:
        command = [sys.executable, "-m", "hdsim"]
    else:
        command = [script]
    return subprocess.run(command + [str(a) for a in args], capture_output=True, text=True, cwd=cwd,
                          timeout=300)


def test_units_console_script():
    p = console("units", "--json")
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    assert data["default"] == "CSG-25-100" and data["units"]["CSG-25-100"]["K1"] == 3.1e4


def test_simulate_module(tmp_path):
    p = console("simulate", ROOT / "scenarios/lost_motion.toml", "--set", "friction=none", "--set", "backlash=none",
                "--no-figures", "--out", tmp_path, "--json", module=True)
    assert p.returncode == 0, p.stderr
    payload = json.loads(p.stdout)
    unit = load_unit()
    elastic = rad_to_arcmin(0.08 * float(unit.drive.rated_torque) / float(unit.base_stiffness))
    assert payload["metrics"]["lost_motion_arcmin"] == pytest.approx(elastic, rel=1e-3)
    assert Path(payload["result"]).is_file()


@pytest.mark.slow(reason="10 s: the demo's two default-unit runs in a fresh process; the default run "
                  "checks the verb in-process on the shared runs (test_cli_simulate.py::"
                  "test_demo_writes_both_default_unit_tests) and the console script with the other verbs")
def test_demo_console_script(tmp_path, png_image):
    """The README's main job, for real: both default-unit tests, figures and results."""
    p = console("demo", "--json", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    check_demo(json.loads(p.stdout), tmp_path / "hdsim-demo", png_image)


def test_sobol_module():
    p = console("sobol", "--function", "ishigami", "--n", "64", "--workers", "1", "--json", module=True)
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    assert data["evaluations"] == 64 * (3 + 2) and data["params"] == ["x1", "x2", "x3"]


def test_fit_console_script(tmp_path, truth_stiffness):
    import truth

    cols, tr = truth_stiffness
    truth.write_csv(tmp_path / "bench.csv", cols, tr["meta"])
    p = console("fit", "bench.csv", "--effects", "friction", "--json", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    summary = json.loads(p.stdout)
    assert summary["effects"] == ["friction"]
    assert abs(summary["offset_rad"] - tr["params"]["offset_rad"]) < 1e-5
    assert (tmp_path / "bench.fit.toml").is_file()


def test_diagnose_module_exit_status(tmp_path):
    """A refused file: exit status 2, one line on stderr, no traceback, nothing written."""
    rows = "".join(f"{i},{'nan' if i == 4 else 1},0\n" for i in range(12))
    (tmp_path / "bad.csv").write_text("# test: stiffness\ntime_s,torque_Nm,angle_rad\n" + rows)
    p = console("diagnose", "bad.csv", "--json", cwd=tmp_path, module=True)
    assert p.returncode == 2 and p.stdout == ""
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert sorted(x.name for x in tmp_path.iterdir()) == ["bad.csv"]


def test_a_reader_that_stops_reading_is_no_internal_error():
    """`hdsim units | true` said "internal error: BrokenPipeError ... a bug in hdsim" (exit 1)
    every time: the reader closing the pipe is neither bad input nor a failure of hdsim."""
    import subprocess
    import sys

    done = subprocess.run(["bash", "-c", f"set -o pipefail; '{sys.executable}' -m hdsim units | true"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "internal error" not in done.stderr, done.stderr
