"""The simulation verbs in-process (``hdsim.cli.main``): contract JSON, results on disk,
clean refusals. The console script itself is exercised once per verb in ``test_console.py``."""

import json
from pathlib import Path

import numpy as np
import pytest

from demo_checks import check_demo
from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import catalog_entry, unit_names
from hdsim.scenarios.run import read_run, run_scenario
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario
from hdsim.units import rad_to_arcmin

ROOT = Path(__file__).resolve().parents[1]
LOST_MOTION = str(ROOT / "scenarios/lost_motion.toml")


def test_simulate_lost_motion_json_and_result(tmp_path, cli, png_image):
    out = tmp_path / "out"
    # one load cycle instead of two (the second retraces the first): 0.6 of the time, the
    # lost motion within 1e-5 of the closed form either way
    code, stdout, err = cli("simulate", LOST_MOTION, "--unit", "CSG-25-100", "--set", "friction=none",
                            "--set", "scenario.load.cycles=1", "--out", out, "--json")
    assert code == 0, err
    payload = json.loads(stdout)
    assert payload["scenario"] == "lost_motion" and payload["unit"] == "CSG-25-100"
    assert set(payload) >= {"scenario", "unit", "metrics", "result"}
    # closed form: the elastic ±4 % span 0.08·T_N/K1 plus the backlash gap
    unit, cat = load_unit("CSG-25-100"), catalog_entry("CSG-25-100")
    expected = rad_to_arcmin(0.08 * cat["rated_torque"] / cat["K1"] + float(unit.backlash.gap))
    assert payload["metrics"]["lost_motion_arcmin"] == pytest.approx(expected, rel=2e-3)
    stored = read_run(payload["result"])
    assert stored.metrics["lost_motion_arcmin"][0] == pytest.approx(payload["metrics"]["lost_motion_arcmin"])
    assert stored.model.name == "CSG-25-100" and stored.scenario.name == "lost_motion"
    assert stored.model.params()["flexspline.h_pz"] == pytest.approx(unit.params()["flexspline.h_pz"])
    assert {k: e.id for k, e in stored.model.effects().items()} == {**{k: e.id for k, e in unit.effects().items()},
                                                                 "friction": "none"}
    assert stored.result.signals["twist_rad"].shape == (1, stored.result.t.size)
    png_image(out / "lost_motion_loop.png")
    png_image(out / "lost_motion_time.png")


def test_set_changes_the_physics(tmp_path, cli):
    """--set reaches the model: with friction and backlash off the ±4 % span is the elastic
    2A/K with K the closed-form stiffness of the changed geometry."""
    common = ("simulate", LOST_MOTION, "--set", "friction=none", "--set", "backlash=none", "--no-figures", "--json")
    _, base, _ = cli(*common, "--out", tmp_path / "a")
    _, thin, _ = cli(*common, "--set", "flexspline.h_pz=0.9e-3", "--out", tmp_path / "b")
    a = json.loads(base)["metrics"]["lost_motion_arcmin"]
    b = json.loads(thin)["metrics"]["lost_motion_arcmin"]
    unit = load_unit()
    T_N = float(unit.drive.rated_torque)
    K_thin = float(unit.with_updates({"flexspline.h_pz": 0.9e-3}).base_stiffness)
    assert a == pytest.approx(rad_to_arcmin(0.08 * T_N / float(unit.base_stiffness)), rel=1e-3)
    assert b == pytest.approx(rad_to_arcmin(0.08 * T_N / K_thin), rel=1e-3)
    assert b > 1.05 * a  # thinner rim under the teeth: softer, more lost motion


@pytest.mark.parametrize("args, needle", [
    (["--unit", "CSG-99-100"], "unknown unit"),
    (["--set", "flexspline.h_q=1e-3"], "unknown parameter"),
    (["--set", "flexspline.h_p=2e-3"], "undercut depth"),
    (["--set", "flexspline.h_c=abc"], "not a number"),
    (["--set", "friction=dahl"], "only 'none'"),
    (["--set", "scenario.load.cycles=x"], "must be int"),
])
def test_bad_options_exit_2_one_line_nothing_written(tmp_path, cli, args, needle):
    out = tmp_path / "out"
    code, stdout, err = cli("simulate", LOST_MOTION, *args, "--out", out, "--json")
    assert code == 2
    assert stdout == ""
    assert len(err.strip().splitlines()) == 1 and needle in err
    assert not out.exists()


@pytest.mark.parametrize("text, needle", [
    ("name = 'x'\nsetup = 'locked_wave_generator'\n[load]\namplitude = 0.04\ncycles = 1\n", "missing load.rate"),
    ("name = 'x'\n[load]\namplitude = 0.04\ncycles = 1\nrate = 0.1\nbogus = 3\n", "unknown key"),
    ("name = 'x'\n[load\n", "not valid TOML"),
    ("name = 'x'\nsetup = 'spinning'\n[load]\namplitude = 0.04\ncycles = 1\nrate = 0.1\n", "unknown setup"),
    ("name = 'x'\n[load]\namplitude = -1\ncycles = 1\nrate = 0.1\n", "amplitude"),
])
def test_malformed_scenario_files(tmp_path, cli, text, needle):
    scenario = tmp_path / "bad.toml"
    scenario.write_text(text)
    out = tmp_path / "out"
    code, stdout, err = cli("simulate", scenario, "--out", out)
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and needle in err
    assert stdout == "" and not out.exists()


