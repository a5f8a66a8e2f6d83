"""The simulation verbs: contract JSON, results on disk, and clean refusals."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hdsim.io.results import read_result

ROOT = Path(__file__).resolve().parents[1]


def hdsim(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "hdsim", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


def test_simulate_lost_motion_json_and_result(tmp_path):
    out = tmp_path / "out"
    p = hdsim("simulate", str(ROOT / "scenarios/lost_motion.toml"), "--unit", "CSG-25-100",
              "--out", str(out), "--json")
    assert p.returncode == 0, p.stderr
    payload = json.loads(p.stdout)
    assert payload["scenario"] == "lost_motion" and payload["unit"] == "CSG-25-100"
    assert set(payload) >= {"scenario", "unit", "metrics", "result"}
    stored = read_result(payload["result"])
    assert stored.metrics["lost_motion_arcmin"][0] == pytest.approx(payload["metrics"]["lost_motion_arcmin"])
    assert stored.attrs["unit"] == "CSG-25-100"
    assert stored.params["flexspline.h_pz"] > 0
    assert stored.effects["friction"] == "dahl_slip"
    assert stored.result.signals["twist_rad"].shape == (1, stored.result.t.size)
    assert (out / "lost_motion_loop.png").stat().st_size > 10_000


def test_set_changes_the_physics(tmp_path):
    base = hdsim("simulate", str(ROOT / "scenarios/lost_motion.toml"), "--set", "friction=none",
                 "--set", "backlash=none", "--out", str(tmp_path / "a"), "--json")
    thin = hdsim("simulate", str(ROOT / "scenarios/lost_motion.toml"), "--set", "friction=none",
                 "--set", "backlash=none", "--set", "flexspline.h_pz=0.9e-3",
                 "--out", str(tmp_path / "b"), "--json")
    a = json.loads(base.stdout)["metrics"]["lost_motion_arcmin"]
    b = json.loads(thin.stdout)["metrics"]["lost_motion_arcmin"]
    assert b > a  # thinner rim under the teeth: softer, more lost motion


@pytest.mark.parametrize("args, needle", [
    (["--unit", "CSG-99-100"], "unknown unit"),
    (["--set", "flexspline.h_q=1e-3"], "unknown parameter"),
    (["--set", "flexspline.h_p=2e-3"], "undercut depth"),
    (["--set", "flexspline.h_c=abc"], "not a number"),
    (["--set", "friction=dahl"], "only 'none'"),
    (["--set", "scenario.load.cycles=x"], "must be int"),
])
def test_bad_options_exit_2_one_line_nothing_written(tmp_path, args, needle):
    out = tmp_path / "out"
    p = hdsim("simulate", str(ROOT / "scenarios/lost_motion.toml"), *args, "--out", str(out), "--json")
    assert p.returncode == 2
    assert p.stdout == ""
    assert len(p.stderr.strip().splitlines()) == 1 and needle in p.stderr
    assert "Traceback" not in p.stderr
    assert not out.exists()


@pytest.mark.parametrize("text, needle", [
    ("name = 'x'\nsetup = 'locked_wave_generator'\n[load]\namplitude = 0.04\ncycles = 1\n", "missing load.rate"),
    ("name = 'x'\n[load]\namplitude = 0.04\ncycles = 1\nrate = 0.1\nbogus = 3\n", "unknown key"),
    ("name = 'x'\n[load\n", "not valid TOML"),
    ("name = 'x'\nsetup = 'spinning'\n[load]\namplitude = 0.04\ncycles = 1\nrate = 0.1\n", "unknown setup"),
    ("name = 'x'\n[load]\namplitude = -1\ncycles = 1\nrate = 0.1\n", "amplitude"),
])
def test_malformed_scenario_files(tmp_path, text, needle):
    scenario = tmp_path / "bad.toml"
    scenario.write_text(text)
    out = tmp_path / "out"
    p = hdsim("simulate", str(scenario), "--out", str(out))
    assert p.returncode == 2, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and needle in p.stderr
    assert not out.exists()


def test_missing_scenario_file(tmp_path):
    p = hdsim("simulate", str(tmp_path / "nope.toml"), "--out", str(tmp_path / "out"))
    assert p.returncode == 2 and "not found" in p.stderr


def test_units_lists_the_catalog():
    p = hdsim("units", "--json")
    data = json.loads(p.stdout)
    assert data["default"] == "CSG-25-100"
    assert set(data["units"]) >= {"CSG-14-100", "CSG-17-100", "CSG-20-100", "CSG-25-100", "CSG-32-100"}
    assert data["units"]["CSG-32-100"]["K1"] == pytest.approx(6.7e4)


def test_demo_writes_figures_and_results(tmp_path):
    p = hdsim("demo", "--json", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    assert data["elastic_lost_motion_arcmin"] < data["metrics"]["lost_motion_arcmin"] < 1.5
    names = {f.name for f in (tmp_path / "hdsim-demo").iterdir()}
    assert {"lost_motion.h5", "stiffness.h5", "lost_motion_loop.png", "stiffness_loop.png"} <= names
    stored = read_result(tmp_path / "hdsim-demo" / "stiffness.h5")
    assert np.isfinite(stored.result.signals["twist_rad"]).all()


def test_no_verb_prints_help_and_exits_2():
    p = hdsim()
    assert p.returncode == 2 and "usage" in p.stderr


def test_simulate_kinematic_error_contract(tmp_path):
    out = tmp_path / "ke"
    p = hdsim("simulate", str(ROOT / "scenarios/kinematic_error.toml"), "--unit", "CSG-25-100",
              "--out", str(out), "--json")
    assert p.returncode == 0, p.stderr
    metrics = json.loads(p.stdout)["metrics"]
    # catalog class for size 25, standard grade, ratio >= 50: 1 arcmin = 60 arcsec
    assert 0 < metrics["transmission_accuracy_arcsec"] < 60
    assert metrics["lost_motion_on_reversal_arcsec"] > 0
    assert (out / "kinematic_error_deviation.png").stat().st_size > 10_000
