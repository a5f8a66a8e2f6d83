"""What a fitted drive predicts for the catalog tests, against closed forms.

A plain linear spring: the fit has one free parameter, the stiffness K0, with its
standard uncertainty σ_K from the fit. Its ±4 % lost motion is ``0.08 T_N / K0`` (no gap,
no friction), so the linearised 95 % band is ``±1.96 · LM · σ_K / K0`` to first order, and
its K1 is K0 with the band ``±1.96 σ_K``.
"""

from __future__ import annotations

import numpy as np
import pytest

from hdsim.identification.fit import fit
from hdsim.identification.predictions import Z95, catalog_predictions
from hdsim.io.measurement import Measurement
from hdsim.model.catalog import load_unit
from hdsim.units import rad_to_arcmin

K, RATED, NOISE = 31_000.0, 87.0, 2e-6


@pytest.fixture(scope="module")
def spring_fit():
    t = np.linspace(0.0, 40.0, 2000)
    torque = RATED * np.sin(2 * np.pi * t / 20.0)
    angle = torque / K + np.random.default_rng(3).normal(0.0, NOISE, t.size)
    meas = Measurement(test="stiffness", time=t, torque=torque, angle=angle)
    return fit(meas, [], unit=load_unit("CSG-25-100").with_effects(
        hardening=_none("hardening"), backlash=_none("backlash"), friction=_none("friction"),
        damping=_none("damping")))


def _none(family):
    from hdsim.model import effects as fx

    return fx.NO_EFFECT[family]


def test_a_linear_spring_predicts_its_lost_motion_and_k1_with_the_closed_form_band(spring_fit):
    K0 = float(spring_fit.derived["K0_Nm_per_rad"])
    sigma = spring_fit.uncertainty["stiffness.K0"]
    assert K0 == pytest.approx(K, rel=1e-3) and 0 < sigma < 1e-2 * K0
    predictions = {p.label: p for p in catalog_predictions(spring_fit)}
    lost = predictions["lost motion, ±4 % T_N"]
    expected = rad_to_arcmin(0.08 * RATED / K0)
    assert lost.value == pytest.approx(expected, rel=1e-3) and lost.method == "linearised"
    half = Z95 * expected * sigma / K0
    assert (lost.high - lost.low) / 2 == pytest.approx(half, rel=0.02)
    k1 = predictions["K1"]
    assert k1.value == pytest.approx(K0, rel=1e-3) and k1.datasheet == 31_000.0
    assert (k1.high - k1.low) / 2 == pytest.approx(Z95 * sigma, rel=0.02)


def test_a_report_page_shows_the_predictions(spring_fit, tmp_path):
    from hdsim.identification.diagnosis import StiffnessTest
    from hdsim.identification.report_page import fit_page

    page = fit_page(spring_fit, tmp_path, spring_fit.summary(), StiffnessTest())
    text = page.read_text()
    assert "What the fitted drive predicts" in text and "95 % band" in text and "lost motion, ±4 % T_N" in text


def test_a_sweeps_running_torque_at_2000_rpm_has_the_band_of_its_linear_law():
    """A Coulomb level plus viscous loss: the running torque at ω = 2000 rpm is
    ``F_c + b ω`` and its variance ``[1, ω] Σ [1, ω]ᵀ`` from the amplitudes' covariance."""
    import math

    from test_running_torque import law_record

    from hdsim.identification.predictions import CATALOG_SPEED, sweep_predictions
    from hdsim.identification.running_fit import fit_running
    from hdsim.model.input_friction import InputFriction

    truth = InputFriction(starting_torque=0.05, coulomb_torque=0.05, viscous=2e-4, stribeck_speed=8.0,
                          velocity_scale=0.05)
    fit = fit_running(law_record(truth, noise=1e-3), ["damping"])
    names = list(fit.fitted)
    c, b = names.index("base.coulomb_torque"), names.index("damping.viscous")
    cov = fit.coordinates.covariance
    w = CATALOG_SPEED
    predictions = {p.label: p for p in sweep_predictions(fit, None)}
    forward = predictions["running torque at 2000 rpm, forward"]
    assert forward.value == pytest.approx(fit.fitted["base.coulomb_torque"] + fit.fitted["damping.viscous"] * w,
                                          rel=1e-6)
    half = Z95 * math.sqrt(cov[c, c] + 2 * w * cov[c, b] + w * w * cov[b, b])
    assert (forward.high - forward.low) / 2 == pytest.approx(half, rel=1e-6)
    assert forward.low < 0.05 + 2e-4 * w < forward.high  # the truth lies in the band
    assert forward.datasheet is None and forward.method == "linear in the amplitudes"


