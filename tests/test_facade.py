"""The public facade: `import hdsim` names, built-in scenarios by name, `hdsim.sobol` on any
drive object (modified, fitted), and units that share no mutable state."""

from __future__ import annotations

import json
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hdsim
from hdsim.cli import main
from hdsim.errors import InputError
from hdsim.identification.fit import load_fitted
from hdsim.io.measurement import make_measurement
from hdsim.model.catalog import load_unit
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario
from hdsim.sensitivity.scenario_outputs import drive_fingerprint, model_function
from hdsim.simulation.solver import SolverOptions

ROOT = Path(__file__).resolve().parents[1]
CONTRACT_KEYS = {"output", "n", "evaluations", "params", "S1", "S1_conf", "ST", "ST_conf",
                 "seconds", "study"}
# a coarse solver keeps the runs short; the comparisons are like for like
COARSE = SolverOptions(rtol=1e-4, atol_scale=1e-4)
# the smallest design the estimator accepts: N = 8 base points in R = 2 replicates
TINY = dict(n=8, replicates=2, workers=1, progress=False)


def test_every_public_name_exists():
    assert {"load_unit", "HarmonicDrive", "run_scenario", "load_scenario", "Scenario", "Run",
            "read_run", "sobol", "load_measurement", "fit", "diagnose",
            "__version__"} <= set(hdsim.__all__)
    for name in hdsim.__all__:
        assert getattr(hdsim, name) is not None, name
    assert isinstance(hdsim.load_unit(), hdsim.HarmonicDrive)
    with pytest.raises(AttributeError):
        hdsim.no_such_name  # noqa: B018


