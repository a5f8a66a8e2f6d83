"""What a drive file may hold beyond its geometry: the ratio, the teeth, the modulus, its kind.

A ratio no strain-wave gear has, teeth that contradict the ratio, a modulus stiffer than any
material, a scenario or fit file given as the unit: each is refused with one line that names
the file, the key and the value given (docs/cli.md, "Your own drive: a drive file").
"""

from __future__ import annotations

from pathlib import Path

import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit

from drive_file_refusal import HEAD, refusal

REPO = Path(__file__).resolve().parents[1]


# ------------------------------------------------------------------- the modulus


def test_a_modulus_stiffer_than_any_material_is_refused_in_a_drive_file(tmp_path):
    # the geometry stops only at the rigid limit a fit may use (5e17 Pa); no datasheet gives that
    message = refusal(tmp_path, HEAD + "[flexspline]\nE = 1e12\n")
    assert "flexspline.E = 1e+12 Pa is above 500 GPa" in message, message


# ------------------------------------------------------------------- ratio and teeth


@pytest.mark.parametrize("ratio", ["1", "1.5", "5", "20", "10000"])
def test_a_ratio_no_strain_wave_gear_has_is_refused_by_name(tmp_path, ratio):
    # ratio 1 had been refused as "R_i must be a positive finite number, got -0.007 m",
    # ratio 2 as an end radius that does not fit, and ratio 5 (10 teeth) accepted
    message = refusal(tmp_path, f'name = "X"\nratio = {ratio}\nrated_torque_Nm = 16.0\n')
    assert f"ratio = {float(ratio):g} is outside 30-320" in message, message


@pytest.mark.parametrize("ratio", ["30", "320"])
def test_the_ends_of_the_ratio_range_load(tmp_path, ratio):
    path = tmp_path / "end.toml"
    path.write_text(f'name = "X"\nratio = {ratio}\nrated_torque_Nm = 16.0\n', encoding="utf-8")
    assert float(load_unit(path).drive.ratio) == float(ratio)


@pytest.mark.parametrize("teeth", ["99", "102", "101.5"])
def test_teeth_that_contradict_the_ratio_are_refused(tmp_path, teeth):
    message = refusal(tmp_path, HEAD + f"[flexspline]\nteeth = {teeth}\n")
    assert f"flexspline.teeth = {float(teeth):g} contradicts ratio = 50" in message, message
    assert "2N = 100" in message, message


def test_teeth_of_the_ratio_load(tmp_path):
    path = tmp_path / "teeth.toml"
    path.write_text(HEAD + "[flexspline]\nteeth = 100\n", encoding="utf-8")
    assert float(load_unit(path).geometry.teeth) == 100.0


# ------------------------------------------------------------------- other files


def test_a_scenario_file_given_as_the_unit_says_so(tmp_path):
    # it had been refused as "unknown drive file key 'description'; did you mean ratio?"
    path = REPO / "scenarios" / "stiffness.toml"
    with pytest.raises(InputError, match=r"a scenario file \(setup = 'locked_wave_generator'\), not a drive file"):
        load_unit(path)


def test_a_scenario_file_given_to_the_cli_as_the_unit_exits_2(cli, tmp_path):
    path = REPO / "scenarios" / "stiffness.toml"
    code, out, err = cli("simulate", "stiffness", "--unit", path, "--json", cwd=tmp_path)
    assert code == 2 and out == "" and "a scenario file" in err and "did you mean" not in err, err


def test_a_running_torque_fit_given_as_the_unit_says_so(tmp_path):
    message = refusal(tmp_path, 'format = "hdsim-running-fit-1"\ntest = "running_torque"\n')
    assert "running-torque fit file" in message, message


# ------------------------------------------------------------------- breakpoints above T_N


def test_breakpoints_above_the_rated_torque_are_kept_and_the_template_says_what_to_do(tmp_path):
    """The maker lists one T1, T2 per size for every ratio (Harmonic Drive size 14: T2 = 6.9 N·m,
    rated 5.4 N·m at ratio 50), so a drive file keeps a T2 above T_N; the ±T_N stiffness test
    does not reach it, and the template says how to make it (docs/cli.md)."""
    from hdsim.model.drive_file import template

    path = tmp_path / "low.toml"
    path.write_text(HEAD + "T1_Nm = 3.9\nT2_Nm = 40\n", encoding="utf-8")
    assert float(load_unit(path).hardening.T2) == 40.0
    text = template()
    assert "T1, T2 above rated_torque_Nm are kept" in text and "--set scenario.load.amplitude=" in text