# --------------------------------------------------------------------------- a model that misses an effect

CAVEAT = "The model leaves structure in the residual"


def _twist_fit(hardening: float):
    """A 250-row ±T_N cycle of a spring whose twist at T_N is short of the linear one by the
    fraction ``hardening`` (stiffer under load: hidden hardening unless 0), fitted with the
    linear spring alone."""
    t = np.linspace(0.0, 40.0, 250)
    torque = RATED * np.sin(2 * np.pi * t / 20.0)
    angle = torque / K * (1 - hardening * (torque / RATED) ** 2) + np.random.default_rng(3).normal(0.0, NOISE, t.size)
    meas = Measurement(test="stiffness", time=t, torque=torque, angle=angle)
    return fit(meas, [], unit=load_unit("CSG-25-100").with_effects(
        **{family: _none(family) for family in ("hardening", "backlash", "friction", "damping")}))


def _fit_page_text(result, folder) -> str:
    from hdsim.identification.diagnosis import StiffnessTest
    from hdsim.identification.report_page import fit_page

    return (fit_page(result, folder, result.summary(), StiffnessTest()).parent / "index.md").read_text()


def test_a_fit_that_misses_hardening_says_its_bands_assume_its_form(tmp_path):
    """The spring fitted without the hardening the record holds: K1's band (wide as the
    structured residual makes it) misses the true 31 000 N·m/rad, and the page says, beside
    the bands, that the model leaves structure: the verdict's judgement and its rms ratio."""
    from hdsim.identification.residuals import whiteness

    result = _twist_fit(0.1)
    w = whiteness(result.residual)
    assert not w["explained"]
    k1 = {p.label: p for p in catalog_predictions(result)}["K1"]
    assert not k1.low <= K <= k1.high  # what the caveat is for
    text = _fit_page_text(result, tmp_path)
    line = next(line for line in text.splitlines() if CAVEAT in line)
    assert f"rms {w['rms_over_noise']:.1f}× the noise floor" in line and "assume its form is right" in line
    assert text.index("What the fitted drive predicts") < text.index(CAVEAT) < text.index("| K1 |")


def test_a_fit_that_explains_its_record_shows_no_caveat(tmp_path):
    text = _fit_page_text(_twist_fit(0.0), tmp_path)
    assert "What the fitted drive predicts" in text and CAVEAT not in text


@pytest.mark.parametrize("families, caveat", [(["damping"], False), ([], True)])
def test_a_sweeps_predictions_carry_the_caveat_when_the_law_misses_an_effect(families, caveat):
    """A sweep of a Coulomb level with viscous loss: fitted with damping its residual is
    explained; fitted without it, the running torque at 2000 rpm comes with the caveat (the
    running-torque verdict's judgement, against the record's model-free noise floor)."""
    from test_running_torque import law_record

    from hdsim.identification.report_page import Page, _predictions
    from hdsim.identification.running_diagnosis import RunningTorqueTest
    from hdsim.identification.running_fit import fit_running
    from hdsim.model.input_friction import InputFriction

    truth = InputFriction(starting_torque=0.05, coulomb_torque=0.05, viscous=2e-4, stribeck_speed=8.0,
                          velocity_scale=0.05)
    result = fit_running(law_record(truth, noise=1e-3, fs=300.0), families)
    page = Page("sweep")
    _predictions(page, RunningTorqueTest(), result, None)
    text = page.markdown()
    assert "running torque at 2000 rpm, forward" in text and (CAVEAT in text) is caveat


def test_a_draw_whose_values_contradict_each_other_is_left_out_not_the_whole_band():
    """run_scenario refuses a batch holding a hardening with T1 above T2 (as --set does); a
    band's draws had then all been lost for one such draw ("no band")."""
    from types import SimpleNamespace

    from hdsim.identification.predictions import _metrics
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

    coordinates = SimpleNamespace(updates=lambda rows: {"hardening.T1": rows[:, 0], "hardening.T2": rows[:, 1]})
    rows = np.array([[14.0, 48.0], [50.0, 48.0], [20.0, 48.0]])
    scenario = load_scenario(builtin_scenario_path("stiffness"))
    (K1,) = _metrics(load_unit("CSG-25-100"), coordinates, rows, scenario, ["K1_Nm_per_rad"])
    assert np.isnan(K1[1]) and np.all(np.isfinite(K1[[0, 2]]))
