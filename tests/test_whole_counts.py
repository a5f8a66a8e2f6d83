"""Counts (the wave generator's balls, the flexspline's teeth) take whole numbers only, at
every edge a value enters by: the model, ``--set``, a fitted-model file, a drive file and a
Sobol' study's inputs (docs/nomenclature.md, docs/sensitivity.md §1)."""

from __future__ import annotations

import re

import pytest

import hdsim
from hdsim.errors import InputError
from hdsim.identification.fit import load_fitted
from hdsim.model.catalog import load_unit


@pytest.mark.parametrize("name, value, what", [
    ("wave_generator.balls", 20.5, "balls"),
    ("wave_generator.balls", [22.0, 20.5], "balls"),  # a batch names its first bad value
    ("flexspline.teeth", 200.5, "teeth"),
])
def test_a_count_that_is_not_whole_is_refused_by_the_model(name, value, what):
    with pytest.raises(InputError, match=rf"^(flexspline geometry: )?{name} = 20\d?\.5 must be a whole number of {what}$"):
        load_unit("CSG-25-100").with_updates({name: value})


def test_a_whole_count_given_as_a_float_is_taken():
    unit = load_unit("CSG-25-100").with_updates({"wave_generator.balls": 20.0, "flexspline.teeth": 200.0})
    assert unit.wave_generator.balls == 20 and unit.geometry.teeth == 200


def test_set_refuses_a_ball_count_that_is_not_whole_with_exit_2(cli):
    """(``hdsim compliance``: the same `apply_sets` as ``simulate``, without the solver's imports.)"""
    code, out, err = cli("compliance", "--set", "wave_generator.balls=20.5")
    assert code == 2 and out == "" and err.strip().splitlines() == [
        "hdsim compliance: error: wave_generator.balls = 20.5 must be a whole number of balls"]


def test_a_count_just_off_a_whole_number_is_shown_as_it_was_given():
    """Shown with ``:g`` it read "balls = 22 must be a whole number", contradicting itself."""
    with pytest.raises(InputError, match=r"wave_generator.balls = 22.000001 must be a whole number of balls"):
        hdsim.load_unit("CSG-25-100").with_updates({"wave_generator.balls": 22.000001})


@pytest.mark.parametrize("value, told", [('"0.9e-3"', "str '0.9e-3'"), ("[20]", "list [20]"), ("true", "bool True")])
def test_a_fit_file_value_that_is_no_number_is_refused_as_a_drive_file_refuses_it(value, told, tmp_path):
    """A string had stopped load_fitted with an internal TypeError; a list or true was taken."""
    path = tmp_path / "fitted.toml"
    path.write_text(f'format = "hdsim-fit-1"\nunit = "CSG-25-100"\n[effects]\n[parameters]\n"wave_generator.balls" = {value}\n')
    with pytest.raises(InputError, match=rf"parameters.wave_generator.balls must be a number, got {re.escape(told)}"):
        load_fitted(path)


def test_a_fit_file_with_a_ball_count_that_is_not_whole_is_refused(tmp_path):
    path = tmp_path / "fitted.toml"
    path.write_text('format = "hdsim-fit-1"\nunit = "CSG-25-100"\n[effects]\n[parameters]\n"wave_generator.balls" = 20.5\n')
    with pytest.raises(InputError, match="wave_generator.balls = 20.5 must be a whole number of balls"):
        load_fitted(path)


def test_a_drive_file_whose_ratio_gives_a_fraction_of_a_tooth_is_refused_in_its_own_words(tmp_path):
    """The drive file's teeth are 2N: ratio 50.25 had been refused as 'flexspline.teeth = 100.5',
    a key the file does not hold; 50.5 (101 teeth) is a drive."""
    path = tmp_path / "drive.toml"
    path.write_text('name = "X"\nratio = 50.25\nrated_torque_Nm = 16.0\n')
    with pytest.raises(InputError, match=r"ratio = 50.25 means 100.5 flexspline teeth \(2N\), not a whole number"):
        load_unit(path)


@pytest.mark.parametrize("params, bounds", [
    (["h_pz", "wave_generator.balls"], {"wave_generator.balls": (18.0, 26.0)}),
    (["teeth"], {"teeth": (180.0, 220.0)}),
])
def test_a_sobol_study_refuses_a_count_before_it_runs(params, bounds, monkeypatch):
    """Every row of a design over a count would be refused (real values drawn across the
    range): the study is refused at once, naming the count."""
    from hdsim.sensitivity import study

    monkeypatch.setattr(study, "evaluate", lambda *a, **k: pytest.fail("the study ran"), raising=False)
    with pytest.raises(InputError, match=r"is a count of (balls|teeth) \(whole numbers only\), which a Sobol' study"):
        hdsim.sobol("CSG-25-100", params, "lost_motion_arcmin", range=0.1, bounds=bounds, n=16)


def test_sobol_cli_refuses_a_count_with_exit_2(cli, tmp_path):
    code, out, err = cli("sobol", "--unit", "CSG-25-100", "--params", "wave_generator.balls",
                         "--bounds", "wave_generator.balls=18:26", "--output", "lost_motion_arcmin", "--n", "16")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "wave_generator.balls is a count of balls" in err
