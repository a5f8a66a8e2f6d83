"""The run file and scenario names: `Run.save` then `read_run` gives the same run back,
and a built-in scenario is found by its name from any working directory."""

from __future__ import annotations

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit
from hdsim.scenarios.registry import SETUPS
from hdsim.scenarios.run import Run, read_run, run_scenario
from hdsim.scenarios.scenario import Scenario, builtin_scenario_names, builtin_scenario_path, load_scenario


def _assert_same_run(back: Run, run: Run):
    assert isinstance(back, Run)
    assert back.scenario.name == run.scenario.name and back.scenario.data == run.scenario.data
    assert back.model.name == run.model.name
    assert {k: e.id for k, e in back.model.effects().items()} == {k: e.id for k, e in run.model.effects().items()}
    expected = run.model.params()
    got = back.model.params()
    assert set(got) == set(expected)
    for name, value in expected.items():
        np.testing.assert_array_equal(np.asarray(got[name], dtype=float), np.asarray(value, dtype=float), name)
    assert set(back.metrics) == set(run.metrics)
    for name, value in run.metrics.items():
        np.testing.assert_array_equal(back.metrics[name], value, name)
    np.testing.assert_array_equal(back.result.t, run.result.t)
    for table in ("signals", "states"):
        stored, fresh = getattr(back.result, table), getattr(run.result, table)
        assert set(stored) == set(fresh)
        for name, value in fresh.items():
            np.testing.assert_array_equal(stored[name], value, name)
    assert back.result.setup == run.result.setup
    assert back.result.metadata["unit"] == run.model.name
    assert back.result.metadata["scenario"] == run.scenario.name


def test_run_round_trip(default_lost_motion_run, tmp_path):
    run = default_lost_motion_run
    path = run.save(tmp_path / "sub" / "lost_motion.h5")
    assert path.is_file() and not list(path.parent.glob(".*.tmp"))  # written through a temporary file
    back = read_run(path)
    _assert_same_run(back, run)
    assert back.metric("lost_motion_arcmin") == run.metric("lost_motion_arcmin")
    assert back.scenario.source == str(path)


def test_batch_run_with_changed_parameters_and_effects_round_trips(tmp_path):
    """The model is the built-in unit with every stored parameter and effect applied."""
    model = load_unit("CSG-20-100").without("friction").with_updates(
        {"flexspline.h_pz": np.array([0.9e-3, 1.1e-3]), "backlash.gap": 2e-5})
    scenario = load_scenario("lost_motion").with_updates({"load.cycles": 1})
    run = run_scenario(model, scenario, samples_per_segment=20)
    back = read_run(run.save(tmp_path / "batch.h5"))
    _assert_same_run(back, run)
    assert back.model.friction.id == "none" and back.model.batch_size == 2
    assert back.model.provenance == model.provenance  # the catalog entry of the unit, T1 and T2 included


def test_read_run_refuses_a_file_that_is_not_a_run(tmp_path):
    (tmp_path / "x.h5").write_text("not hdf5")
    with pytest.raises(InputError, match="not a readable hdsim result"):
        read_run(tmp_path / "x.h5")


def test_run_scenario_by_built_in_name_from_any_directory(tmp_path, monkeypatch):
    # the name is what is tested, not the physics: a unit without friction and backlash runs
    # the scenario in a tenth of a second instead of seconds
    model = load_unit().without("friction", "backlash")
    reference = run_scenario(model, load_scenario(builtin_scenario_path("lost_motion")))
    monkeypatch.chdir(tmp_path)
    run = run_scenario(model, "lost_motion")
    assert run.scenario.source == str(builtin_scenario_path("lost_motion"))
    assert run.scenario.data == reference.scenario.data
    assert run.metrics["lost_motion_arcmin"] == pytest.approx(reference.metrics["lost_motion_arcmin"], rel=0, abs=0)


def test_load_scenario_takes_a_name_a_path_or_a_scenario(tmp_path, monkeypatch):
    by_path = load_scenario(builtin_scenario_path("stiffness"))
    assert load_scenario(by_path) is by_path
    monkeypatch.chdir(tmp_path)
    assert load_scenario("stiffness").data == by_path.data
    # a directory of that name (an output folder, say) is not a scenario file: the built-in is meant
    (tmp_path / "stiffness").mkdir()
    assert load_scenario("stiffness").data == by_path.data
    # a file of that name is taken as it is
    (tmp_path / "lost_motion").write_text('name = "mine"\n[load]\namplitude = 0.1\ncycles = 1\nrate = 0.5\n')
    assert load_scenario("lost_motion").name == "mine"


