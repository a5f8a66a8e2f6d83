"""Closed forms of the compliance chain against independent references."""

import numpy as np
import pytest
from scipy.integrate import quad

from hdsim.model.catalog import load_unit, nominal_geometry, unit_names
from hdsim.errors import InputError
from hdsim.physics import compliance as cc

G = 210e9 / 2.6


def test_thin_tube_matches_exact_annulus_polar_moment():
    R, t, L = 30e-3, 0.6e-3, 40e-3
    ro, ri = R + t / 2, R - t / 2
    J = np.pi / 2 * (ro**4 - ri**4)  # exact polar moment of an annulus
    exact = L / (G * J)
    assert cc.thin_tube(L, R, t, G) == pytest.approx(exact, rel=5e-3)


def test_annular_diaphragm_matches_radial_integration():
    ri, ro, t = 12e-3, 27e-3, 0.8e-3
    # each ring dr carries T with shear stress T/(2π r² t): dφ = T dr / (2π G t r³)
    integral, _ = quad(lambda r: 1.0 / (2 * np.pi * G * t * r**3), ri, ro)
    assert cc.annular_diaphragm(ri, ro, t, G) == pytest.approx(integral, rel=1e-9)


def test_fillet_matches_quadrature_and_vanishes_with_radius():
    Rk, Rc, t = 3e-3, 30e-3, 0.7e-3
    integral, _ = quad(lambda a: Rk / (2 * np.pi * G * t * (Rc - Rk * np.cos(a)) ** 3), 0, np.pi / 2)
    assert cc.toroidal_fillet(Rk, Rc, t, G) == pytest.approx(integral, rel=1e-9)
    assert cc.toroidal_fillet(1e-9, Rc, t, G) < 1e-6 * integral


def test_transition_between_equal_walls_is_a_tube():
    assert cc.wall_transition(2e-3, 30e-3, 0.6e-3, 0.6e-3, G) == pytest.approx(
        cc.thin_tube(2e-3, 30.3e-3, 0.6e-3, G), rel=1e-12)


def test_chain_terms_are_the_closed_forms_of_the_unit_geometry():
    """Three terms of the chain recomputed by hand from the geometry (formulas written out
    here, not the library's): the cylinder and the rim as thin tubes, the diaphragm as an
    annulus between the hub and the start of the end radius."""
    model = load_unit()
    g, chain = model.geometry, model.compliance()
    Gm = g.E / (2 * (1 + g.nu))
    R_c, R_rim = g.R_i + g.h_c / 2, g.R_i + g.h_pz / 2
    L_cyl = g.cup_length - g.R_k - g.R_v - g.undercut_width - g.face_width
    assert float(chain.cylinder) == pytest.approx(L_cyl / (2 * np.pi * Gm * R_c**3 * g.h_c), rel=1e-12)
    assert float(chain.rim) == pytest.approx(g.face_width / 2 / (2 * np.pi * Gm * R_rim**3 * g.h_pz), rel=1e-12)
    ri, ro = g.r_hub, R_c - g.R_k
    assert float(chain.diaphragm) == pytest.approx((1 / ri**2 - 1 / ro**2) / (4 * np.pi * Gm * g.t_d), rel=1e-12)


def test_a_longer_cylinder_adds_exactly_its_tube_compliance():
    """Series chain: lengthening the cup by ΔL lengthens only the plain cylinder, so
    1/K grows by the thin-tube compliance of ΔL, ΔL/(2π G R_c³ h_c), and nothing else."""
    model = load_unit()
    g = model.geometry
    dL = 0.1 * g.cup_length
    longer = model.with_updates({"flexspline.cup_length": g.cup_length + dL})
    Gm = g.E / (2 * (1 + g.nu))
    R_c = g.R_i + g.h_c / 2
    added = 1 / float(longer.base_stiffness) - 1 / float(model.base_stiffness)
    assert added == pytest.approx(dL / (2 * np.pi * Gm * R_c**3 * g.h_c), rel=1e-9)
    assert added > 0.01 / float(model.base_stiffness)  # a visible change, not round-off


def test_tube_alone_is_several_times_stiffer_than_the_catalog():
    # the reason a calibration exists (reference §4): closed-form shell terms are far stiffer
    model = load_unit("CSG-25-100")
    assert 1.0 / float(model.compliance().cylinder) > 3 * model.provenance["catalog"]["K3"]


@pytest.mark.parametrize("unit", unit_names())
@pytest.mark.parametrize("dimension", ["h_pz", "h_c"])
def test_thicker_walls_are_always_stiffer(unit, dimension):
    model = load_unit(unit)
    nominal = model.params()[f"flexspline.{dimension}"]
    factors = np.linspace(0.8, 1.2, 9)
    stiffness = [model.with_updates({f"flexspline.{dimension}": f * nominal}).base_stiffness for f in factors]
    assert np.all(np.diff(stiffness) > 0)


def test_calibration_is_fixed_when_geometry_changes():
    model = load_unit()
    thicker = model.with_updates({"flexspline.h_c": 1.1 * model.params()["flexspline.h_c"]})
    assert thicker.calibration.kappa_mesh == model.calibration.kappa_mesh
    assert thicker.hardening.e2 == model.hardening.e2


@pytest.mark.parametrize("change, message", [
    ({"flexspline.h_p": 2e-3}, "undercut depth"),
    ({"flexspline.h_c": -1e-4}, "positive"),
    ({"flexspline.R_k": 20e-3}, "does not fit"),
    ({"flexspline.R_v": 40e-3}, "no cylinder left"),
    ({"flexspline.h_pz": 5e-3}, "thin-shell"),
])
def test_impossible_shapes_are_refused(change, message):
    with pytest.raises(InputError, match=message):
        load_unit().with_updates(change)


def test_batch_geometry_names_the_bad_sample():
    model = load_unit()
    h_p = np.array([0.2e-3, 0.3e-3, 5e-3])
    with pytest.raises(InputError, match=r"sample 2"):
        model.with_updates({"flexspline.h_p": h_p})


def test_size_number_is_pitch_diameter_in_tenths_of_an_inch():
    g = nominal_geometry(25, 100)
    assert 2 * g.pitch_radius == pytest.approx(63.5e-3, rel=1e-12)


@pytest.mark.parametrize("name, value", [("wave_generator.balls", 1.0), ("drive.J_out", -1.0),
                                         ("calibration.kappa_mesh", 0.0)])
def test_out_of_range_unit_data_is_refused_by_name(name, value):
    with pytest.raises(InputError, match=name.replace(".", r"\.")):
        load_unit().with_updates({name: value})