def test_import_hdsim_leaves_solvers_hdf5_and_plotting_unloaded(tmp_path):
    code = ("import sys, hdsim; heavy = ('scipy.integrate', 'scipy.optimize', 'h5py', 'dask', "
            "'matplotlib'); print([m for m in heavy if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT), "PATH": ""}, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_run_scenario_by_name_from_any_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no scenarios/ folder here: the name is the built-in file
    # without friction and backlash: the name is tested, not the physics (0.1 s a run)
    run = hdsim.run_scenario(hdsim.load_unit().without("friction", "backlash"), "lost_motion", options=COARSE)
    reference = run_scenario(load_unit().without("friction", "backlash"),
                             load_scenario(builtin_scenario_path("lost_motion")), options=COARSE)
    assert run.metric("lost_motion_arcmin") == reference.metric("lost_motion_arcmin")
    assert run.scenario.name == "lost_motion"


def test_sobol_on_a_modified_drive_and_a_scenario_object():
    # without the micro-slip: the study's 32 rows take a second (the physics is not the point)
    drive = hdsim.load_unit("CSG-25-100").without("friction").with_updates({"backlash.gap": 2e-5})
    scenario = hdsim.load_scenario("lost_motion").with_updates({"load.cycles": 1})
    result = hdsim.sobol(drive, ["h_pz", "backlash.gap"], "lost_motion_arcmin",
                         scenario=scenario, range=0.1, **TINY)
    assert result.problem.names == ("h_pz", "backlash.gap")
    assert result.evaluations == 8 * (2 + 2) and not result.failures
    assert np.isfinite(result.analysis["S1"]).all() and np.isfinite(result.analysis["ST"]).all()
    summary = result.to_json()
    assert CONTRACT_KEYS <= set(summary) and summary["output"] == "lost_motion_arcmin"
    assert summary["model"]["unit"] == "CSG-25-100"
    assert summary["model"]["fingerprint"] == drive_fingerprint(drive, scenario, summary["model"]["evaluator"])
    # the gap is ±10 % around the modified drive's value, not the catalog's
    assert result.problem.bounds[1] == pytest.approx((1.8e-5, 2.2e-5))


def test_study_callable_pickles_with_its_drive_object():
    # a modified drive without friction and backlash: one evaluation takes 0.1 s, not 2
    drive = load_unit().without("friction", "backlash").with_updates({"flexspline.R_v": 2.0e-3})
    func = model_function(drive, ["h_pz"], "lost_motion_arcmin")
    clone = pickle.loads(pickle.dumps(func))  # what a process pool or Dask sends
    assert drive_fingerprint(clone.drive) == drive_fingerprint(drive)  # the very same drive
    assert np.isfinite(clone(np.array([[1.05e-3]]))).all()


def test_resume_with_another_drive_is_refused(tmp_path):
    study = tmp_path / "s.h5"
    # without friction and backlash the 32 rows take a second, not five
    drive = load_unit().without("friction", "backlash")
    hdsim.sobol(drive, "h_pz,h_c", "lost_motion_arcmin", out=study, **TINY)
    other = drive.with_updates({"flexspline.R_v": 2.0e-3})  # a parameter the study does not vary
    with pytest.raises(InputError):
        hdsim.sobol(other, "h_pz,h_c", "lost_motion_arcmin", out=study, resume=True, **TINY)
    again = hdsim.sobol(load_unit().without("friction", "backlash"), "h_pz,h_c", "lost_motion_arcmin",
                        out=study, resume=True, **TINY)
    assert again.evaluated_now == 0


@pytest.fixture(scope="module")
def fitted_file(tmp_path_factory):
    """A fitted-model file as ``hdsim fit --out`` writes it, fitted to the ±4 % T_N loop of a
    drive with a dead zone and without friction, evaluated quasi-statically (the evaluator
    the fit uses; the dynamic run of the lost-motion test took seconds)."""
    from hdsim.simulation.quasistatic import locked_twist

    truth = load_unit().without("friction").with_updates({"backlash.gap": 3e-5})
    T_N = float(truth.drive.rated_torque)
    t = np.linspace(0.0, 8.0, 321)  # two cycles, 40 samples a ramp
    torque = 0.04 * T_N * np.sin(2.0 * np.pi * t / 4.0)
    meas = make_measurement("stiffness", t, torque, locked_twist(truth, t, torque)[0], rated_torque=T_N)
    fitted = hdsim.fit(meas, "hardening=three_segment,backlash")
    return fitted.save(tmp_path_factory.mktemp("fit") / "fitted.toml")


def test_sobol_cli_on_a_fitted_model_file(fitted_file, tmp_path, capsys):
    import tomli_w

    # a scenario file of one load cycle: the 32 runs of the fitted dead zone take a third as long;
    # through solve_ivp, since `auto` would also run the fitted drive's stiff friction through
    # solve_ivp at rtol 1e-6 once for the quasi-static gap (3 s), which this test is not about
    scenario_file = tmp_path / "lost_motion_once.toml"
    scenario_file.write_text(tomli_w.dumps(load_scenario("lost_motion").with_updates({"load.cycles": 1}).data))
    argv = ["sobol", "--unit", str(fitted_file), "--scenario", str(scenario_file),
            "--params", "h_pz,backlash.gap", "--range", "10%", "--output", "lost_motion_arcmin",
            "--n", "8", "--replicates", "2", "--workers", "1", "--evaluator", "dynamic", "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert CONTRACT_KEYS <= set(out) and out["evaluations"] == 8 * 4
    assert out["params"] == ["h_pz", "backlash.gap"]
    fitted, scenario = load_fitted(fitted_file), load_scenario(scenario_file)
    assert out["model"]["fingerprint"] == drive_fingerprint(fitted, scenario, out["model"]["evaluator"])
    assert out["model"]["fingerprint"] != drive_fingerprint(load_unit(), scenario)


@pytest.mark.parametrize("option, value, fragment", [
    ("--unit", "missing/fitted.toml", "not found"),
    ("--scenario", "missing/test.toml", "not found"),
])
def test_sobol_cli_bad_paths_exit_2_with_one_line(option, value, fragment, capsys):
    argv = ["sobol", "--unit", "CSG-25-100", "--params", "h_pz", "--range", "10%",
            "--output", "lost_motion_arcmin", "--n", "8", "--workers", "1", option, value, "--json"]
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert captured.out == "" and len(lines) == 1 and fragment in lines[0], captured.err


def test_provenance_is_shared_read_only_and_pickles():
    unit = load_unit("CSG-20-100")
    derived = unit.with_updates({"flexspline.h_c": 0.5e-3})
    K1 = unit.provenance["catalog"]["K1"]
    with pytest.raises(TypeError):
        derived.provenance["catalog"]["K1"] = 0.0
    with pytest.raises(TypeError):
        derived.provenance["note"] = "changed"
    with pytest.raises(TypeError):
        derived.provenance.update(note="changed")
    assert load_unit("CSG-20-100").provenance["catalog"]["K1"] == K1
    assert "note" not in unit.provenance
    back = pickle.loads(pickle.dumps(derived))
    assert back.provenance == unit.provenance and back.params() == derived.params()
    json.dumps(back.provenance)  # still plain data for run files and reports