def test_unknown_scenario_names_the_built_ins(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match="not found") as err:
        load_scenario("lost_motoin")
    for name in builtin_scenario_names():
        assert name in str(err.value)


def test_every_set_up_is_registered_once_and_validates_its_scenarios():
    assert set(SETUPS) == {"locked_wave_generator", "driven_wave_generator"}
    for name in builtin_scenario_names():
        scenario = load_scenario(name)
        setup = SETUPS[scenario.setup]
        assert set(scenario.metrics) <= set(setup.metrics)
    with pytest.raises(InputError, match="unknown setup"):
        Scenario({"name": "x", "setup": "spinning"})
    with pytest.raises(InputError, match="metric in scenario"):
        run_scenario(load_unit(), Scenario({**load_scenario("lost_motion").data, "metrics": ["windup"]}))


def test_cli_simulate_by_name_from_another_directory(tmp_path, monkeypatch, cli):
    import json

    monkeypatch.chdir(tmp_path)
    # friction and backlash off: the name is tested, not the physics (a tenth of the run time)
    code, stdout, err = cli("simulate", "lost_motion", "--set", "friction=none", "--set", "backlash=none",
                            "--out", "out", "--json", "--no-figures")
    assert code == 0, err
    payload = json.loads(stdout)
    assert payload["scenario"] == "lost_motion"
    assert read_run(payload["result"]).metric("lost_motion_arcmin") == pytest.approx(
        payload["metrics"]["lost_motion_arcmin"])
    code, _, err = cli("simulate", "no_such_scenario", "--out", "out2")
    assert code == 2 and "lost_motion" in err and len(err.strip().splitlines()) == 1


def test_a_full_disk_fails_in_python_naming_the_file_and_leaves_nothing(default_lost_motion_run, tmp_path,
                                                                         monkeypatch, cli):
    """The HDF5 file is made in memory and written by Python (`hdsim.atomic.hdf5_atomic`): on a
    full disk the HDF5 library's own writes had crashed the process (exit 139)."""
    import errno
    from pathlib import Path

    def full(self, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_bytes", full)
    with pytest.raises(OSError) as info:
        default_lost_motion_run.save(tmp_path / "run.h5")
    assert info.value.errno == errno.ENOSPC and info.value.filename == str(tmp_path / "run.h5")
    assert list(tmp_path.iterdir()) == []  # not even the temporary file
    from hdsim.cli import simulate

    monkeypatch.setattr(simulate, "run_scenario", lambda *a, **k: default_lost_motion_run)
    code, out, err = cli("simulate", "lost_motion", "--out", str(tmp_path / "o"), "--no-figures", cwd=tmp_path)
    assert code == 2 and out == "" and err.count("\n") == 1
    assert f"{tmp_path / 'o' / 'lost_motion.h5'}: No space left on device" in err


def test_a_run_whose_figure_cannot_be_saved_leaves_the_folder_as_it_was(default_lost_motion_run, tmp_path,
                                                                          monkeypatch):
    """The result file and its figures are written as one group (`hdsim.atomic.atomic_group`):
    a full disk at the second figure left a new result file beside the old figures."""
    import errno

    import matplotlib.figure

    from hdsim.cli._common import write_outputs

    out = tmp_path / "o"
    first = write_outputs(default_lost_motion_run, out)
    for path in out.iterdir():  # an earlier result: any file replaced shows
        path.write_bytes(b"earlier " + path.name.encode())
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert len(before) == 3
    saved = []
    real = matplotlib.figure.Figure.savefig

    def full_at_the_second(self, *args, **kwargs):
        saved.append(args[0])
        if len(saved) == 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, *args, **kwargs)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", full_at_the_second)
    with pytest.raises(OSError):
        write_outputs(default_lost_motion_run, out)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # nothing replaced, no temporary left
    assert sorted(first) == ["loop_figure", "result", "time_figure"]


def test_a_driven_runs_windows_survive_the_file(short_ke_run, tmp_path):
    """The tutorial reads the metric windows from ``result.metadata["windows"]``: a saved and
    read run had lost them (and the input mode and profile)."""
    back = read_run(short_ke_run.save(tmp_path / "ke.h5"))
    for key in ("windows", "input_mode", "profile"):
        assert back.result.metadata[key] == short_ke_run.result.metadata[key], key
