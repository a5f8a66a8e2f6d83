"""Plane-stress finite-element rim (hdsim.physics.fe_rim) against exact and handbook solutions.

The Lamé thick cylinder (Timoshenko & Goodier, Theory of Elasticity, §33) and the thin
ring pinched by two opposite loads (Roark's Formulas for Stress and Strain, 8th ed.,
Table 9.2 case 1) are written out here rather than taken from the library. The rim on
the balls has no exact solution: it is checked for mesh convergence, equilibrium,
scale invariance and against the closed form it is meant to judge. scikit-fem is in the
test extras: these tests run, never skip.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit
from hdsim.model.drive import radial_support
from hdsim.model.fe_check import fe_rim_stiffness
from hdsim.physics import fe_rim

E, NU = 210e9, 0.3
BALLS = 22


def _lame_outer_displacement(a, b, p, E, nu):
    """Plane-stress radial displacement of the outer surface under external pressure p [m]."""
    return -(p * b / E) * ((b**2 + a**2) / (b**2 - a**2) - nu)


def _roark_pinched_shortening(W, R, h, width, E, nu):
    """Roark Table 9.2 case 1 with the hoop (α) and shear (β, F = 1.2) corrections [m]."""
    inertia = width * h**3 / 12
    area = width * h
    alpha = inertia / (area * R**2)
    beta = 1.2 * E * inertia / (E / (2 * (1 + nu)) * area * R**2)
    k1, k2 = 1 - alpha + beta, 1 - alpha
    return W * R**3 / (E * inertia) * (k1 * np.pi / 4 - 2 * k2**2 / np.pi)


def _rim_args(unit="CSG-25-100", **overrides):
    g = load_unit(unit).geometry
    args = dict(bore_radius=float(g.R_i), wall=float(g.h_pz), face_width=float(g.face_width), E=float(g.E),
                nu=float(g.nu), balls=BALLS, arc_length=0.15 * 2 * np.pi * float(g.R_i + g.h_pz / 2))
    args.update(overrides)
    return args


@pytest.fixture(scope="module")
def nominal():
    return fe_rim.rim_radial_stiffness_fe(**_rim_args())


@pytest.mark.parametrize("inner, outer", [(0.03, 0.031), (1.0, 1.5)])
def test_thick_cylinder_under_external_pressure_is_lame(inner, outer):
    p = 5e6
    result = fe_rim.ring_under_external_pressure_fe(inner_radius=inner, outer_radius=outer, thickness=0.01,
                                                    E=E, nu=NU, pressure=p)
    exact = _lame_outer_displacement(inner, outer, p, E, NU)
    assert result.outer_radial.size >= 128
    np.testing.assert_allclose(result.outer_radial, exact, rtol=1e-3)
    assert result.displacement == pytest.approx(-exact, rel=1e-3)


@pytest.mark.parametrize("slenderness", [20, 40])
def test_thin_ring_pinched_by_two_loads_is_roark(slenderness):
    R, width, W = 0.03, 0.01, 100.0
    h = R / slenderness
    thin = 0.1488 * W * R**3 / (E * width * h**3 / 12)
    corrected = _roark_pinched_shortening(W, R, h, width, E, NU)
    errors = []
    for refinement in (0.5, 1, 2):
        result = fe_rim.ring_pinched_fe(mean_radius=R, wall=h, face_width=width, E=E, nu=NU, force=W,
                                        refinement=refinement)
        shortening = 2 * result.displacement
        assert shortening == pytest.approx(thin, rel=0.02)
        errors.append(abs(shortening / corrected - 1))
    assert errors[-1] < 2e-3
    assert errors[-1] <= errors[0]


def test_rim_stiffness_is_mesh_converged(nominal):
    finer = fe_rim.rim_radial_stiffness_fe(**_rim_args(), refinement=2)
    assert finer.elements > 3 * nominal.elements
    assert abs(finer.stiffness / nominal.stiffness - 1) < 0.02


def test_rim_is_in_equilibrium_and_the_middle_balls_carry_the_load(nominal):
    reactions = np.array(nominal.reactions)
    assert reactions.sum() == pytest.approx(1.0, abs=0.01)  # the rest leaks to the far side of the ring
    np.testing.assert_allclose(reactions, reactions[::-1], atol=1e-3)  # mirror symmetry about the zone
    assert reactions[reactions.size // 2] > 0.25 and reactions.min() > -0.01
    assert len(nominal.ball_angles) == 7  # on-centre: ±(a/2 + 1.5 p) reaches three balls either side


def test_rim_stiffness_scales_with_size():
    """Plane stress: all lengths times s (face width included) multiplies the stiffness by s."""
    base = fe_rim.rim_radial_stiffness_fe(**_rim_args(), refinement=0.5)
    args = {k: (2 * v if k in ("bore_radius", "wall", "face_width", "arc_length") else v)
            for k, v in _rim_args().items()}
    doubled = fe_rim.rim_radial_stiffness_fe(**args, refinement=0.5)
    assert doubled.stiffness == pytest.approx(2 * base.stiffness, rel=1e-6)


def test_rim_is_far_stiffer_than_a_simply_supported_span(nominal):
    """The closed form hdsim used before this model: each span a simply supported beam with
    a central load, k = (a/p)·48 E I/p³. The ring is about fifteen times stiffer."""
    g = load_unit("CSG-25-100").geometry
    pitch = 2 * np.pi * g.R_i / BALLS
    a = 0.15 * 2 * np.pi * (g.R_i + g.h_pz / 2)
    simply_supported = a / pitch * 48 * g.E * (g.face_width * g.h_pz**3 / 12) / pitch**3
    assert 10 < nominal.stiffness / simply_supported < 20


@pytest.mark.parametrize("wall_factor", [0.9, 1.0, 1.1])
def test_closed_form_rim_agrees_with_the_fe_for_the_unit_support(wall_factor):
    """The chain's rim term against this model at the built-in support width, both ball
    placements averaged (the WG turns, so the balls pass every position), walls ±10 %."""
    model = load_unit("CSG-25-100")
    shape = model.with_updates({"flexspline.h_pz": wall_factor * model.params()["flexspline.h_pz"]})
    fe = fe_rim_stiffness(shape, refinement=1)
    closed = float(radial_support(shape.geometry, shape.wave_generator).rim)
    assert fe / closed == pytest.approx(1.0, abs=0.05)


def test_stiffness_is_the_inverse_of_the_mean_deflection_of_the_loaded_arc(nominal):
    assert nominal.stiffness * nominal.arc_deflection == pytest.approx(1.0, abs=0.002)


def test_straddling_balls_and_wider_contacts():
    on = fe_rim.rim_radial_stiffness_fe(**_rim_args(), refinement=0.5)
    straddle = fe_rim.rim_radial_stiffness_fe(**_rim_args(), ball_on_centre=False, refinement=0.5)
    assert len(straddle.ball_angles) == 6
    assert straddle.stiffness == pytest.approx(on.stiffness, rel=0.1)
    pitch = 2 * np.pi * _rim_args()["bore_radius"] / BALLS
    wide = fe_rim.rim_radial_stiffness_fe(**_rim_args(), contact_width=0.3 * pitch, refinement=0.5)
    assert wide.stiffness > 1.5 * on.stiffness


def test_soft_balls_make_a_softer_rim(nominal):
    springs = fe_rim.rim_radial_stiffness_fe(**_rim_args(), ball_stiffness=1e9)
    stiff = fe_rim.rim_radial_stiffness_fe(**_rim_args(), ball_stiffness=1e14)
    assert springs.stiffness < 0.9 * nominal.stiffness
    assert stiff.stiffness == pytest.approx(nominal.stiffness, rel=0.02)


@pytest.mark.parametrize("override", [dict(wall=-1e-3), dict(nu=0.5), dict(balls=3), dict(balls=22.0),
                                      dict(arc_length=0.2), dict(contact_width=0.01), dict(E=float("nan"))])
def test_bad_rim_input_is_one_line(override):
    with pytest.raises(InputError) as err:
        fe_rim.rim_radial_stiffness_fe(**_rim_args(**override))
    assert "\n" not in str(err.value)


def test_missing_scikit_fem_is_an_input_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "skfem", None)
    with pytest.raises(InputError, match=r"pip install 'hdsim\[fe\]'"):
        fe_rim.rim_radial_stiffness_fe(**_rim_args())


def test_ball_offset_is_periodic_and_mirror_symmetric():
    args = _rim_args(refinement=0.5)
    straddle = fe_rim.rim_radial_stiffness_fe(**args, ball_on_centre=False)
    assert fe_rim.rim_radial_stiffness_fe(**args, ball_offset=0.5).stiffness == straddle.stiffness
    on = fe_rim.rim_radial_stiffness_fe(**args, ball_offset=0.0)
    assert fe_rim.rim_radial_stiffness_fe(**args, ball_offset=1.0).stiffness == pytest.approx(on.stiffness, rel=1e-3)
    quarter = fe_rim.rim_radial_stiffness_fe(**args, ball_offset=0.25)
    mirror = fe_rim.rim_radial_stiffness_fe(**args, ball_offset=-0.25)
    assert quarter.stiffness == pytest.approx(mirror.stiffness, rel=2e-3)
    np.testing.assert_allclose(quarter.reactions, mirror.reactions[::-1], atol=2e-3)
