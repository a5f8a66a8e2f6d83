"""Checks of a record before any fit (hdsim.io.data_checks) and the honest outcome of a
diagnosis (hdsim.identification.outcome). Records are built here or by tests/truth.py,
which shares no code with hdsim; expected values come from how they were built."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import truth
from hdsim.identification.outcome import assess
from hdsim.identification.workflow import examine
from hdsim.io.data_checks import DriveScale
from hdsim.io.measurement import make_measurement, save_measurement
from hdsim.model.catalog import load_unit
from hdsim.signals import local_cubic_weights, noise_level

DRIVE = DriveScale.of(load_unit("CSG-25-100"))


def _by_name(checks):
    return {c.check: c for c in checks}


@pytest.mark.parametrize("sigma", [1e-6, 1e-3, 0.5])
def test_noise_is_estimated_without_a_model(sigma):
    """White noise on a slow cycle with steps: the estimate is within 10 % of the σ drawn."""
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 10.0, 4000)
    clean = 50.0 * sigma * (np.sin(2 * np.pi * 0.3 * t) + (t > 4.0))  # a smooth swing and one step
    assert noise_level(clean + rng.normal(0.0, sigma, t.size)) == pytest.approx(sigma, rel=0.1)
    coarse = 50.0 * np.sin(np.linspace(0, 2 * np.pi, 60))  # 60 samples a cycle: curvature, not noise
    assert noise_level(coarse) < 1e-4 * np.ptp(coarse)


@pytest.mark.parametrize("jitter", [0.2, 0.45])
def test_noise_of_an_unevenly_sampled_log_is_its_own(jitter):
    """A logger's jitter makes a swing no smooth function of the row number: read by row, 45 %
    jitter gave 2.2 times the σ drawn; fitted in time, the estimate is within 10 % again."""
    rng = np.random.default_rng(2)
    steps = 1.0 + jitter * (2.0 * rng.random(3999) - 1.0)
    t = np.concatenate([[0.0], np.cumsum(steps)]) * 1e-2  # a swing of 87 moves ~1 a row
    x = 87.0 * np.sin(2 * np.pi * t / 5.0) + rng.normal(0.0, 0.05, t.size)
    assert noise_level(x) > 1.3 * 0.05  # the row number is no clock here
    assert noise_level(x, t) == pytest.approx(0.05, rel=0.1)


def test_an_evenly_sampled_log_is_read_by_row_whatever_its_time_stamps_say():
    """Time stamps printed to a few digits (0.000732 s) spread by their rounding: the row number
    is the better clock, and the estimate is the one without a time axis, bit for bit."""
    rng = np.random.default_rng(3)
    t = np.round(np.arange(4000) * 7.32e-4, 6)
    x = np.sin(t) + rng.normal(0.0, 1e-3, t.size)
    assert noise_level(x, t) == noise_level(x)


def test_local_cubic_weights_are_savitzky_golay_coefficients():
    from scipy.signal import savgol_coeffs

    for window in (5, 7, 11):
        np.testing.assert_allclose(local_cubic_weights(window), savgol_coeffs(window, 3), atol=1e-14)


def test_rank_correlation_is_spearmans_with_ties():
    from scipy.stats import spearmanr

    from hdsim.io.data_checks import _rank_correlation

    rng = np.random.default_rng(3)
    a = rng.normal(size=500)
    b = np.round(a + rng.normal(0, 0.8, a.size), 1)  # quantised: many ties, as an encoder gives
    assert _rank_correlation(a, b) == pytest.approx(spearmanr(a, b).statistic, abs=1e-12)
    assert _rank_correlation(a, np.round(-a, 0)) == pytest.approx(spearmanr(a, np.round(-a, 0)).statistic, abs=1e-12)


def test_a_truth_stiffness_record_passes_and_its_cycle_is_counted():
    cols, _ = truth.make_stiffness_data(set(), set(), seed=4, n_rows=2000)  # two loading rates, one cycle each
    meas = make_measurement("stiffness", cols["time_s"], cols["torque_Nm"], cols["angle_rad"])
    checks, data, wrong = examine(meas, DRIVE)
    by = _by_name(checks)
    assert wrong == ""
    assert all(by[c].status == "ok" for c in ("twist_span", "angle_follows_torque", "torque_noise", "reversals",
                                              "loading_rates"))
    assert data["reversals"] == 7  # per block 0→+A→−A→+A→0 turns 3 times, and 0→+A again at the join
    assert data["loading_rates"] == 2
    # the truth's angle noise: 2e-6 rad white plus a 1.5e-6 rad quantiser (σ = q/√12)
    assert data["noise_floor_rad"] == pytest.approx(math.hypot(2e-6, truth.QUANT_RAD / math.sqrt(12)), rel=0.15)


def _friction_sweep():
    """An 80° friction sweep at constant speed each way, torque from current with ±1.5 N·m noise."""
    t = np.linspace(0.0, 20.0, 2000)
    angle = math.radians(80.0) * np.abs((t / 10.0) % 2.0 - 1.0)
    torque = 7.0 * np.sign(np.gradient(angle)) + np.random.default_rng(0).normal(0.0, 1.5, t.size)
    return t, torque, angle


def test_a_friction_sweep_is_not_a_stiffness_test(tmp_path, cli):
    t, torque, angle = _friction_sweep()
    path = save_measurement(make_measurement("stiffness", t, torque, angle), tmp_path / "sweep.csv")
    code, out, err = cli("fit", path, "--json")
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "not a stiffness test" in err and "turning freely" in err
    code, out, err = cli("diagnose", path, "--json", "--report", str(tmp_path / "rep"))
    assert code == 0, err
    summary = json.loads(out)
    assert summary["outcome"] == "wrong_test" and summary["added"] == []
    page = (tmp_path / "rep" / "index.html").read_text()  # the page says why nothing was fitted
    assert summary["report"].endswith("index.html") and "not a stiffness test" in page and "twist_span" in page
    by = {c["check"]: c for c in summary["checks"]}
    assert by["twist_span"]["status"] == "fail" and by["torque_noise"]["status"] == "warn"


def test_angles_in_other_units_are_caught():
    cols, _ = truth.make_stiffness_data(set(), set(), seed=2, n_rows=800)
    in_degrees = make_measurement("stiffness", cols["time_s"], cols["torque_Nm"], np.degrees(cols["angle_rad"]))
    checks, _, wrong = examine(in_degrees, DRIVE)
    assert "other units" in wrong
    in_arcsec_as_rad = make_measurement("stiffness", cols["time_s"], cols["torque_Nm"],
                                        cols["angle_rad"] / 206264.8)
    checks, _, wrong = examine(in_arcsec_as_rad, DRIVE)
    assert wrong == "" and _by_name(checks)["twist_span"].status == "warn"


def test_kinematic_error_records_that_cannot_be_one():
    cols, _ = truth.make_ke_data(set(), set(), seed=1, n_rows=2000)
    ratio = 100.0
    good = make_measurement("kinematic_error", cols["time_s"], cols["torque_Nm"], cols["output_angle_rad"],
                            cols["wg_angle_rad"], ratio=ratio)
    assert examine(good, DRIVE)[2] == ""
    one_encoder = make_measurement("kinematic_error", cols["time_s"], cols["torque_Nm"],
                                   cols["wg_angle_rad"] / ratio, cols["wg_angle_rad"], ratio=ratio)
    assert "one encoder logged twice" in examine(one_encoder, DRIVE)[2]
    wrong_ratio = make_measurement("kinematic_error", cols["time_s"], cols["torque_Nm"], cols["output_angle_rad"],
                                   cols["wg_angle_rad"], ratio=50.0)
    assert "wrong ratio" in examine(wrong_ratio, DRIVE)[2]


def test_a_saturated_torque_channel_is_named():
    cols, _ = truth.make_stiffness_data(set(), set(), seed=3, n_rows=1000)
    torque = np.clip(cols["torque_Nm"], -60.0, 60.0)  # the amplifier's current limit
    meas = make_measurement("stiffness", cols["time_s"], torque, cols["angle_rad"])
    sat = _by_name(examine(meas, DRIVE)[0])["saturation"]
    assert sat.status == "warn" and "maximum 60" in sat.message


def _diagnosis(added=(), success=False, n_eff=500.0, ambiguous=(), first="hardening"):
    return {"test": "stiffness", "added": list(added), "success": success, "ambiguous": list(ambiguous),
            "ranking": [{"family": first, "score": -5.0, "n_eff": n_eff}]}


@pytest.mark.parametrize("diagnosis, data, outcome, says", [
    (_diagnosis(["hardening"], True), {"reversals": 7, "loading_rates": 2}, "found", ""),
    (_diagnosis(["hardening"], False), {"reversals": 7, "loading_rates": 2}, "improved", ""),
    (_diagnosis([], True), {"reversals": 7, "loading_rates": 2}, "nothing_missing", ""),
    (_diagnosis([], False, n_eff=2.0), {"rows": 154, "reversals": 7, "loading_rates": 2}, "cannot_decide",
     "independent samples"),
    (_diagnosis([], False), {"reversals": 0, "loading_rates": 1}, "cannot_decide", "torque cycle"),
    (_diagnosis([], False, first="damping"), {"reversals": 7, "loading_rates": 1}, "cannot_decide",
     "second loading rate"),
    (_diagnosis([], False, ambiguous=[{"families": ["friction", "backlash"], "measurement": "a slower cycle"}]),
     {"reversals": 7, "loading_rates": 2}, "cannot_decide", "a slower cycle"),
    # a loss one rate could not name (the pair reported, neither added) is never "nothing
    # missing", and a found family does not silence its measurement
    (_diagnosis([], True, ambiguous=[{"families": ["damping", "friction"], "measurement": "a second rate",
                                      "added": False}]), {"reversals": 7, "loading_rates": 1},
     "cannot_decide", "a second rate"),
    (_diagnosis(["hardening"], True, ambiguous=[{"families": ["damping", "friction"], "measurement": "a second rate",
                                                 "added": False}]), {"reversals": 7, "loading_rates": 1},
     "found", "a second rate"),
])
def test_outcomes_are_honest(diagnosis, data, outcome, says):
    from hdsim.identification.workflow import test_kind

    got, next_measurement = assess(diagnosis, data, test_kind(diagnosis["test"]))
    assert got == outcome
    assert says in next_measurement


def test_loading_direction_survives_a_torque_from_motor_current():
    """A triangular torque cycle with 10 % noise (torque from current): the direction is the
    leg's, at nearly every sample (the sign of dT/dt of the raw torque is a coin toss)."""
    from hdsim.signals import loading_direction

    t = np.linspace(0.0, 8.0, 4000)
    clean = 80.0 * (2.0 * np.abs((t / 4.0 + 0.25) % 1.0 - 0.5) * 2.0 - 1.0)  # ±80 N·m, 4 s period
    noisy = clean + np.random.default_rng(5).normal(0.0, 8.0, t.size)
    truth_sign = np.sign(np.gradient(clean, t))
    sign, _ = loading_direction(t, noisy)
    inside = np.abs(clean) < 70.0  # away from the turning points, where a leg's end is a matter of definition
    assert np.mean(sign[inside] == truth_sign[inside]) > 0.99
    assert np.mean(np.sign(np.gradient(noisy, t))[inside] == truth_sign[inside]) < 0.7