def test_missing_scenario_file(tmp_path, cli):
    code, _, err = cli("simulate", tmp_path / "nope.toml", "--out", tmp_path / "out")
    assert code == 2 and "not found" in err


def test_units_lists_the_catalog(cli):
    code, stdout, _ = cli("units", "--json")
    assert code == 0
    data = json.loads(stdout)
    assert data["default"] == "CSG-25-100"
    assert list(data["units"]) == unit_names()
    assert set(data["units"]) >= {"CSG-14-100", "CSG-17-100", "CSG-20-100", "CSG-25-100", "CSG-32-100"}
    # the catalog values (reference table 2.1): size 32, T_N 178 N·m, K1..K3
    assert data["units"]["CSG-32-100"]["rated_torque"] == 178.0
    assert [data["units"]["CSG-32-100"][k] for k in ("K1", "K2", "K3")] == [6.7e4, 11.0e4, 12.0e4]
    code, table, _ = cli("units")
    assert code == 0 and "CSG-25-100" in table and "(default)" in table


def test_demo_writes_both_default_unit_tests(tmp_path, cli, monkeypatch, png_image, default_lost_motion_run,
                                            default_stiffness_run):
    """``hdsim demo`` in-process: its summary, figures and results. The demo runs the two
    shipped scenarios on the default unit, which are the session's shared runs; the verb
    gets those (after checking it asked for them) instead of making them a second time.
    The console script with its own runs: ``test_console.py::test_demo_console_script``
    (``-m slow``)."""
    from hdsim.cli import demo

    shared = {"lost_motion": default_lost_motion_run, "stiffness": default_stiffness_run}
    asked = []

    def shared_run(model, scenario):
        assert model.name == "CSG-25-100" and model.params() == load_unit().params()
        assert {k: e.id for k, e in model.effects().items()} == {k: e.id for k, e in load_unit().effects().items()}
        assert scenario.source == str(builtin_scenario_path(scenario.name))
        asked.append(scenario.name)
        return shared[scenario.name]

    monkeypatch.setattr(demo, "run_scenario", shared_run)
    code, stdout, err = cli("demo", "--json", cwd=tmp_path)
    assert code == 0, err
    assert sorted(asked) == ["lost_motion", "stiffness"]
    check_demo(json.loads(stdout), tmp_path / "hdsim-demo", png_image)


def test_no_verb_prints_help_and_exits_2(cli):
    code, stdout, err = cli()
    assert code == 2 and "usage" in err and stdout == ""


def _linear_batch():
    return load_unit().without("friction", "backlash").with_updates(
        {"flexspline.h_pz": np.array([0.9e-3, 1.1e-3])})


def test_batch_result_round_trip(tmp_path):
    """Batch results I/O: a run of M = 2 parameter sets is written and read back whole."""
    model = _linear_batch()
    run = run_scenario(model, load_scenario(builtin_scenario_path("lost_motion")))
    stored = read_run(run.save(tmp_path / "batch.h5"))
    assert stored.model.params()["flexspline.h_pz"].tolist() == [0.9e-3, 1.1e-3]
    assert stored.model.params()["drive.rated_torque"] == pytest.approx(87.0)
    assert stored.metrics["lost_motion_arcmin"].shape == (2,)
    np.testing.assert_array_equal(stored.metrics["lost_motion_arcmin"], run.metrics["lost_motion_arcmin"])
    assert set(stored.result.signals) == set(run.result.signals)
    for name, values in run.result.signals.items():
        np.testing.assert_array_equal(stored.result.signals[name], values)
    np.testing.assert_array_equal(stored.result.t, run.result.t)
    assert stored.scenario.data["load"] == run.scenario.data["load"]
    assert stored.model.friction.id == "none" and stored.model.hardening.id == model.hardening.id


def test_batch_rows_are_their_own_elastic_closed_forms():
    """Each sample of a batch is the elastic closed form 2A/K(h_pz) of its own geometry,
    as a single run is (solver rtol 1e-6: agreement to 1e-4 expected)."""
    model = _linear_batch()
    run = run_scenario(model, load_scenario(builtin_scenario_path("lost_motion")))
    T_N = float(load_unit().drive.rated_torque)
    expected = [rad_to_arcmin(0.08 * T_N / float(load_unit().with_updates({"flexspline.h_pz": h}).base_stiffness))
                for h in (0.9e-3, 1.1e-3)]
    assert run.metrics["lost_motion_arcmin"] == pytest.approx(expected, rel=1e-4)


def test_read_result_refuses_other_files(tmp_path):
    from hdsim.errors import InputError

    (tmp_path / "x.h5").write_text("not hdf5")
    with pytest.raises(InputError, match="not a readable hdsim result"):
        read_run(tmp_path / "x.h5")


def test_a_first_breakpoint_set_above_the_second_is_refused_as_a_drive_file_refuses_it(cli, tmp_path):
    code, out, err = cli("simulate", "stiffness", "--set", "hardening.T1=60", "--out", str(tmp_path / "o"))
    assert code == 2 and out == "" and not (tmp_path / "o").exists()
    assert err.strip().endswith("hardening.T1 = 60 must be below hardening.T2 = 48 N·m (more teeth engage at "
                                "the second breakpoint)")
