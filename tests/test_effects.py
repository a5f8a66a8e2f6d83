"""Every effect of every family: laws against closed forms, and the registry in a model."""

import dataclasses

import numpy as np
import pytest

from hdsim.model import effects as fx
from hdsim.model.catalog import load_unit
from hdsim.physics import backlash as bl
from hdsim.physics import friction as fr
from hdsim.physics import stiffness as st
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

K1 = 3.1e4
SAMPLE = {  # one physically sensible parameter set per effect of the registry
    ("hardening", "three_segment"): dict(T1=14.0, T2=48.0, e2=2.0, e3=2.7),
    ("hardening", "tanh"): dict(e_inf=2.5, T_s=20.0),
    ("backlash", "dead_zone"): dict(gap=1e-4),
    ("friction", "dahl_slip"): dict(slip_torque=3.0, slip_max=1e-4),
    ("friction", "dahl"): dict(torque_max=1.0, sigma=3 * K1),
    ("friction", "coulomb"): dict(torque=0.5, velocity_scale=1e-5),
    ("friction", "maxwell_slip"): dict(k_total=K1, slip_torque_max=2.0, velocity_scale=1e-6),
    ("damping", "viscous"): dict(coefficient=1.0),
    ("kinematic_error", "fourier"): dict(a1=1e-5, a2=3e-5, a4=5e-6, p1=0.1, p2=0.2, p4=0.3,
                                         a_out=2e-5, p_out=0.0, load_gain=0.1),
}


def test_every_registered_effect_has_a_sample_and_a_none():
    registered = {(fam, eid) for fam, classes in fx.FAMILIES.items() for eid in classes if eid != "none"}
    assert registered == set(SAMPLE)
    assert all("none" in classes for classes in fx.FAMILIES.values())


@pytest.mark.parametrize("key", sorted(SAMPLE))
def test_effects_are_frozen_parameter_holders(key):
    effect = fx.make_effect(*key, **SAMPLE[key])
    assert dataclasses.is_dataclass(effect)
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(effect, next(iter(SAMPLE[key])), 0.0)
    for name in SAMPLE[key]:
        meta = type(effect).param_meta()[name]
        assert meta["unit"] and meta["doc"]


@pytest.mark.parametrize("key", [k for k in sorted(SAMPLE) if k[0] != "kinematic_error"])
def test_every_effect_runs_in_the_lost_motion_test(key):
    model = load_unit().without("hardening", "backlash", "friction").with_effects(
        **{key[0]: fx.make_effect(*key, **SAMPLE[key])})
    run = run_scenario(model, load_scenario(builtin_scenario_path("lost_motion")))
    assert np.isfinite(run.result.signals["twist_rad"]).all()
    assert 0.3 < run.metric("lost_motion_arcmin") < 5.0


def test_make_effect_refuses_unknown_and_missing_parameters():
    from hdsim.errors import InputError

    with pytest.raises(InputError, match="unknown parameter"):
        fx.make_effect("backlash", "dead_zone", gap=1e-4, width=1)
    with pytest.raises(InputError, match="needs"):
        fx.make_effect("friction", "dahl")
    with pytest.raises(InputError, match="did you mean"):
        fx.effect_class("friction", "dahll")
    with pytest.raises(InputError, match="outside"):
        fx.make_effect("backlash", "dead_zone", gap=-1e-4)


# ------------------------------------------------------------------ laws vs closed forms
def test_dead_zone_is_seed_paper_eq_2():
    x = np.array([-3.0, -1.0, 0.0, 0.5, 1.0, 2.5])
    assert bl.dead_zone(x, 1.0).tolist() == [-2.0, 0.0, 0.0, 0.0, 0.0, 1.5]


def test_smooth_dead_zone_converges_to_the_exact_one():
    x = np.linspace(-3, 3, 601)
    assert np.max(np.abs(bl.smooth_dead_zone(x, 1.0, 1e-3) - bl.dead_zone(x, 1.0))) < 1e-3


