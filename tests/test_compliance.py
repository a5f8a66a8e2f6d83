"""Closed forms of the compliance chain against independent references."""

import numpy as np
import pytest
from scipy.integrate import quad

from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import nominal_geometry, unit_names
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


def test_fillet_matches_quadrature_along_its_arc_and_vanishes_with_radius():
    """The arc tangent to the diaphragm (z = 0) and to the cylinder (r = R_c), written here
    as points (r, z) with its length element from their derivatives."""
    Rk, Rc, t = 3e-3, 30e-3, 0.7e-3
    centre_r, centre_z = Rc - Rk, Rk

    def point(b):  # b from 0 (on the diaphragm) to π/2 (on the cylinder)
        return centre_r + Rk * np.sin(b), centre_z - Rk * np.cos(b)

    r0, z0 = point(0.0)
    r1, z1 = point(np.pi / 2)
    assert (r0, z0) == pytest.approx((Rc - Rk, 0.0)) and (r1, z1) == pytest.approx((Rc, Rk))

    def element(b):
        dr, dz = Rk * np.cos(b), Rk * np.sin(b)
        return np.hypot(dr, dz) / (2 * np.pi * G * t * point(b)[0] ** 3)

    integral, _ = quad(element, 0, np.pi / 2)
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


# ----------------------------------------------------------------------- mesh zone and size


def test_mesh_zone_is_tan_squared_over_the_radial_support():
    """The mesh zone from a contact model solved here as a constrained minimum: a tooth on
    a radial spring k_r, free tangentially, pressed by a tangential force F_t against a
    fixed flank at pressure angle α. The flank forbids motion along its normal,
    u_t cos α + u_r sin α = 0 (u_r outward), so advancing means retreating inwards.
    Minimising ½ k_r u_r² − F_t u_t on that constraint (Lagrange multiplier) gives the
    tangential give; the twist is u_t / r_p with F_t = T / (2 r_p) in each of two zones."""
    k_r, r_p, T = 6e7, 0.032, 10.0
    for alpha in np.radians([14.5, 20.0, 30.0]):
        F_t = T / (2 * r_p)
        normal = np.array([np.cos(alpha), np.sin(alpha)])  # (tangential, radial) components
        # unknowns (u_t, u_r, λ): stationarity of the Lagrangian, then the constraint
        A = np.array([[0.0, 0.0, normal[0]], [0.0, k_r, normal[1]], [normal[0], normal[1], 0.0]])
        u_t, u_r, _ = np.linalg.solve(A, [F_t, 0.0, 0.0])
        assert u_t > 0 and u_r < 0  # the tooth advances and the rim is pushed in
        assert -k_r * u_r == pytest.approx(F_t * np.tan(alpha), rel=1e-12)  # the flank's radial push
        assert cc.mesh_zone(k_r, r_p, alpha) == pytest.approx((u_t / r_p) / T, rel=1e-12)


def test_mesh_zone_grows_with_the_pressure_angle():
    base = load_unit()
    steeper = base.with_updates({"flexspline.pressure_angle": np.radians(25.0)})
    ratio = float(steeper.compliance().mesh_zone / base.compliance().mesh_zone)
    assert ratio == pytest.approx((np.tan(np.radians(25.0)) / np.tan(np.radians(20.0))) ** 2, rel=1e-12)


def test_pressure_angle_of_45_degrees_or_more_is_refused():
    with pytest.raises(InputError, match="pressure angle"):
        load_unit().with_updates({"flexspline.pressure_angle": 50.0})  # degrees given as radians


def test_every_term_of_the_chain_follows_similitude():
    """Scaling every length by s (geometry and wave generator; the bearing stiffness, a
    force per length, by s) scales every torsional compliance by s⁻³ exactly."""
    from dataclasses import fields

    from hdsim.model.datasheet import nominal_wave_generator
    from hdsim.model.drive import WaveGenerator, compliance_chain

    s = 1.7
    g = load_unit("CSG-20-100").geometry
    wg = nominal_wave_generator(20)
    dimensionless = {"teeth", "E", "nu", "pressure_angle"}
    big = g.replace(**{f.name: s * getattr(g, f.name) for f in fields(g) if f.name not in dimensionless})
    big_wg = WaveGenerator(k_bearing=s * wg.k_bearing, balls=wg.balls, support_width=s * wg.support_width,
                           engagement_fraction=wg.engagement_fraction)
    small, large = compliance_chain(g, wg).as_dict(), compliance_chain(big, big_wg).as_dict()
    for name in small:
        assert float(large[name]) == pytest.approx(float(small[name]) / s**3, rel=1e-9), name


def test_calibration_factor_is_nearly_the_same_for_every_size():
    """The catalog K1 grows as size³ (K1/size³ = 1.7–2.0 N·m/rad over sizes 14–32), and so
    does the chain: the factor that closes the gap must not drift with size."""
    kappas = [load_unit(name).calibration.kappa_mesh for name in unit_names()]
    assert max(kappas) / min(kappas) <= 1.5


def test_ball_pitch_is_the_angular_pitch_along_the_bore():
    model = load_unit()
    wg, g = model.wave_generator, model.geometry
    assert float(wg.ball_pitch(g.R_i)) == pytest.approx(2 * np.pi * g.R_i / wg.balls, rel=1e-12)


def test_support_wider_than_the_ball_pitch_is_refused():
    model = load_unit()
    pitch = 2 * np.pi * model.geometry.R_i / model.wave_generator.balls
    with pytest.raises(InputError, match="support_width"):
        model.with_updates({"wave_generator.support_width": 1.01 * pitch}).compliance()


def test_rim_on_the_balls_is_a_clamped_timoshenko_span():
    """Written out here: mean deflection of a fixed-fixed span under a uniform load q,
    bending q L⁴/(720 E I) (from w = q x² (L − x)² / (24 E I)) plus shear q L²/(12 κ G A)
    (from w = q x (L − x) / (2 κ G A)), both averaged over the span numerically."""
    h, b, E, nu, p, w_c, a = 1.0e-3, 10e-3, 210e9, 0.3, 8.7e-3, 1.6e-3, 29e-3
    L = p - w_c + 0.8 * h
    x = np.linspace(0.0, L, 200001)
    q = 1.0
    I, A, G = b * h**3 / 12, b * h, E / (2 * (1 + nu))
    w = q * x**2 * (L - x) ** 2 / (24 * E * I) + q * x * (L - x) / (2 * (5 / 6) * G * A)
    k = q * a / np.trapezoid(w, x) * L
    assert cc.rim_between_balls_stiffness(h, b, E, nu, p, w_c, a) == pytest.approx(k, rel=1e-8)


def test_tooth_root_sits_one_and_a_quarter_modules_inside_the_pitch_circle():
    g = nominal_geometry(25, 100)
    assert g.pitch_radius - (g.R_i + g.h_pz) == pytest.approx(1.25 * g.module, rel=1e-12)
