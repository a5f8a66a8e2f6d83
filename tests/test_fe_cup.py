"""Finite-element torsion of the flexspline cup (hdsim.physics.fe_cup) against closed forms.

The tube and the annular plate have exact solutions (ψ = z/L and ψ ∝ 1/r²), written out
here rather than taken from the library. The cup is compared with the closed-form chain
of the model (`hdsim.model.drive.compliance_chain`) at the five built-in sizes and across
the ±10 % box of the seed paper's five dimensions. scikit-fem is in the test extras:
these tests run, never skip.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import unit_names
from hdsim.model.fe_check import closed_form_cup, corner_shapes, cup_section
from hdsim.physics import fe_cup

G = 210e9 / 2.6
DESIGN = ("h_pz", "h_c", "R_v", "R_k", "h_p")


def _nominal(unit="CSG-25-100") -> dict:
    return cup_section(load_unit(unit).geometry)


def test_tube_is_exact():
    ri, ro, L = 30e-3, 30.8e-3, 12e-3
    J = np.pi * (ro**4 - ri**4) / 2
    fe = fe_cup.tube_torsion_fe(r_inner=ri, r_outer=ro, length=L, G=G)
    assert fe.compliance == pytest.approx(L / (G * J), rel=1e-6)
    assert fe.elements > 0 and fe.dofs > fe.elements and fe.seconds > 0.0


def test_annular_plate_converges_to_roark():
    ri, ro, t = 10e-3, 30e-3, 2e-3
    exact = (1 / ri**2 - 1 / ro**2) / (4 * np.pi * G * t)
    errors = [abs(fe_cup.annular_plate_torsion_fe(r_inner=ri, r_outer=ro, thickness=t, G=G,
                                                  elements_through_wall=n).compliance / exact - 1)
              for n in (2, 4)]
    assert errors[1] < 1e-3
    assert errors[1] < 0.5 * errors[0]  # P2 converges fast; a broken weight or form would not


@pytest.mark.parametrize("unit", unit_names())
def test_cup_is_converged_and_agrees_with_the_closed_form_chain(unit):
    model = load_unit(unit)
    fe = fe_cup.converged_cup_compliance(**cup_section(model.geometry))
    assert fe.change < 0.005
    # measured 1.0001 for every size (scaled copies of one geometry); the fillet on the
    # mirror-image arc, 9 % off in that one term, made it 0.9947
    assert fe.compliance / closed_form_cup(model) == pytest.approx(1.0, abs=0.01)


def test_cup_agrees_with_the_closed_forms_across_the_seed_study_box():
    """Every corner of the ±10 % box of h_pz, h_c, R_v, R_k and h_p (32 shapes)."""
    ratios = [fe_cup.cup_torsion_fe(**cup_section(shape.geometry)).compliance / closed_form_cup(shape)
              for shape in corner_shapes(load_unit(), DESIGN)]
    assert len(ratios) == 32
    assert max(abs(r - 1.0) for r in ratios) < 0.01, ratios


def test_refinement_changes_the_cup_little():
    d = _nominal()
    coarse, fine = (fe_cup.cup_torsion_fe(**d, elements_through_wall=n).compliance for n in (2, 8))
    assert fine == pytest.approx(coarse, rel=1e-3)
    assert fine > coarse  # a finer displacement mesh is softer (energy bound)


def test_bad_geometry_is_refused():
    d = _nominal()
    with pytest.raises(InputError, match="too large to fit"):
        fe_cup.cup_torsion_fe(**{**d, "R_k": d["R_i"] + d["h_c"] / 2 - d["r_hub"]})
    with pytest.raises(InputError, match="half the wall"):
        fe_cup.cup_torsion_fe(**{**d, "R_k": 0.4 * d["t_d"]})
    with pytest.raises(InputError, match="t_d must be a positive"):
        fe_cup.cup_torsion_fe(**{**d, "t_d": 0.0})
    with pytest.raises(InputError, match="h_p must be smaller"):
        fe_cup.cup_torsion_fe(**{**d, "h_p": d["h_pz"]})
    with pytest.raises(InputError, match="elements_through_wall"):
        fe_cup.cup_torsion_fe(**d, elements_through_wall=0)
    with pytest.raises(InputError, match="r_outer must exceed"):
        fe_cup.tube_torsion_fe(r_inner=2e-3, r_outer=1e-3, length=1e-2, G=G)


def test_missing_scikit_fem_is_one_clear_input_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "skfem", None)  # a None entry makes `import skfem` fail
    with pytest.raises(InputError, match=r"needs scikit-fem: pip install 'hdsim\[fe\]'"):
        fe_cup.cup_torsion_fe(**_nominal())
    with pytest.raises(InputError, match="scikit-fem"):
        fe_cup.tube_torsion_fe(r_inner=1e-2, r_outer=1.1e-2, length=1e-2, G=G)