@pytest.mark.parametrize("half,width", [(1e-4, 4e-5), (1e-4, 1e-6), (0.0, 1e-12)])
def test_inverse_smooth_dead_zone_is_the_inverse(half, width):
    y = np.concatenate([np.linspace(-3e-3, 3e-3, 20001), [0.0, 40 * width, -45 * width]])
    v = bl.smooth_dead_zone(y, half, width)
    back = bl.inverse_smooth_dead_zone(v, half, width)
    # the forward law is flat in the gap (slope ~e^(-h/w)): compare where it has slope
    sloped = bl.smooth_contact(y, half, width) > 1e-6
    np.testing.assert_allclose(back[sloped], y[sloped], rtol=0, atol=1e-12)
    np.testing.assert_allclose(bl.smooth_dead_zone(back, half, width), v, rtol=0, atol=1e-15)


def test_optional_parameters_take_their_default():
    damping = fx.make_effect("damping", "viscous", coefficient=2.0)
    assert damping.stiffness_share == 0.0
    assert damping.coefficient_at(3.0) == 2.0  # constant without a stiffness share
    rayleigh = fx.make_effect("damping", "viscous", coefficient=2.0, stiffness_share=1.0)
    assert rayleigh.coefficient_at(3.0) == pytest.approx(6.0)  # β·K_t


@pytest.mark.parametrize("law", [bl.elasto_backlash_torque, bl.smooth_elasto_backlash_torque])
def test_elasto_backlash_never_pulls_and_damping_never_exceeds_spring(law):
    rng = np.random.default_rng(0)
    spring = rng.normal(size=1000)
    damping = 5 * rng.normal(size=1000)
    torque = law(spring, damping)
    assert np.all(torque * np.sign(spring) >= -1e-12)           # never pulls
    assert np.all(np.abs(torque - spring) <= np.abs(spring) + 1e-12)


def test_tanh_hardening_tangent_goes_from_K0_to_Kinf():
    K0, Kinf, s = 3e4, 6e4, 1e-4
    assert st.tanh_hardening_tangent(0.0, K0, Kinf, s) == pytest.approx(K0)
    assert st.tanh_hardening_tangent(0.01, K0, Kinf, s) == pytest.approx(Kinf)
    phi = np.linspace(-1e-3, 1e-3, 2001)
    numeric = np.gradient(st.tanh_hardening_torque(phi, K0, Kinf, s), phi)
    assert numeric[1:-1] == pytest.approx(st.tanh_hardening_tangent(phi, K0, Kinf, s)[1:-1], rel=1e-3)


def test_dahl_rate_saturates_at_the_coulomb_level():
    # integrate dz/dx = σ(1 − z/F) along a monotonic sweep: z = F(1 − exp(−σx/F))
    sigma, F = 1e4, 2.0
    x = np.linspace(0, 1e-3, 20001)
    z = np.zeros_like(x)
    for i in range(1, x.size):
        z[i] = z[i - 1] + fr.dahl_rate(z[i - 1], 1.0, sigma, F) * (x[i] - x[i - 1])
    assert z[-1] == pytest.approx(F * (1 - np.exp(-sigma * x[-1] / F)), rel=1e-3)


def test_coulomb_is_odd_and_saturates():
    assert fr.smooth_coulomb(1.0, 0.5, 1e-3) == pytest.approx(0.5)
    assert fr.smooth_coulomb(-1.0, 0.5, 1e-3) == pytest.approx(-0.5)


def test_maxwell_slip_elements_stick_then_slide():
    k = np.array([[1e3], [1e3]])
    f = np.array([[1.0], [2.0]])
    sticking = fr.maxwell_slip_rates(np.zeros((2, 1)), 1e-3, k, f, 1e-6)
    assert sticking.ravel() == pytest.approx([1e-3, 1e-3])
    saturated = fr.maxwell_slip_rates(np.array([[1e-3], [1e-3]]), 1e-3, k, f, 1e-6)  # element 0 at its slip torque
    assert saturated.ravel()[0] == pytest.approx(0.0, abs=1e-9)
    assert saturated.ravel()[1] > 0.99e-3


def test_fourier_kinematic_error_is_the_configured_series():
    effect = fx.make_effect("kinematic_error", "fourier", **{**SAMPLE[("kinematic_error", "fourier")],
                                                             "load_gain": 0.0})
    wg = np.linspace(0, 4 * np.pi, 50)
    out = wg / 100
    expected = (1e-5 * np.sin(wg + 0.1) + 3e-5 * np.sin(2 * wg + 0.2) + 5e-6 * np.sin(4 * wg + 0.3)
                + 2e-5 * np.sin(out))
    assert effect.displacement(wg, out, 0.0) == pytest.approx(expected, abs=1e-15)
