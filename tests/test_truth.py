"""The independent truth generators: determinism, realism, and each family's signature.

The signature checks work on the noisy, offset, quantised columns a diagnosis would see
(and on the clean arrays only where a number is compared with its drawn parameter).
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import truth
from hdsim.io.measurement import load_measurement

ARCMIN = truth.ARCMIN
SEEDS = [0, 1, 2]


def stiff(hidden=(), baseline=(), seed=0, **kw):
    return truth.make_stiffness_data(set(hidden), set(baseline), seed=seed, **kw)


def leg(tr, block, index):
    """Sample mask of one leg (0-based within a rate block) of the torque profile."""
    knots = tr["profile"]["knots_t"]
    per_block = 2 + 2 * tr["profile"]["cycles"]
    k = block * per_block + index
    t = np.linspace(knots[0], knots[-1], tr["clean"]["torque_Nm"].size)
    return (t >= knots[k]) & (t < knots[k + 1])


def line_fit(torque, angle, lo, hi):
    """Slope [rad/N·m] and intercept [rad] of angle vs torque for lo <= T <= hi."""
    m = (torque >= lo) & (torque <= hi)
    return np.polyfit(torque[m], angle[m], 1)


# --------------------------------------------------------------------------- independence


def test_truth_module_does_not_import_hdsim():
    tree = ast.parse(Path(truth.__file__).read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            assert not any(a.name.split(".")[0] == "hdsim" for a in node.names)
        if isinstance(node, ast.ImportFrom):
            assert (node.module or "").split(".")[0] != "hdsim"
    text = Path(truth.__file__).read_text()
    assert "from hdsim" not in text and "import hdsim" not in text
    assert "import_module" not in text and "__import__" not in text


# --------------------------------------------------------------------------- determinism


@pytest.mark.parametrize("make", [truth.make_stiffness_data, truth.make_ke_data])
def test_same_seed_same_data_other_seed_other_data(make):
    fams = {"friction", "hardening"}
    a_cols, a_tr = make(fams, set(), seed=5, n_rows=600)
    b_cols, b_tr = make(fams, set(), seed=5, n_rows=600)
    c_cols, c_tr = make(fams, set(), seed=6, n_rows=600)
    for name in a_cols:
        np.testing.assert_array_equal(a_cols[name], b_cols[name])
    assert a_tr["params"]["k1"] == b_tr["params"]["k1"] != c_tr["params"]["k1"]
    angle = "angle_rad" if "angle_rad" in a_cols else "output_angle_rad"
    assert not np.array_equal(a_cols[angle], c_cols[angle])


def test_family_draws_do_not_depend_on_other_families():
    _, alone = stiff({"friction"}, seed=3)
    _, mixed = stiff({"friction"}, {"damping", "backlash"}, seed=3)
    assert alone["params"]["friction"] == mixed["params"]["friction"]
    assert alone["params"]["offset_rad"] == mixed["params"]["offset_rad"]


def test_hidden_and_baseline_are_recorded_and_checked():
    _, tr = stiff({"backlash"}, {"friction", "hardening"}, seed=0)
    assert tr["hidden"] == ["backlash"] and tr["baseline"] == ["friction", "hardening"]
    assert tr["families"] == ["backlash", "friction", "hardening"]
    assert tr["params"]["damping"] is None
    with pytest.raises(ValueError, match="both hidden and in the baseline"):
        stiff({"friction"}, {"friction"})
    with pytest.raises(ValueError, match="kinematic_error"):
        stiff({"kinematic_error"})
    with pytest.raises(ValueError, match="frictoin"):
        truth.make_ke_data({"frictoin"})


# --------------------------------------------------------------------------- measurement chain


def test_noise_quantisation_offset_and_csv_round_trip(tmp_path):
    cols, tr = stiff(seed=2)
    q, clean = tr["measurement"]["quant_rad"], tr["clean"]["angle_rad"]
    steps = cols["angle_rad"] / q
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)  # on the encoder grid
    error = cols["angle_rad"] - clean
    assert 1.5e-6 < error.std() < 3e-6  # 2e-6 rad noise + q/sqrt(12) quantisation
    assert abs(tr["params"]["offset_rad"]) <= math.pi and abs(tr["params"]["offset_rad"]) > 0
    assert 0.005 < (cols["torque_Nm"] - tr["clean"]["torque_Nm"]).std() < 0.015
    _, fixed = stiff(seed=2, offset_rad=0.25)
    assert fixed["params"]["offset_rad"] == 0.25

    meas = load_measurement(truth.write_csv(tmp_path / "s.csv", cols, tr["meta"]))
    np.testing.assert_array_equal(meas.angle, cols["angle_rad"])
    assert meas.rated_torque == truth.RATED_TORQUE_NM
    h5 = load_measurement(truth.write_hdf5(tmp_path / "s.h5", cols, tr["meta"]))
    np.testing.assert_array_equal(h5.torque, cols["torque_Nm"])


def test_default_profile_has_two_rates_and_reaches_rated_torque():
    cols, tr = stiff(seed=0)
    clean_T, block = tr["clean"]["torque_Nm"], tr["clean"]["block"]
    assert set(np.unique(block)) == {0, 1}
    assert clean_T.max() == pytest.approx(truth.RATED_TORQUE_NM, rel=0.01)
    assert clean_T.min() == pytest.approx(-truth.RATED_TORQUE_NM, rel=0.01)
    rates = [np.median(np.abs(np.gradient(clean_T[block == b], cols["time_s"][block == b])))
             for b in (0, 1)]
    assert rates[1] / rates[0] == pytest.approx(4.0, rel=0.01)


def test_base_alone_is_linear_elastic():
    cols, tr = stiff(seed=1, noise_rad=0.0, quant_rad=0.0, noise_Nm=0.0)
    twist = cols["angle_rad"] - tr["params"]["offset_rad"]
    np.testing.assert_allclose(twist, cols["torque_Nm"] / tr["params"]["k1"], atol=1e-12)


def test_every_form_runs_together_and_stays_finite():
    """The heaviest combinations (Maxwell-slip with every stiffness family; KE with friction
    and backlash) run and give finite, quantised columns. (Their speed is not a test.)"""
    cols, tr = stiff({"friction", "damping", "hardening", "backlash"}, seed=0, friction_form="maxwell_slip")
    assert all(np.all(np.isfinite(c)) for c in cols.values())
    assert tr["params"]["friction"]["form"] == "maxwell_slip"
    cols, tr = truth.make_ke_data({"kinematic_error", "friction", "backlash"}, seed=0)
    assert all(np.all(np.isfinite(c)) for c in cols.values())
    steps = cols["output_angle_rad"] / tr["measurement"]["quant_rad"]
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)


# --------------------------------------------------------------------------- signatures


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("form", ["cubic", "exponential"])
def test_hardening_slope_grows_with_load(seed, form):
    cols, tr = stiff({"hardening"}, seed=seed, hardening_form=form)
    T, th = cols["torque_Nm"], cols["angle_rad"]
    first = leg(tr, 0, 0)  # virgin loading 0 -> +T_N
    low = line_fit(T[first], th[first], 1.0, 8.0)[0]
    high = line_fit(T[first], th[first], 65.0, 85.0)[0]
    assert 1.0 / high > 1.5 / low  # tangent stiffness at load well above K1
    assert 1.0 / low == pytest.approx(tr["params"]["k1"], rel=0.05)
    theta_n = tr["clean"]["twist_rad"][np.argmax(tr["clean"]["torque_Nm"])]
    linear = truth.RATED_TORQUE_NM / tr["params"]["k1"]
    assert theta_n == pytest.approx((1 - tr["params"]["hardening"]["h"]) * linear, rel=1e-3)

    base, _ = stiff(seed=seed)
    base_T, base_th = base["torque_Nm"][first], base["angle_rad"][first]
    base_low = line_fit(base_T, base_th, 1.0, 8.0)[0]
    base_high = line_fit(base_T, base_th, 65.0, 85.0)[0]
    assert base_high == pytest.approx(base_low, rel=0.02)  # without the family: linear


@pytest.mark.parametrize("seed", SEEDS)
def test_backlash_step_at_zero_torque(seed):
    def step(cols, tr):
        down = leg(tr, 0, 1)  # +T_N -> -T_N
        T, th = cols["torque_Nm"][down], cols["angle_rad"][down]
        pos = line_fit(T, th, 3.0, 25.0)
        neg = line_fit(T, th, -25.0, -3.0)
        return pos[1] - neg[1]  # intercepts of both sides at T = 0

    cols, tr = stiff({"backlash"}, seed=seed)
    b = tr["params"]["backlash"]["b_rad"]
    assert 0.3 * ARCMIN <= b <= 1.0 * ARCMIN
    assert step(cols, tr) == pytest.approx(b, rel=0.05)
    assert abs(step(*stiff(seed=seed))) < 0.05 * ARCMIN


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("form", ["bouc_wen", "maxwell_slip"])
def test_friction_branches_separate_and_do_not_depend_on_rate(seed, form):
    cols, tr = stiff({"friction"}, seed=seed, friction_form=form)
    block = tr["clean"]["block"]
    widths = [truth.loop_width_at_zero_torque(cols["torque_Nm"][block == b],
                                              cols["angle_rad"][block == b]) for b in (0, 1)]
    target = tr["params"]["friction"]["width_rad"]
    assert 0.5 * ARCMIN <= target <= 1.5 * ARCMIN
    assert widths[0] == pytest.approx(target, rel=0.05)
    assert widths[1] == pytest.approx(widths[0], rel=0.05)  # rate-independent
    if form == "bouc_wen":
        assert tr["params"]["friction"]["n"] >= 1.5  # not the Dahl (n = 1) shape


@pytest.mark.parametrize("seed", SEEDS)
def test_damping_loop_grows_with_rate(seed):
    cols, tr = stiff({"damping"}, seed=seed)
    block = tr["clean"]["block"]
    slow, fast = (truth.loop_width_at_zero_torque(cols["torque_Nm"][block == b],
                                                  cols["angle_rad"][block == b]) for b in (0, 1))
    assert slow > 0.1 * ARCMIN
    assert fast / slow == pytest.approx(4.0, rel=0.15)  # Kelvin-Voigt: width ~ rate
    tau = tr["params"]["damping"]["tau_c"]
    expected = 2 * tau * truth.RATED_TORQUE_NM / 1.0 / tr["params"]["k1"]
    assert slow == pytest.approx(expected, rel=0.1)


@pytest.mark.parametrize("seed", SEEDS)
def test_damping_with_hardening_grows_like_the_root_of_the_tangent_stiffness(seed):
    """Constant damping ratio: on a ramp of rate Ṫ the twist lags by
    τ·sqrt(k1·K_t)·Ṫ/K_t², i.e. ∝ K_t^-1.5; a constant coefficient would give K_t^-2 and
    stiffness-proportional (Rayleigh, the library's other end) K_t^-1."""
    damped = stiff({"hardening", "damping"}, seed=seed, hardening_form="cubic")[1]
    plain = stiff({"hardening"}, seed=seed, hardening_form="cubic")[1]
    k1, k3 = damped["params"]["k1"], damped["params"]["hardening"]["k3"]
    first = leg(damped, 0, 0)  # 0 -> +T_N at the slow rate
    T = damped["clean"]["torque_Nm"][first]
    lag = plain["clean"]["twist_rad"][first] - damped["clean"]["twist_rad"][first]
    theta = plain["clean"]["twist_rad"][first]
    lags, stiffness = [], []
    for level in (0.15, 0.8):
        i = np.argmin(np.abs(T - level * truth.RATED_TORQUE_NM))
        lags.append(lag[i])
        stiffness.append(k1 + 3 * k3 * theta[i] ** 2)
    ratio = stiffness[1] / stiffness[0]
    assert ratio > 1.5  # the tangent stiffness does change
    assert lags[0] / lags[1] == pytest.approx(ratio**1.5, rel=0.05)


@pytest.mark.parametrize("seed", SEEDS)
def test_unknown_rate_loss_is_neither_friction_nor_viscous(seed):
    cols, tr = stiff({"rate_dependent_unknown"}, seed=seed)
    block = tr["clean"]["block"]
    slow, fast = (truth.loop_width_at_zero_torque(cols["torque_Nm"][block == b],
                                                  cols["angle_rad"][block == b]) for b in (0, 1))
    assert slow > 0.2 * ARCMIN
    assert 1.15 < fast / slow < 3.0  # grows with rate, but far slower than viscous (x4)


def test_all_families_together_run_and_record_their_parameters():
    fams = set(truth.STIFFNESS_FAMILIES)
    cols, tr = stiff(set(fams), seed=9, n_rows=1000)
    assert all(tr["params"][f] is not None for f in fams)
    assert np.all(np.isfinite(cols["angle_rad"]))


# --------------------------------------------------------------------------- kinematic error


def ke_harmonics(cols, tr, ratio):
    """Least-squares amplitudes [rad] of 1x, 2x, 4x WG and 1x output in the KE."""
    t = cols["time_s"]
    away = np.abs(t - tr["profile"]["t_rev"]) > 5 * tr["profile"]["reversal_s"]
    wg = cols["wg_angle_rad"][away]
    ke = cols["output_angle_rad"][away] - wg / ratio
    out = wg / ratio
    direction = np.sign(tr["profile"]["t_rev"] - t[away])
    basis = [np.ones_like(wg), direction]
    for arg in (wg, 2 * wg, 4 * wg, out):
        basis += [np.sin(arg), np.cos(arg)]
    coef, *_ = np.linalg.lstsq(np.column_stack(basis), ke, rcond=None)
    return {name: math.hypot(coef[2 + 2 * i], coef[3 + 2 * i])
            for i, name in enumerate(("1x", "2x", "4x", "out"))}


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("ratio", [100.0, -80.0])
def test_ke_harmonics_are_present_at_wave_generator_orders(seed, ratio):
    cols, tr = truth.make_ke_data({"kinematic_error"}, {"friction"}, seed=seed, ratio=ratio)
    amp = ke_harmonics(cols, tr, ratio)
    ke = tr["params"]["kinematic_error"]
    assert amp["2x"] == pytest.approx(ke["a2"], rel=0.05)
    assert amp["1x"] == pytest.approx(ke["a1"], rel=0.1)
    assert amp["out"] == pytest.approx(ke["ao"], rel=0.1)
    assert amp["2x"] > 10 * truth.ARCSEC * 0.9

    plain, plain_tr = truth.make_ke_data(set(), {"friction"}, seed=seed, ratio=ratio)
    assert max(ke_harmonics(plain, plain_tr, ratio).values()) < 0.3 * truth.ARCSEC


def test_ke_data_shape_load_and_lost_motion(tmp_path):
    cols, tr = truth.make_ke_data({"kinematic_error"}, {"backlash"}, seed=1)
    assert list(cols) == ["time_s", "wg_angle_rad", "output_angle_rad", "torque_Nm"]
    wg = tr["clean"]["wg_angle_rad"]
    forward, back = wg.max() - wg[0], wg.max() - wg[-1]
    assert forward > 2 * math.pi * 100 and back > 2 * math.pi * 100  # one output rev each way
    load = tr["params"]["load_Nm"]
    assert 0.15 * truth.RATED_TORQUE_NM <= load <= 0.35 * truth.RATED_TORQUE_NM
    # the load opposes motion: negative torque while turning forward, positive after
    assert cols["torque_Nm"][0] == pytest.approx(-load, abs=0.05)
    assert cols["torque_Nm"][-1] == pytest.approx(load, abs=0.05)
    twist = tr["clean"]["twist_rad"]
    lost = twist[-1] - twist[0]
    expected = 2 * load / tr["params"]["k1"] + tr["params"]["backlash"]["b_rad"]
    assert lost == pytest.approx(expected, rel=0.01)

    meas = load_measurement(truth.write_csv(tmp_path / "ke.csv", cols, tr["meta"]))
    np.testing.assert_allclose(meas.kinematic_error,
                               cols["output_angle_rad"] - cols["wg_angle_rad"] / 100.0)
    assert meas.ratio == 100.0


def numbers(path):
    """The numeric table of a contract CSV (after the '#' lines and the header)."""
    lines = Path(path).read_text().splitlines()
    body = [line for line in lines if not line.startswith("#")][1:]
    return np.array([[float(x) for x in line.split(",")] for line in body])


def test_example_files_match_their_generator(tmp_path):
    fresh = truth.write_examples(tmp_path)
    for path in fresh:
        if path.suffix != ".csv":
            continue
        stored = Path(__file__).parent / "data" / path.name
        assert stored.read_text().splitlines()[:4] == path.read_text().splitlines()[:4]
        # numbers may differ in the last digits between scipy/numpy versions
        a, b = numbers(stored), numbers(path)
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9)
