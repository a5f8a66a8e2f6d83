"""The truth zoo (``tests/truth_zoo.py``, ``tests/truth_zoo_forms.py``) against closed forms.

Nothing here needs ``hdsim``: the generator's own promises are checked (a linear spring
is ``T/k``; a Coulomb-plus-viscous loop, a piecewise spring, a hard gap, a Kelvin–Voigt
loop and the KE harmonics match their closed forms; path-exact friction laws; the row
cap, reproducibility, the visibility rule, finite records for every form and profile).
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import truth_zoo as tz
import truth_zoo_forms as zf

QUIET = {"noise_arcsec": 0.0, "quant_bits": 0, "noise_Nm": 0.0, "drift": False, "enforce_visibility": False}


def zero_crossing_angles(T, angle, rising: bool) -> np.ndarray:
    """Angle [rad] where ``T`` crosses zero upwards (or downwards), linear between samples."""
    s = np.sign(T)
    idx = np.flatnonzero((s[:-1] < 0) & (s[1:] > 0)) if rising else np.flatnonzero((s[:-1] > 0) & (s[1:] < 0))
    w = T[idx] / (T[idx] - T[idx + 1])
    return angle[idx] + w * (angle[idx + 1] - angle[idx])


def loop_width(truth) -> float:
    c = truth["clean"]
    return float(np.mean(zero_crossing_angles(c["torque_Nm"], c["angle_rad"], False))
                 - np.mean(zero_crossing_angles(c["torque_Nm"], c["angle_rad"], True)))


# --------------------------------------------------------------------------- independence


@pytest.mark.parametrize("module", [tz, zf])
def test_no_hdsim_import(module):
    for node in ast.walk(ast.parse(Path(module.__file__).read_text())):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
            [node.module or ""] if isinstance(node, ast.ImportFrom) else []
        assert not any(n.split(".")[0] in ("hdsim", "truth", "truth_running") for n in names), names


# --------------------------------------------------------------------------- closed forms


def test_linear_spring_is_offset_plus_compliance_plus_noise():
    cols, meta, truth = tz.make_case({}, {}, "one_rate", seed=4, drift=False)
    c, m = truth["clean"], truth["measurement"]
    np.testing.assert_allclose(c["angle_rad"], c["torque_Nm"] / truth["k1"], rtol=1e-9, atol=1e-15)
    noise = cols["angle_rad"] - truth["offset_rad"] - c["torque_Nm"] / truth["k1"]
    assert abs(noise.mean()) < 4 * m["noise_eff_rad"] / math.sqrt(noise.size)
    assert noise.std() == pytest.approx(m["noise_eff_rad"], rel=0.1)
    assert np.std(cols["torque_Nm"] - c["torque_Nm"]) == pytest.approx(m["noise_Nm"], rel=0.1)
    assert meta == {"test": "stiffness", "rated_torque_Nm": "87"}


@pytest.mark.parametrize("seed", [0, 1])
def test_coulomb_viscous_loop_width(seed):
    _, _, truth = tz.make_case({"friction": "coulomb_viscous"}, {}, "one_rate", seed, **QUIET)
    p, k1, prof = truth["params"]["friction"], truth["k1"], truth["profile"]
    rate = prof["amplitude_Nm"] / prof["blocks"][0]["quarter_s"]  # [N·m/s]
    closed = 2 * p["Fc"] / k1 + 2 * p["c_v"] * rate / k1**2
    assert loop_width(truth) == pytest.approx(closed, rel=1e-6)
    assert truth["secondary"] == {"damping": "viscous part of coulomb_viscous"}


def test_kelvin_voigt_loop_widens_with_the_rate():
    _, _, truth = tz.make_case({"damping": "kelvin_voigt"}, {}, "two_rates_equal", 2, **QUIET)
    c, prof, k1 = truth["clean"], truth["profile"], truth["k1"]
    tau = truth["params"]["damping"]["tau_c"]
    split = 6 * prof["blocks"][0]["quarter_s"]  # end of the slow block [s]
    for sel, q in ((c["time_s"] < split, prof["blocks"][0]["quarter_s"]),
                   (c["time_s"] > split, prof["blocks"][1]["quarter_s"])):
        T, a = c["torque_Nm"][sel], c["angle_rad"][sel]
        width = np.mean(zero_crossing_angles(T, a, False)) - np.mean(zero_crossing_angles(T, a, True))
        assert width == pytest.approx(2 * tau * prof["amplitude_Nm"] / q / k1, rel=1e-3)


def test_piecewise_hardening_segment_slopes():
    _, _, truth = tz.make_case({"hardening": "piecewise"}, {}, "one_rate", 5, **QUIET)
    c, p = truth["clean"], truth["params"]["spring"]
    T, a = c["torque_Nm"], c["angle_rad"]
    edges = [0.0] + p["kinks_Nm"] + [truth["profile"]["amplitude_Nm"]]
    for lo, hi, k in zip(edges[:-1], edges[1:], p["slopes"]):
        sel = (T > lo + 0.2) & (T < hi - 0.2)
        assert np.polyfit(T[sel], a[sel], 1)[0] == pytest.approx(1.0 / k, rel=1e-6)
    h = 1 - brentq(lambda x: zf.Piecewise(p["k1"], p["kinks_Nm"], np.array(p["slopes"]) / p["k1"]).torque(x)
                      - tz.RATED_TORQUE_NM, 0, 1e-2) * p["k1"] / tz.RATED_TORQUE_NM
    assert 0.2 <= h <= 0.4


@pytest.mark.parametrize("form", tz.FORMS["hardening"])
def test_hardening_cuts_rated_twist_by_20_to_40_percent(form):
    spring = zf.draw_spring(form, np.random.default_rng(11), 3.1e4, 87.0)

    twist = brentq(lambda x: spring.torque(x) - 87.0, 0.0, 1e-2)
    assert 0.6 <= twist * 3.1e4 / 87.0 <= 0.8
    assert spring.tangent(twist) > spring.tangent(0.0)


def test_hard_gap_width_is_the_step_at_zero_torque():
    _, _, truth = tz.make_case({"backlash": "hard_gap"}, {}, "one_rate", 6, **QUIET)
    c, p = truth["clean"], truth["params"]["backlash"]
    T, a = c["torque_Nm"], c["angle_rad"]
    up = np.polyfit(T[T > 0.5], a[T > 0.5], 1)
    down = np.polyfit(T[T < -0.5], a[T < -0.5], 1)
    assert up[1] - down[1] == pytest.approx(p["b_rad"], rel=1e-6)
    assert up[0] == pytest.approx(1 / truth["k1"] + p["contact_compliance"], rel=1e-6)
    assert 0.3 * tz.ARCMIN <= p["b_rad"] <= 1.5 * tz.ARCMIN


def test_ke_harmonics_have_their_drawn_amplitudes():
    cols, meta, truth = tz.make_case({"kinematic_error": "plain"}, {}, "one_rate", 7, drift=False)
    assert meta["test"] == "kinematic_error" and meta["ratio"] == "100"
    wg, out, T = cols["wg_angle_rad"], cols["output_angle_rad"], cols["torque_Nm"]
    ke = out - wg / tz.RATIO  # what a reader computes: the offsets are constants
    phi = wg - truth["wg_offset_rad"]
    orders = (1, 2, 4, 3, 6, 8)
    X = [np.ones_like(phi), truth["clean"]["torque_Nm"]]
    for m in orders:
        X += [np.sin(m * phi), np.cos(m * phi)]
    X += [np.sin(phi / tz.RATIO), np.cos(phi / tz.RATIO)]
    coef, *_ = np.linalg.lstsq(np.column_stack(X), ke, rcond=None)
    amp = {m: math.hypot(coef[2 + 2 * i], coef[3 + 2 * i]) for i, m in enumerate(orders)}
    p = truth["params"]["kinematic_error"]
    for m, key in ((1, "e1"), (2, "e2"), (4, "e4")):
        assert amp[m] == pytest.approx(p[key], abs=0.03 * p["e2"])
    assert coef[1] == pytest.approx(1 / truth["k1"], rel=0.02)  # the load's windup
    assert np.all(np.abs(T) <= 9.5)


# --------------------------------------------------------------------------- laws


def test_bouc_wen_path_matches_direct_integration():
    law = zf.draw_friction("bouc_wen", np.random.default_rng(3), 3.1e4, 87.0)
    z, th = law.initial(), 0.0
    for th1, d in ((2e-4, 1), (-1e-4, -1), (5e-5, 1)):
        H, z1 = law.path(z, th, th1, 0.1, d)

        def f(s, y):  # s = |twist travelled|, dth = d ds
            return [d * (law.A - abs(y[0]) ** law.n * (law.beta * np.sign(y[0] * d) + law.gamma))]

        ref = solve_ivp(f, (0, abs(th1 - th)), [z], rtol=1e-10, atol=1e-9).y[0, -1]
        assert H == pytest.approx(ref, abs=1e-4 * law.z_u)
        z, th = z1, th1


def test_preisach_return_point_memory_and_dissipation():
    law = zf.draw_friction("preisach", np.random.default_rng(8), 3.1e4, 87.0)
    T = np.concatenate([np.linspace(0, 80, 50), np.linspace(80, 10, 30), np.linspace(10, 40, 20),
                        np.linspace(40, 20, 10), np.linspace(20, 40, 10), np.linspace(40, -80, 60)])
    slip = law.series(T)
    at40 = slip[np.flatnonzero(T == 40.0)]
    assert at40[1] == pytest.approx(at40[2], abs=1e-12)  # back at a minor loop's start: same state
    _, _, truth = tz.make_case({"friction": "preisach"}, {}, "one_rate", 8, **QUIET)
    assert loop_width(truth) > 0.3 * truth["params"]["friction"]["width_rad"]  # counter-clockwise


@pytest.mark.parametrize("form", tz.FORMS["friction"])
def test_friction_loops_are_dissipative_and_near_their_width(form):
    _, _, truth = tz.make_case({"friction": form}, {}, "one_rate", 9, max_rows=1500, **QUIET)
    W = truth["params"]["friction"]["width_rad"]
    assert 0.5 * W < loop_width(truth) < 1.6 * W


# --------------------------------------------------------------------------- records


def test_rows_cap_and_sample_rates():
    for kind in ("long_2kHz", "unbalanced_rates"):
        cols, _, truth = tz.make_case({}, {}, kind, 0)
        assert truth["profile"]["rows"] == cols["time_s"].size <= tz.MAX_ROWS
        assert truth["profile"]["fs"] == 2000.0 or kind != "long_2kHz"
    cols, _, truth = tz.make_case({}, {}, "short_low_rate_sampling", 0)
    assert np.diff(cols["time_s"]).mean() == pytest.approx(0.05)
    cols, _, _ = tz.make_case({}, {"kinematic_error": "plain"}, "long_2kHz", 0)
    assert cols["time_s"].size <= tz.MAX_ROWS
    assert tz.make_case({}, {}, "unbalanced_rates", 0, max_rows=3000)[0]["time_s"].size <= 3000


def test_reproducible_seeds_and_per_family_streams():
    a = tz.make_case({"friction": "lugre"}, {"hardening": "sinh"}, "sine", 3)
    b = tz.make_case({"friction": "lugre"}, {"hardening": "sinh"}, "sine", 3)
    for k in a[0]:
        np.testing.assert_array_equal(a[0][k], b[0][k])
    c = tz.make_case({"friction": "lugre"}, {"hardening": "sinh"}, "sine", 4)
    assert not np.array_equal(a[0]["angle_rad"], c[0]["angle_rad"])
    d = tz.make_case({"friction": "lugre"}, {}, "sine", 3)  # the same friction without hardening
    assert d[2]["params"]["friction"] == a[2]["params"]["friction"]


def test_csv_contract_round_trip(tmp_path):
    cols, meta, _ = tz.make_case({"backlash": "closing_gap"}, {}, "short_low_rate_sampling", 1)
    path = tz.write_csv(tmp_path / "x.csv", cols, meta)
    lines = path.read_text().splitlines()
    assert lines[:3] == ["# test: stiffness", "# rated_torque_Nm: 87", "time_s,torque_Nm,angle_rad"]
    back = np.array([[float(x) for x in line.split(",")] for line in lines[3:]])
    np.testing.assert_array_equal(back, np.column_stack(list(cols.values())))


def test_drift_profile_drifts():
    cols, _, truth = tz.make_case({}, {}, "drift_offset", 2)
    d = truth["clean"]["drift_rad"]
    assert d[0] == 0.0 and 0.3 * tz.ARCSEC < np.ptp(d) < 6 * tz.ARCSEC
    assert truth["measurement"]["drift"] is not None


CASES = [(fam, form) for fam, forms in tz.FORMS.items() for form in forms]


@pytest.mark.parametrize("i", range(len(CASES)))
def test_every_form_gives_a_finite_visible_record(i):
    fam, form = CASES[i]
    kind = list(tz.PROFILES)[i % len(tz.PROFILES)]
    baseline = {"friction": "bouc_wen"} if fam in ("hardening", "kinematic_error") else {"hardening": "cubic"}
    cols, meta, truth = tz.make_case({fam: form}, baseline, kind, seed=i, max_rows=2500)
    assert all(np.all(np.isfinite(v)) for v in cols.values())
    assert truth["visibility"][fam] >= tz.VISIBILITY * 0.999
    assert truth["measurement"]["noise_rad"] >= tz.NOISE_FLOOR_ARCSEC * tz.ARCSEC * 0.999
    assert (meta["test"] == "kinematic_error") == (fam == "kinematic_error")
    if form == "with_windup":
        assert "friction" in truth["baseline"]


@pytest.mark.parametrize("kind", list(tz.PROFILES))
def test_every_profile_gives_a_finite_record(kind):
    for hidden, base in (({"damping": "frequency_dependent"}, {"backlash": "asymmetric_gap"}),
                         ({"kinematic_error": "varying_load"}, {})):
        cols, _, truth = tz.make_case(hidden, base, kind, seed=1, max_rows=2500)
        assert all(np.all(np.isfinite(v)) for v in cols.values())
        assert np.all(np.diff(cols["time_s"]) > 0)
        assert 2 <= truth["profile"]["rows"] <= 2500
