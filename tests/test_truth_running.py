"""The running-torque truth generator (``tests/truth_running.py``) against closed forms.

These tests need nothing from ``hdsim``: they check the generator's own promises (the
laws on plateaus, ripple out of the whole-revolution mean, inertia only in ramps, the
ranges of every draw, the file contract, reproducibility), so they hold before the
library reads running-torque tests at all.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import truth_running as tr

SEEDS = range(12)
ALL = {"friction", "damping", "ripple"}
# Noise, cogging and the temperature drift off: the torque is the law and nothing else.
CLEAN = {"noise": False, "cogging": False, "temperature": False, "quantise_angles": False}


def closed_form(omega: float, params: dict) -> float:
    """Input torque [N·m] on a plateau at WG speed ``omega`` [rad/s], written from the docstring."""
    b, fr, dm = params["base"], params["friction"], params["damping"]
    s = omega / math.sqrt(omega**2 + b["w_e"] ** 2)
    total = b["F_c"] * s
    if fr:
        x = abs(omega) / fr["w_s"]
        if fr["shape"] == "power":
            total += s * fr["E"] * math.exp(-(x ** fr["d"]))
        elif fr["shape"] == "lorentzian":
            total += s * fr["E"] / (1.0 + x * x)
        total += fr["side"] * fr["a"] * b["F_c"] * 0.5 * (1.0 + fr["side"] * s)
    if dm:
        total += dm["c"] * s * abs(omega) ** dm["p"] if dm["form"] == "power" else dm["c"] * omega
    return total


def plateau_mask(truth: dict, p: dict, whole_revs: bool = False) -> np.ndarray:
    """Samples of plateau ``p``; with ``whole_revs`` only its first whole WG revolutions."""
    t = truth["clean"]["time_s"]
    t1 = p["t1"]
    if whole_revs:
        t1 = p["t0"] + math.floor(p["revs"]) * 2.0 * math.pi / abs(p["omega"])
    return (t >= p["t0"]) & (t < t1)


# --------------------------------------------------------------------------- independence


def test_generator_does_not_import_hdsim():
    text = Path(tr.__file__).read_text()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Import):
            assert not any(a.name.split(".")[0] in ("hdsim", "truth") for a in node.names)
        if isinstance(node, ast.ImportFrom):
            assert (node.module or "").split(".")[0] not in ("hdsim", "truth")
    assert "import_module" not in text and "__import__" not in text


def test_same_seed_same_data_other_seed_other_data():
    a, ma, ta = tr.make_running_data(ALL, 5)
    b, mb, tb = tr.make_running_data(ALL, 5)
    c, _, tc = tr.make_running_data(ALL, 6)
    assert list(a) == list(b) and ma == mb
    for name in a:
        np.testing.assert_array_equal(a[name], b[name])
    assert ta["params"]["base"]["F_c"] == tb["params"]["base"]["F_c"] != tc["params"]["base"]["F_c"]


def test_family_draws_do_not_depend_on_other_families():
    _, _, alone = tr.make_running_data({"friction"}, 3)
    _, _, mixed = tr.make_running_data(ALL, 3)
    for key in ("base", "friction", "nuisance"):
        assert repr(alone["params"][key]) == repr(mixed["params"][key])
    np.testing.assert_array_equal(alone["clean"]["omega"], mixed["clean"]["omega"])


def test_unknown_family_or_override_is_refused():
    with pytest.raises(ValueError, match="unknown families"):
        tr.make_running_data({"backlash"}, 0)
    with pytest.raises(ValueError, match="unknown overrides"):
        tr.make_running_data((), 0, nosie=False)
    with pytest.raises(ValueError, match="friction form"):
        tr.make_running_data({"friction"}, 0, friction_form="gaussian")


# --------------------------------------------------------------------------- closed forms


@pytest.mark.parametrize("seed", SEEDS)
def test_plateau_torque_is_the_closed_form(seed):
    """No ripple: every plateau sample equals Coulomb + friction + damping at its speed."""
    hidden = {"friction", "damping"} if seed % 3 else set()
    _, _, truth = tr.make_running_data(hidden, seed, **CLEAN)
    total = truth["clean"]["parts"]["total"]
    for p in truth["profile"]["plateaus"]:
        m = plateau_mask(truth, p)
        assert m.sum() >= 30
        np.testing.assert_allclose(total[m], closed_form(p["omega"], truth["params"]), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("form", ["additive", "modulated"])
@pytest.mark.parametrize("seed", SEEDS)
def test_ripple_leaves_the_whole_revolution_mean(seed, form):
    """Mean over whole WG revolutions = closed form (+ the output-order term's own mean)."""
    _, _, truth = tr.make_running_data(ALL, seed, ripple_form=form, ripple_output=True, fs=2000.0, **CLEAN)
    rp, F_c = truth["params"]["ripple"], truth["params"]["base"]["F_c"]
    c = truth["clean"]
    checked = 0
    for p in truth["profile"]["plateaus"]:
        if p["revs"] < 1.0:
            continue
        m = plateau_mask(truth, p, whole_revs=True)
        phi = c["wg_angle_rad"][m]
        # the 1/N term turns by 2 pi k / N over k WG revolutions: its mean is not zero
        a = phi[0] / tr.RATIO + rp["po"]
        b = a + 2 * math.pi * math.floor(p["revs"]) * np.sign(p["omega"]) / tr.RATIO
        out_mean = rp["ao"] * (math.cos(a) - math.cos(b)) / (b - a)
        # the modulated form scales the rate-independent level (Coulomb + friction) at this speed
        level = closed_form(p["omega"], {**truth["params"], "damping": None})
        s = p["omega"] / math.hypot(p["omega"], truth["params"]["base"]["w_e"])
        expected_rip = s * out_mean if form == "additive" else level * out_mean / F_c
        # rectangle rule on whole periods: error below a few peak values over the sample count
        tol = 3.0 * np.abs(c["parts"]["ripple"][m]).max() / m.sum() + 1e-12
        assert abs(c["parts"]["ripple"][m].mean() - expected_rip) <= tol
        assert abs(c["parts"]["total"][m].mean() - closed_form(p["omega"], truth["params"]) - expected_rip) <= tol
        checked += 1
    assert checked >= 2


def test_ripple_without_output_term_has_zero_mean_and_its_peak_is_visible():
    _, _, truth = tr.make_running_data({"ripple"}, 4, ripple_output=False, fs=2000.0, **CLEAN)
    c, rp = truth["clean"], truth["params"]["ripple"]
    for p in truth["profile"]["plateaus"]:
        if p["revs"] >= 1.0:
            m = plateau_mask(truth, p, whole_revs=True)
            assert abs(c["parts"]["ripple"][m].mean()) <= 3.0 * rp["total"] * 1.5 / m.sum()
            assert np.ptp(c["parts"]["ripple"][m]) >= rp["a2"]  # the 2x bump alone spans > a2


@pytest.mark.parametrize("ramp", ["cosine", "linear"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_inertia_only_in_ramps_and_kinematics_consistent(seed, ramp):
    _, _, truth = tr.make_running_data((), seed, ramp=ramp, fs=2000.0, **CLEAN)
    c, J = truth["clean"], truth["params"]["base"]["J"]
    assert 1e-5 <= J <= 5e-5
    on_plateau = np.zeros(c["time_s"].size, bool)
    for p in truth["profile"]["plateaus"]:
        on_plateau |= plateau_mask(truth, p)
    assert np.all(c["parts"]["inertia"][on_plateau] == 0.0)
    np.testing.assert_allclose(c["parts"]["inertia"], J * c["acc"], rtol=0, atol=1e-15)
    np.testing.assert_allclose(c["parts"]["total"] - c["parts"]["coulomb"], J * c["acc"], atol=1e-15)
    dt = 1.0 / truth["profile"]["fs"]
    # the angle is the integral of the speed and the speed that of the acceleration
    np.testing.assert_allclose(np.diff(c["wg_angle_rad"]) / dt, 0.5 * (c["omega"][1:] + c["omega"][:-1]),
                               atol=5e-3 * np.abs(c["omega"]).max())
    smooth = ramp == "cosine"  # a linear ramp's acceleration steps at its corners
    d_omega = np.diff(c["omega"]) / dt
    mid_acc = 0.5 * (c["acc"][1:] + c["acc"][:-1])
    ok = np.abs(d_omega - mid_acc) <= 0.02 * np.abs(c["acc"]).max()
    assert ok.mean() >= (0.999 if smooth else 0.99)
    a_peak = np.abs(c["acc"]).max()
    assert a_peak <= 3000.0 * 1.0001 and J * a_peak > 0.0
    # starts at rest, ends within one sample of rest (the last sample falls before the end)
    assert c["omega"][0] == 0.0 and abs(c["omega"][-1]) <= 1.01 * a_peak * dt


# --------------------------------------------------------------------------- ranges


@pytest.mark.parametrize("seed", range(30))
def test_every_draw_in_its_stated_range_and_visible(seed):
    cols, meta, truth = tr.make_running_data(ALL, seed, **CLEAN)
    P, prof = truth["params"], truth["profile"]
    F_c = P["base"]["F_c"]
    assert 0.03 <= F_c <= 0.08 and len(cols["time_s"]) <= tr.MAX_ROWS
    rpm = prof["levels_rad_s"] / tr.RPM
    assert 3 <= rpm.size <= 6 and 20 <= rpm.min() <= 40 and 1500 <= rpm.max() <= 3000
    assert 200.0 <= prof["fs"] <= 2000.0
    pl = prof["plateaus"]
    assert len(pl) == 2 * rpm.size and {p["direction"] for p in pl} == {-1, 1}
    dwell = [p["t1"] - p["t0"] for p in pl]
    assert len(set(np.round(dwell, 9))) >= len(dwell) - 1  # unequal dwells
    parts = truth["clean"]["parts"]
    slow = [p for p in pl if abs(p["omega"]) == prof["levels_rad_s"].min()]
    fast = [p for p in pl if abs(p["omega"]) == prof["levels_rad_s"].max()]
    fr = P["friction"]
    excess = min(abs(parts["friction"][plateau_mask(truth, p)]).min() for p in slow)
    assert fr["form"] in tr.FRICTION_FORMS
    assert (fr["shape"] and fr["excess_at_slowest"] >= 0.3 * F_c) or 0.15 <= fr["a"] <= 0.40
    if fr["shape"] and not fr["a"]:
        assert excess >= 0.3 * F_c
    if fr["a"]:  # the asymmetric part alone: forward and reverse levels differ by a
        _, _, alone = tr.make_running_data({"friction"}, seed, friction_form="asymmetric", **CLEAN)
        part = alone["clean"]["parts"]
        level = [abs(part["total"][m]).mean() for m in (plateau_mask(alone, p) for p in fast)]
        assert max(level) / min(level) - 1.0 == pytest.approx(fr["a"], rel=1e-6)
    for p in fast:
        share = abs(parts["damping"][plateau_mask(truth, p)]).mean() / F_c
        assert 0.5 - 1e-9 <= share <= 2.0 + 1e-9
    rp = P["ripple"]
    assert 0.08 <= rp["total_frac"] <= 0.30 and rp["a2"] > max(rp["a1"], rp["a4"], rp["ao"])
    assert 0.5 <= rp["kappa"] <= 1.5
    nz = P["nuisance"]
    drawn = tr.draw_nuisance(seed, F_c, tr.DEFAULTS)
    assert 0.02 * F_c <= drawn["sigma"] <= 0.08 * F_c and 0.003 * F_c <= drawn["q"] <= 0.007 * F_c
    assert nz["cog_order"] in (12, 24) and nz["cog_a"] <= 0.03 * F_c


def test_row_limit_and_short_records():
    for seed in range(10):
        cols, _, truth = tr.make_running_data(ALL, seed, max_rows=6000)
        assert len(cols["time_s"]) <= 6000 and truth["profile"]["fs"] >= 200.0
        assert np.all(np.diff(cols["time_s"]) > 0)


# --------------------------------------------------------------------------- nuisances


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_current_noise_and_quantisation(seed):
    cols, _, truth = tr.make_running_data(ALL, seed)
    nz = truth["params"]["nuisance"]
    torque_in = cols["torque_Nm"] / truth["torque_factor"]
    err = torque_in - truth["clean"]["parts"]["total"]
    assert 0.9 <= err.std() / math.hypot(nz["sigma"], nz["q"] / math.sqrt(12)) <= 1.1
    steps = torque_in / nz["q"]
    assert np.abs(steps - np.round(steps)).max() < 1e-6
    assert 0.003 * truth["params"]["base"]["F_c"] <= nz["q"] <= 0.007 * truth["params"]["base"]["F_c"]


def test_temperature_drift_and_cogging():
    cols, _, truth = tr.make_running_data(ALL, 1, temperature=True, cogging=True)
    temp = cols["temperature_C"]
    assert abs(temp[0] - 20.0) < 0.1 and abs(temp[-1] - 30.0) < 0.1
    assert np.all(np.diff(truth["clean"]["temperature_C"]) >= 0)
    k = truth["clean"]["k_T"]
    assert 0.95 <= k.min() < 1.0 == k[0]
    cog = truth["clean"]["parts"]["cogging"]
    assert 0 < np.abs(cog).max() <= 0.03 * truth["params"]["base"]["F_c"]
    cols, _, truth = tr.make_running_data(ALL, 1, temperature=False, cogging=False)
    assert "temperature_C" not in cols and not truth["clean"]["parts"]["cogging"].any()


@pytest.mark.parametrize("layout", tr.LAYOUTS)
def test_layouts_and_torque_side(layout):
    cols, meta, truth = tr.make_running_data(ALL, 2, layout=layout, noise=False)
    assert meta["test"] == "running_torque" and meta["ratio"] == "100" and meta["rated_torque_Nm"] == "87"
    wg = truth["clean"]["wg_angle_rad"]
    nz = truth["params"]["nuisance"]
    if layout == "output":
        assert meta["torque_side"] == "output" and "wg_angle_rad" not in cols
        np.testing.assert_allclose(cols["torque_Nm"], 100.0 * truth["clean"]["parts"]["total"], rtol=1e-12)
    else:
        assert meta["torque_side"] == "input"
        np.testing.assert_allclose(cols["torque_Nm"], truth["clean"]["parts"]["total"], rtol=1e-12)
        assert np.abs(cols["wg_angle_rad"] - wg).max() <= math.pi / nz["wg_counts"] * (1 + 1e-9)
    if layout != "wg":
        step = 2 * math.pi / nz["out_counts"]
        assert np.abs(cols["output_angle_rad"] - wg / 100.0).max() <= 0.5 * step * (1 + 1e-9)
    else:
        assert "output_angle_rad" not in cols


def test_layouts_all_drawn_somewhere():
    seen = {tr.make_running_data((), s)[2]["layout"] for s in range(20)}
    assert seen == set(tr.LAYOUTS)


# --------------------------------------------------------------------------- file


def test_file_reads_back_exactly(tmp_path):
    cols, meta, _ = tr.make_running_data(ALL, 7, max_rows=3000)
    path = tr.write_csv(tmp_path / "run.csv", cols, meta)
    text = path.read_text()
    assert text.startswith("# test: running_torque\n")
    back, back_meta = tr.read_csv(path)
    assert back_meta == meta and list(back) == list(cols)
    for name in cols:
        np.testing.assert_array_equal(back[name], cols[name])