def test_implausible_fits_are_named():
    """A fitted stiffness 40× below the datasheet, a friction above rated torque, a gap of
    degrees and an undetermined parameter are each named; a sensible fit is ok."""
    from hdsim.identification.outcome import plausibility

    odd = {"fitted": {"stiffness.K0": DRIVE.K_soft / 40, "friction.torque_max": 2 * DRIVE.rated_torque,
                      "backlash.gap": math.radians(3.0), "friction.sigma": 1e5},
           "uncertainty": {"friction.sigma": 3e5}, "derived": {}}
    named = {c["check"] for c in plausibility(odd, DRIVE)}
    assert named == {"stiffness", "friction_level", "gap", "uncertainty"}
    sane = {"fitted": {"stiffness.K0": DRIVE.K_soft * 1.1, "friction.torque_max": 3.0},
            "uncertainty": {"stiffness.K0": 100.0, "friction.torque_max": 0.1}, "derived": {}}
    assert [c["status"] for c in plausibility(sane, DRIVE)] == ["ok"]


def test_a_kinematic_error_record_at_few_samples_a_turn_has_its_encoders_noise_floor(truth_ke):
    """29 samples per wave-generator turn: a period of the 4x order spans seven samples, the
    window of the noise estimate, so the kinematic error is not locally cubic; the floor is
    read once its WG orders are removed and comes out at the truth's encoder noise (white
    noise plus the quantisation step over √12)."""
    cols, tr = truth_ke
    meas = make_measurement("kinematic_error", cols["time_s"], cols["torque_Nm"], cols["output_angle_rad"],
                            wg_angle=cols["wg_angle_rad"], ratio=float(tr["meta"]["ratio"]))
    noise = tr["measurement"]
    expected = math.hypot(noise["noise_rad"], noise["quant_rad"] / math.sqrt(12.0))
    turns = np.ptp(meas.wg_angle) / (2 * math.pi)
    assert len(meas) / turns < 30  # few samples a turn
    assert noise_level(meas.kinematic_error) > 5 * expected  # what the plain estimate gives
    _, data, _ = examine(meas, DriveScale.of(load_unit()))
    assert data["noise_floor_rad"] == pytest.approx(expected, rel=0.15)
