"""What a flexspline geometry may hold: units slipped, extremes (docs/physics.md §2.2).

A modulus in GPa, a wall or cup length in millimetres, a point-like hub, a face narrower
than a module: each is refused with one line naming the dimension and the value given,
and where a length read as millimetres would fit, saying so. Extreme but finite values are
refused before they reach the closed forms, whose floats would overflow.
"""

from __future__ import annotations

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import nominal_geometry

from drive_file_refusal import HEAD, refusal


# ------------------------------------------------------------------- units slipped


@pytest.mark.parametrize("modulus, fragments", [
    ("210", ["flexspline.E = 210 Pa", "below 1 GPa", "210 GPa is 2.1e+11"]),
    ("210000", ["flexspline.E = 2.1e+05 Pa", "MPa is 2.1e+11"]),
])
def test_a_modulus_outside_the_materials_names_the_unit_mistake(tmp_path, modulus, fragments):
    # E = 210 had given K = 2e-5 N·m/rad and a stiffness test that blamed the load rate
    message = refusal(tmp_path, HEAD + f"[flexspline]\nE = {modulus}\n")
    for fragment in fragments:
        assert fragment in message, message


def test_a_modulus_in_gpa_beside_a_datasheet_stiffness_is_named_too(tmp_path):
    # with K given the calibration used to refuse it as "too soft for the catalog stiffness"
    message = refusal(tmp_path, HEAD + "K1_Nm_per_rad = 1.0e4\n[flexspline]\nE = 210\n")
    assert "flexspline.E = 210 Pa" in message, message


@pytest.mark.parametrize("key, value, fragments", [
    ("h_pz", "0.5", ["flexspline.h_pz = 500 mm", "bore radius R_i = ", "0.5 mm is 0.0005"]),
    ("h_c", "1e-9", ["flexspline.h_c = 1e-06 mm", "less than 0.1 % of the bore radius"]),
    ("t_d", "1e-9", ["flexspline.t_d = 1e-06 mm", "less than 0.1 % of the bore radius"]),
    ("r_hub", "1e-9", ["flexspline.r_hub = 1e-06 mm", "less than 10 % of the bore radius"]),
    ("r_hub", "0.05", ["flexspline.r_hub = 50 mm does not fit inside the cylinder"]),
    ("face_width", "1e-9", ["flexspline.face_width = 1e-06 mm", "narrower than one module"]),
    ("cup_length", "33.4", ["flexspline.cup_length = 3.34e+04 mm", "33.4 mm is 0.0334"]),
    ("pressure_angle", "20", ["pressure angle 20 rad", "20° is 0.3491"]),
])
def test_a_dimension_out_of_proportion_is_named_with_its_value(tmp_path, key, value, fragments):
    # r_hub = 1e-9 had given K = 6e-10 N·m/rad, face_width = 1e-9 K = 508; r_hub = 0.05 was
    # reported as "end radius R_k = 2.086 mm does not fit", h_pz = 0.5 without its name
    message = refusal(tmp_path, HEAD + f"[flexspline]\n{key} = {value}\n")
    for fragment in fragments:
        assert fragment in message, message


# ------------------------------------------------------------------- extremes


@pytest.mark.parametrize("name, value, fragment", [
    ("E", 1e308, r"flexspline.E = 1e\+308 Pa is above"),
    ("E", 1e-300, r"flexspline.E = 1e-300 Pa is below 1 GPa"),
    ("h_c", 1e-200, "flexspline.h_c = "),
    ("h_c", 1e-100, "flexspline.h_c = "),
    ("t_d", 1e-200, "flexspline.t_d = "),
    ("r_hub", 1e-300, "flexspline.r_hub = "),
    ("pressure_angle", 1e-300, "must be at least 5°"),
])
def test_extreme_finite_values_are_refused_before_the_closed_forms(name, value, fragment):
    # E = 1e308, h_c = 1e-200, r_hub and pressure_angle = 1e-300 had ended in a
    # ZeroDivisionError inside hdsim.physics.compliance; E = 1e-300 printed "inf%"
    with pytest.raises(InputError, match=fragment):
        load_unit().with_updates({f"flexspline.{name}": value})


@pytest.mark.parametrize("setting", ["flexspline.E=1e308", "flexspline.h_c=1e-200", "flexspline.E=1e-300"])
def test_the_compliance_command_refuses_extremes_with_exit_2(cli, setting):
    code, out, err = cli("compliance", "--set", setting)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert "flexspline." in err and "internal error" not in err


def test_a_batch_names_the_sample_with_the_slipped_modulus():
    E = np.array([2.1e11, 210.0])
    with pytest.raises(InputError, match=r"\(sample 1\): flexspline.E = 210 Pa"):
        load_unit().with_updates({"flexspline.E": E})


def test_the_rigid_limit_a_fit_stiffens_towards_is_still_a_model():
    # hdsim.identification.problem raises E up to 1e6 × nominal for a far trial, and a rigid
    # reference runs at that modulus: the material range holds for drive files, not here
    unit = load_unit()
    rigid = unit.with_updates({"flexspline.E": 1e6 * unit.geometry.E})
    assert np.isfinite(float(rigid.base_stiffness)) and float(rigid.base_stiffness) > float(unit.base_stiffness)


@pytest.mark.parametrize("size", [5.0, 14.0, 100.0])
@pytest.mark.parametrize("ratio", [30.0, 100.0, 320.0])
def test_the_assumed_proportions_pass_every_limit_over_the_drive_file_range(size, ratio):
    """Every size and ratio a drive file may scale to builds (hdsim/data/units.toml ranges)."""
    g = nominal_geometry(size, ratio)
    assert float(g.teeth) == 2.0 * ratio
