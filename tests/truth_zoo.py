"""The truth zoo: bench records of a CSG-25-100 whose hidden physics is not the library's.

Test and validation support, like ``tests/truth.py`` but with several forms per family
and many profile kinds, so that ``validation/zoo_battery.py`` can measure how
``diagnose`` *generalises*. It imports nothing from ``hdsim`` (numpy/scipy only); the
laws live in ``tests/truth_zoo_forms.py``. SI units inside; ``U(a, b)`` is uniform,
``LU(a, b)`` log-uniform.

The drive and the arrangement
-----------------------------
CSG-25-100: ratio 100, rated torque ``T_N = 87 N·m``, ``k1 = 3.1e4 * U(0.85, 1.15)``
N·m/rad. The torque ``T(t)`` on the output is the input; the measured angle is::

    angle = offset + drift(t) + theta_s + gap(T) + [KE(phi) + wg/N] + noise, quantised

``theta_s`` obeys the body's torque balance ``T = F(theta_s) + H + c dtheta_s/dt + sum v_j``
(spring, parallel friction, dashpot, Maxwell arms), integrated by this package's own
implicit stepper (``truth_zoo_forms.simulate_body``: a bracketed root of the balance
at each step, friction path-exact, steps at every sample and corner and at most 2 % of
the torque swing). A series friction (Preisach) adds a slip twist driven by ``T``.

Families and forms (``FORMS``; ``size`` scales the drawn size, 1 unless raised for
visibility)
``hardening`` (spring ``F``; twist at ``T_N`` cut by ``h = U(0.20, 0.40)`` of ``T_N/k1``)
    ``cubic`` ``k1 th + k3 th^3``; ``sinh`` ``(k1/a) sinh(a th)``; ``piecewise``
    four linear segments, kinks at ``T_N * (U(.08,.2), U(.3,.5), U(.6,.8))``, stiffness
    ``k1 (1 + s c_i)``, ``c`` cumulative ``U(0.5, 1.5)`` steps; ``exponential``
    tangent stiffness ``K - (K - k1) exp(-|T|/T0)``, ``T0 = T_N U(0.15, 0.40)`` (closed-form
    compliance, saturating towards ``K``).
``backlash`` (series dead zone, total width ``b = U(0.3, 1.5) arcmin``)
    ``hard_gap`` ``(b/2) sign(T) + T c_c``, contact compliance ``c_c = U(.03,.1)/k1``;
    ``smooth_gap`` ``(b/2) T/sqrt(T^2 + T_b^2)``, ``T_b = T_N U(.001,.005)``;
    ``asymmetric_gap`` flanks ``b w`` and ``b (1-w)``, ``w = U(.25,.4)``, closing torques
    ``T_N U(.001,.004)`` and ``T_N U(.006,.015)``, extra compliance ``U(.02,.06)/k1`` on
    the negative flank; ``closing_gap`` closes over ``|T| < T_c = T_N U(.02,.06)`` along
    the odd smoothstep ``(b/2) x (3 - x^2)/2``, ``x = T/T_c``.
``friction`` (nominal zero-torque loop width ``W = U(0.5, 1.5) arcmin``, level ``Fc = W k1/2``)
    ``gen_maxwell_slip`` (Al-Bender et al. 2005) 4-8 elements, weights Dirichlet(2),
    break-away twists ``W LU(0.05, 0.6)``, Stribeck ``Fs = Fc U(1.05, 1.3)``,
    ``vs = U(5e-5, 2e-4) rad/s``, slip attraction time ``U(1, 5) ms``; ``lugre``
    ``sigma0 = k1 U(1.5, 4)``, ``sigma1 = sigma0 U(5e-5, 2e-4) s``, ``Fs = Fc U(1.1, 1.4)``,
    ``vs = U(5e-5, 2e-4) rad/s``, no viscous term; ``bouc_wen`` ``dz/dth = A - |z|^n
    (beta sign(z dth) + gamma)``, ``A = k1 U(1.5, 4)``, ``n = U(1.5, 3)``,
    ``beta/(beta+gamma) = U(.55, .9)``, saturating at ``Fc``; ``preisach`` series slip
    driven by the torque, relay density Gaussian in the interaction field
    (``sd T_N U(.03,.10)``) times log-normal in the coercive field (median
    ``T_N U(.08,.20)``, log-sd ``U(.3,.6)``): the branches run parallel, ``W`` apart,
    around zero torque and the slip moves where the torque passes the thresholds;
    ``coulomb_viscous`` ``Fc sign(v) + c_v v``, ``c_v`` giving ``U(2, 5) %`` of the loop
    width at 1 T_N/s (a small damping part is thus present: ``truth['secondary']``).
``damping`` (``tau_c = U(0.008, 0.020) s``, coefficient ``k1 tau_c`` at zero load)
    ``kelvin_voigt`` constant damping ratio ``tau_c sqrt(k1 F'(th))``;
    ``load_dependent`` ``0.6 k1 tau_c (1 + q (|T|/T_N)^p)``, ``q = U(1, 3)``,
    ``p = U(1, 2)``; ``frequency_dependent`` two Maxwell arms (standard linear solid),
    ``tau_1 = U(.01,.04) s`` and ``tau_2 = U(.1,.4) s``, low-frequency coefficients
    summing to ``k1 tau_c``, split ``U(.5,.8)`` : rest.
``kinematic_error`` (kinematic-error test; ``e1 = U(3,10)``, ``e2 = U(10,30)``,
``e4 = U(2,6)``, ``eo = U(10,30)`` arcsec at 1x, 2x, 4x WG and 1x output, plus 3x, 6x,
8x WG terms each ``U(.03,.12) e2``; random phases). The load opposes the output's
motion, ``T = -T_L w/sqrt(w^2 + w_e^2)``, so the body windup flips on reversal:
    ``plain`` ``T_L = U(3, 9) N·m``; ``with_windup`` the same with friction in the body
    (added to the baseline, form drawn, when the caller has none); ``varying_load``
    ``T_L = 6 + 3 sin(2 pi t/P + p)`` N·m, ``P = U(2, 6) s``.

Profiles (``PROFILES``; torque triangle or sine, peak ``A = T_N U(0.85, 1.0)``)
    ``two_rates_equal`` quarter cycle ``q = U(0.8, 1.25) s`` then ``q/4``, 1 cycle each,
    ``U(150, 400) Hz``; ``one_rate`` ``q = U(0.4, 1.5) s``, 1-3 cycles, ``U(100, 500) Hz``;
    ``unbalanced_rates`` 1 cycle at ``q = U(1, 2) s`` + 10 at ``q/U(4, 6)``,
    ``U(1, 2) kHz``; ``sine`` ``f1 = U(0.15, 0.3) Hz`` for 1-2 cycles then ``U(3, 5) f1``
    for 2-4, ``U(100, 400) Hz``; ``triangle_many`` ``q = U(0.3, 0.6) s`` x 3-8 cycles +
    ``q/U(2.5, 4)`` x 8-12 (<= 20 in all), ``U(100, 300) Hz``; ``short_low_rate_sampling``
    ``q = U(3, 4) s`` then ``q/4``, 1 cycle each, 20 Hz; ``long_2kHz`` ``q = U(0.6, 1) s``
    x 1 + ``q/4`` x 3, 2 kHz; ``drift_offset`` ``q``, ``q/4`` with 1 and 2 cycles,
    ``U(150, 400) Hz``, plus a drift ``+-U(0.5, 3) arcsec`` linear over the record and a
    ``U(0.3, 1.5) arcsec`` sine of period ``U(0.7, 1.5)`` record lengths. Every kind:
    angle noise ``LU(0.3, 5) arcsec``, encoder 21-23 bits, torque noise
    ``U(0.005, 0.03) N·m``, offset ``U(-pi, pi)``, rows <= 20,000 (the sample rate is
    lowered to fit; so ``unbalanced_rates`` runs at ~0.7 kHz).
    The KE test maps each kind to WG passes (forward then back; speed steps smoothed by
    tanh over 0.2 s), >= 24 samples per WG revolution, the travel cut to fit the rows:
    ``two_rates_equal`` U(1.5,3) and 3x WG rev/s, U(.3,.6) output rev; ``one_rate`` and
    ``drift_offset`` U(2,5) rev/s, U(.5,1.05) rev; ``unbalanced_rates`` one pass at
    U(2,3) rev/s + 3 at U(4,6)x, U(300,500) Hz; ``sine`` output angle
    ``X (1 - cos(2 pi t/P))/2``, ``P = U(20,60) s``, 2 cycles; ``triangle_many`` 6-10
    short passes; ``short_low_rate_sampling`` 20 Hz, U(.5,.8) rev/s; ``long_2kHz``
    2 kHz, U(10,20) rev/s.

Visibility rule
    For each hidden family the clean angle with and without it is simulated; its
    *contribution* less its least-squares fit by offset + linear compliance (what the
    base model absorbs) must have rms >= 3x the effective noise ``sqrt(sigma^2 + q^2/12)``.
    When not, the noise is lowered (to 0.3 arcsec at least), then the encoder made 24-bit,
    then the family's size raised (``x1.5`` margin, at most ``x4`` in all); the ratios
    are in ``truth['visibility']``.

Random draws: one stream per (seed, family), so a family's parameters do not depend on
the others present (data with and without a family differ only by it).
"""

from __future__ import annotations

import math

import numpy as np
from truth_files import to_csv_text, write_csv  # noqa: F401  (re-exported: one writer of the file contract)

import truth_zoo_forms as zf

RATED_TORQUE_NM = 87.0
K1_NM_PER_RAD = 3.1e4
RATIO = 100.0
MAX_ROWS = 20_000
ARCSEC, ARCMIN = zf.ARCSEC, zf.ARCMIN
VISIBILITY = 3.0  # contribution rms / effective noise
NOISE_FLOOR_ARCSEC = 0.3

FORMS = {
    "friction": ("gen_maxwell_slip", "lugre", "bouc_wen", "preisach", "coulomb_viscous"),
    "hardening": ("cubic", "sinh", "piecewise", "exponential"),
    "backlash": ("hard_gap", "smooth_gap", "asymmetric_gap", "closing_gap"),
    "damping": ("kelvin_voigt", "load_dependent", "frequency_dependent"),
    "kinematic_error": ("plain", "with_windup", "varying_load"),
}
BODY_FAMILIES = ("hardening", "backlash", "friction", "damping")
#: the forms ``tests/truth.py`` has (the diagnosis was tuned on them)
TUNING_FORMS = ("friction:bouc_wen", "hardening:cubic", "hardening:sinh", "backlash:smooth_gap",
                "damping:kelvin_voigt", "kinematic_error:plain")

PROFILES = {
    "two_rates_equal": "triangle, quarter U(0.8,1.25) s and 1/4 of it, 1 cycle each, U(150,400) Hz",
    "one_rate": "triangle, one rate, quarter U(0.4,1.5) s, 1-3 cycles, U(100,500) Hz",
    "unbalanced_rates": "triangle, 1 slow cycle (quarter U(1,2) s) + 10 fast (U(4,6)x), U(1,2) kHz",
    "sine": "sine, f1 = U(0.15,0.3) Hz for 1-2 cycles then U(3,5) f1 for 2-4 cycles, U(100,400) Hz",
    "triangle_many": "triangle, quarter U(0.3,0.6) s x 3-8 cycles + U(2.5,4)x faster x 8-12, U(100,300) Hz",
    "short_low_rate_sampling": "triangle, quarter U(3,4) s and 1/4 of it, 1 cycle each, 20 Hz",
    "long_2kHz": "triangle, quarter U(0.6,1.0) s x 1 cycle + 1/4 of it x 3, 2 kHz (<= 20,000 rows)",
    "drift_offset": "triangle, two rates (x1, x4) with 1 and 2 cycles, U(150,400) Hz, angle drift",
}

_STREAM = {"base": 1, "hardening": 2, "backlash": 3, "friction": 4, "damping": 5, "kinematic_error": 6,
           "profile": 7, "noise": 8, "load": 9, "windup": 10}
OVERRIDES = ("noise_arcsec", "quant_bits", "noise_Nm", "offset_rad", "drift", "max_rows", "fs",
             "enforce_visibility", "sizes", "amplitude_Nm", "k1")


def _rng(seed: int, stream: str) -> np.random.Generator:
    return np.random.default_rng([int(seed), _STREAM[stream]])


# --------------------------------------------------------------------------- profiles


def draw_profile(kind: str, seed: int, test: str = "stiffness") -> dict:
    """The drawn schedule of a profile kind: torque blocks (stiffness) or WG passes (KE)."""
    if kind not in PROFILES:
        raise ValueError(f"unknown profile {kind!r}; known: {', '.join(PROFILES)}")
    r = _rng(seed, "profile")
    # the measurement chain first, so it is the same draw for both tests
    p = {"kind": kind, "noise_arcsec": float(math.exp(r.uniform(math.log(0.3), math.log(5.0)))),
         "quant_bits": int(r.integers(21, 24)), "noise_Nm": r.uniform(0.005, 0.03),
         "amplitude_Nm": RATED_TORQUE_NM * r.uniform(0.85, 1.0), "drift": None}
    if kind == "drift_offset":
        p["drift"] = {"linear_arcsec": r.choice([-1, 1]) * r.uniform(0.5, 3.0),
                      "wave_arcsec": r.uniform(0.3, 1.5), "period_frac": r.uniform(0.7, 1.5),
                      "phase": r.uniform(0, 2 * math.pi)}
    if test == "kinematic_error":
        return {**p, **_ke_schedule(kind, r)}
    tri = lambda q, c: {"shape": "triangle", "quarter_s": q, "cycles": int(c)}  # noqa: E731
    if kind in ("two_rates_equal", "drift_offset"):
        q = r.uniform(0.8, 1.25)
        blocks, fs = [tri(q, 1), tri(q / 4, 1 if kind == "two_rates_equal" else 2)], r.uniform(150, 400)
    elif kind == "one_rate":
        blocks, fs = [tri(r.uniform(0.4, 1.5), r.integers(1, 4))], r.uniform(100, 500)
    elif kind == "unbalanced_rates":
        q = r.uniform(1.0, 2.0)
        blocks, fs = [tri(q, 1), tri(q / r.uniform(4, 6), 10)], r.uniform(1000, 2000)
    elif kind == "sine":
        f1 = r.uniform(0.15, 0.3)
        blocks = [{"shape": "sine", "freq_hz": f1, "cycles": int(r.integers(1, 3))},
                  {"shape": "sine", "freq_hz": f1 * r.uniform(3, 5), "cycles": int(r.integers(2, 5))}]
        fs = r.uniform(100, 400)
    elif kind == "triangle_many":
        q = r.uniform(0.3, 0.6)
        blocks, fs = [tri(q, r.integers(3, 9)), tri(q / r.uniform(2.5, 4), r.integers(8, 13))], r.uniform(100, 300)
    elif kind == "short_low_rate_sampling":
        q = r.uniform(3, 4)
        blocks, fs = [tri(q, 1), tri(q / 4, 1)], 20.0
    else:  # long_2kHz
        q = r.uniform(0.6, 1.0)
        blocks, fs = [tri(q, 1), tri(q / 4, 3)], 2000.0
    return {**p, "blocks": blocks, "fs": float(fs)}


def _ke_schedule(kind: str, r) -> dict:
    """WG passes ``(speed [WG rev/s], travel [output rev])``, each forward then back, or a sine."""
    if kind in ("two_rates_equal",):
        w = r.uniform(1.5, 3.0)
        x = r.uniform(0.3, 0.6)
        passes, fs = [(w, x), (3 * w, x)], r.uniform(200, 400)
    elif kind in ("one_rate", "drift_offset"):
        passes, fs = [(r.uniform(2, 5), r.uniform(0.5, 1.05))], r.uniform(150, 400)
    elif kind == "unbalanced_rates":  # a kHz rate would leave too few WG turns in 20,000 rows
        w = r.uniform(2, 3)
        passes = [(w, r.uniform(0.3, 0.5))] + [(w * r.uniform(4, 6), r.uniform(0.1, 0.2))] * 3
        fs = r.uniform(300, 500)
    elif kind == "sine":
        return {"sine": {"period_s": r.uniform(20, 60), "travel_rev": r.uniform(0.3, 0.6), "cycles": 2},
                "passes": [], "fs": float(r.uniform(200, 400))}
    elif kind == "triangle_many":
        w = r.uniform(2, 4)
        passes, fs = [(w, r.uniform(0.05, 0.12)) for _ in range(int(r.integers(6, 11)))], r.uniform(100, 300)
    elif kind == "short_low_rate_sampling":
        passes, fs = [(r.uniform(0.5, 0.8), r.uniform(0.25, 0.4))], 20.0
    else:  # long_2kHz
        passes, fs = [(r.uniform(10, 20), r.uniform(0.5, 0.9))], 2000.0
    return {"passes": [(float(a), float(b)) for a, b in passes], "fs": float(fs), "sine": None}


def stiffness_torque(profile: dict):
    """``(t_end, knots_t, T(t))``: corner times [s] and the torque function [N·m] of the blocks."""
    A = profile["amplitude_Nm"]
    segs, knots, t0 = [], [0.0], 0.0
    for b in profile["blocks"]:
        if b["shape"] == "triangle":
            q = b["quarter_s"]
            legs = [(A, q)] + [(-A, 2 * q), (A, 2 * q)] * b["cycles"] + [(0.0, q)]
            T0 = 0.0
            for target, dur in legs:
                segs.append(("lin", t0, t0 + dur, T0, target))
                t0, T0 = t0 + dur, target
                knots.append(t0)
        else:
            f, c = b["freq_hz"], b["cycles"]
            segs.append(("sin", t0, t0 + c / f, f, 0.0))
            knots += list(t0 + (np.arange(1, 2 * c + 1) - 0.5) / (2 * f)) + [t0 + c / f]
            t0 += c / f

    def torque(t):
        t = np.asarray(t, dtype=float)
        out = np.zeros_like(t)
        for kind, a, b, x, y in segs:
            m = (t >= a) & (t <= b)
            out[m] = (x + (y - x) * (t[m] - a) / (b - a)) if kind == "lin" \
                else A * np.sin(2 * math.pi * x * (t[m] - a))
        return out

    return t0, np.array(knots), torque


def _logcosh(x):
    x = np.abs(x)
    return x + np.log1p(np.exp(-2.0 * x)) - math.log(2.0)


def ke_motion(profile: dict, reversal_s: float = 0.2):
    """``(t_end, x(t), w(t))``: nominal output angle [rad] and speed [rad/s] of the KE schedule.

    Passes: speed steps smoothed by ``tanh((t - t_i)/reversal_s)``, integrated in closed form.
    """
    if profile["sine"]:
        s = profile["sine"]
        P, X = s["period_s"], 2 * math.pi * s["travel_rev"]
        t_end = s["cycles"] * P
        return (t_end, lambda t: 0.5 * X * (1 - np.cos(2 * math.pi * np.asarray(t) / P)),
                lambda t: X * math.pi / P * np.sin(2 * math.pi * np.asarray(t) / P))
    levels, durations = [], []
    for wg_rev_s, travel in profile["passes"]:
        w = 2 * math.pi * wg_rev_s / RATIO
        levels += [w, -w]
        durations += [2 * math.pi * travel / w] * 2
    levels.append(0.0)
    times = 3 * reversal_s + np.concatenate(([0.0], np.cumsum(durations)))
    steps = np.diff(np.concatenate(([0.0], levels)))
    t_end = times[-1] + 3 * reversal_s

    def w(t):
        t = np.asarray(t, dtype=float)[..., None]
        return (steps * 0.5 * (1 + np.tanh((t - times) / reversal_s))).sum(-1)

    def x(t):
        t = np.asarray(t, dtype=float)[..., None]
        prim = 0.5 * (t - times) + 0.5 * reversal_s * _logcosh((t - times) / reversal_s)
        prim0 = 0.5 * (0 - times) + 0.5 * reversal_s * _logcosh((0 - times) / reversal_s)
        return (steps * (prim - prim0)).sum(-1)

    return t_end, x, w


def _ke_profile_fit(profile: dict, max_rows: int) -> dict:
    """Sample rate >= 24 per WG revolution, then travel cut so that rows <= ``max_rows``."""
    p = dict(profile)
    if p["sine"]:
        s = p["sine"]
        peak_wg = s["travel_rev"] * RATIO * math.pi / s["period_s"]  # [rev/s]
        p["fs"] = max(p["fs"], 24 * peak_wg) if p["fs"] != 20.0 else p["fs"]
        dur = s["cycles"] * s["period_s"]
        if dur * p["fs"] > max_rows:
            p["sine"] = {**s, "period_s": s["period_s"] * max_rows / (dur * p["fs"])}
            p["sine"]["travel_rev"] = s["travel_rev"] * max_rows / (dur * p["fs"])
        return p
    if p["fs"] != 20.0:
        p["fs"] = max(p["fs"], 24 * max(w for w, _ in p["passes"]))
    dur = sum(2 * x * RATIO / w for w, x in p["passes"]) + 1.2
    if dur * p["fs"] > max_rows:
        cut = (max_rows / p["fs"] - 1.2) / (dur - 1.2)
        p["passes"] = [(w, x * cut) for w, x in p["passes"]]
    return p


# --------------------------------------------------------------------------- laws and cases


def _forms_present(hidden: dict, baseline: dict) -> dict:
    for name, fams in (("hidden", hidden), ("baseline", baseline)):
        for fam, form in fams.items():
            if fam not in FORMS or form not in FORMS[fam]:
                raise ValueError(f"{name}: unknown family/form {fam}:{form}; known: {FORMS}")
    both = set(hidden) & set(baseline)
    if both:
        raise ValueError(f"families both hidden and in the baseline: {sorted(both)}")
    return {**baseline, **hidden}


def _laws(present: dict, seed: int, k1: float, sizes: dict) -> dict:
    """Law objects of the body families and the KE dict, each from its own stream."""
    s = lambda f: float(sizes.get(f, 1.0))  # noqa: E731
    out = {"spring": zf.draw_spring(present.get("hardening"), _rng(seed, "hardening"), k1,
                                    RATED_TORQUE_NM, s("hardening"))}
    out["gap"] = zf.draw_gap(present["backlash"], _rng(seed, "backlash"), k1, RATED_TORQUE_NM,
                             s("backlash")) if "backlash" in present else None
    out["friction"] = zf.draw_friction(present["friction"], _rng(seed, "friction"), k1, RATED_TORQUE_NM,
                                       s("friction")) if "friction" in present else None
    out["damping"] = zf.draw_damping(present["damping"], _rng(seed, "damping"), k1, RATED_TORQUE_NM,
                                     s("damping")) if "damping" in present else None
    out["ke"] = zf.draw_ke(_rng(seed, "kinematic_error"), s("kinematic_error")) \
        if "kinematic_error" in present else None
    return out


def _step_grid(t_samples, knots, torque, swing: float):
    """Sample times and corners, subdivided so that no step moves the torque by > 2 % of ``swing``."""
    grid = np.unique(np.concatenate((t_samples, knots[(knots >= 0) & (knots <= t_samples[-1])])))
    T = torque(grid)
    n = np.maximum(1, np.ceil(np.abs(np.diff(T)) / (0.02 * swing)).astype(int))
    pieces = [grid[:1]] + [np.linspace(a, b, k + 1)[1:] for a, b, k in zip(grid[:-1], grid[1:], n)]
    fine = np.concatenate(pieces)
    return fine, torque(fine), np.searchsorted(fine, t_samples)


def _clean_angle(laws: dict, drop: str | None, steps) -> np.ndarray:
    """Clean twist [rad] of body + gap (+ KE) at the samples; ``drop`` leaves one family out."""
    t, T, idx, phi = steps
    spring = laws["spring"] if drop != "hardening" else zf.Spring(laws["spring"].k1)
    friction = laws["friction"] if drop != "friction" else None
    damping = laws["damping"] if drop != "damping" else None
    body = zf.simulate_body(spring, friction, damping, t, T)[idx]
    gap = zf.gap_angle(T[idx], laws["gap"] if drop != "backlash" else None)
    ke = zf.ke_angle(phi, RATIO, laws["ke"] if drop != "kinematic_error" else None) if phi is not None else 0.0
    return body + gap + ke


def _visible_rms(contribution, torque) -> float:
    """Rms [rad] of a contribution less its least-squares offset + linear-compliance part."""
    X = np.column_stack((np.ones_like(torque), torque))
    coef, *_ = np.linalg.lstsq(X, contribution, rcond=None)
    return float(np.sqrt(np.mean((contribution - X @ coef) ** 2)))


def make_case(hidden: dict, baseline: dict, profile: str, seed: int, **overrides):
    """One bench record with hidden and baseline families, in the file contract.

    Parameters
    ----------
    hidden, baseline : dict of str to str
        Family -> form (:data:`FORMS`). Both are in the data; ``baseline`` is what a
        diagnosis is told, ``hidden`` what it should find. A kinematic-error form makes
        the record a kinematic-error test, else it is a stiffness test.
    profile : str
        A kind of :data:`PROFILES`.
    seed : int
        Seeds every draw.
    **overrides
        ``noise_arcsec`` [arcsec] (0: none), ``quant_bits`` (0: none), ``noise_Nm`` [N·m],
        ``offset_rad`` [rad], ``drift`` (bool), ``max_rows``, ``fs`` [Hz],
        ``enforce_visibility`` (bool, default True), ``sizes`` (family -> factor),
        ``amplitude_Nm`` [N·m], ``k1`` [N·m/rad].

    Returns
    -------
    columns : dict of str to numpy.ndarray
        Stiffness: ``time_s``, ``torque_Nm``, ``angle_rad``; KE: ``time_s``,
        ``wg_angle_rad``, ``output_angle_rad``, ``torque_Nm``.
    meta : dict of str to str
        The ``#`` keys.
    truth : dict
        ``test``, ``seed``, ``profile`` (the drawn schedule, ``rows``, ``duration_s``),
        ``hidden``, ``baseline`` (the effective one: ``with_windup`` may add friction),
        ``params`` (per family), ``k1``, ``offset_rad``, ``measurement`` (``noise_rad``,
        ``quant_rad``, ``noise_Nm``, ``drift``), ``visibility`` (family -> ratio),
        ``sizes``, ``secondary`` (families present as a minor part of a form) and ``clean``
        (``time_s``, ``torque_Nm``, ``angle_rad`` without offset, drift and noise,
        ``drift_rad``, and for KE ``wg_angle_rad``, ``ke_rad``).
    """
    unknown = set(overrides) - set(OVERRIDES)
    if unknown:
        raise ValueError(f"unknown overrides {sorted(unknown)}; known: {', '.join(OVERRIDES)}")
    hidden, baseline = dict(hidden), dict(baseline)
    present = _forms_present(hidden, baseline)
    ke_form = present.get("kinematic_error")
    test = "kinematic_error" if ke_form else "stiffness"
    if ke_form == "with_windup" and "friction" not in present:
        baseline["friction"] = FORMS["friction"][int(_rng(seed, "windup").integers(len(FORMS["friction"])))]
        present = {**baseline, **hidden}
    base = _rng(seed, "base")
    k1 = float(overrides.get("k1", K1_NM_PER_RAD * base.uniform(0.85, 1.15)))
    offset = float(overrides.get("offset_rad", base.uniform(-math.pi, math.pi)))
    wg_offset = base.uniform(-math.pi, math.pi)
    prof = draw_profile(profile, seed, test)
    for key in ("noise_arcsec", "quant_bits", "noise_Nm", "amplitude_Nm", "fs"):
        if key in overrides:
            prof[key] = overrides[key]
    if overrides.get("drift") is False:
        prof["drift"] = None
    elif overrides.get("drift") is True and prof["drift"] is None:
        prof["drift"] = {"linear_arcsec": 1.5, "wave_arcsec": 0.8, "period_frac": 1.0, "phase": 0.0}
    max_rows = int(overrides.get("max_rows", MAX_ROWS))

    load = None
    if test == "stiffness":
        t_end, knots, torque = stiffness_torque(prof)
        prof["fs"] = min(prof["fs"], (max_rows - 1) / t_end)
        t = np.arange(int(math.floor(t_end * prof["fs"])) + 1) / prof["fs"]
        swing, phi_fn = 2 * prof["amplitude_Nm"], None
    else:
        prof = _ke_profile_fit(prof, max_rows)
        t_end, x_fn, w_fn = ke_motion(prof)
        t = np.arange(int(math.floor(t_end * prof["fs"])) + 1) / prof["fs"]
        lr = _rng(seed, "load")
        if ke_form == "varying_load":
            load = {"mean_Nm": 6.0, "amp_Nm": 3.0, "period_s": lr.uniform(2, 6), "phase": lr.uniform(0, 2 * math.pi)}
        else:
            load = {"mean_Nm": lr.uniform(3, 9), "amp_Nm": 0.0, "period_s": 1.0, "phase": 0.0}
        if prof["sine"]:  # the peak output speed [rad/s]
            w_ref = 2 * math.pi * prof["sine"]["travel_rev"] * math.pi / prof["sine"]["period_s"]
        else:
            w_ref = min(2 * math.pi * w / RATIO for w, _ in prof["passes"])
        w_e = 0.05 * w_ref  # the load torque flips over ~5 % of the speed

        def torque(tt):
            tt = np.asarray(tt, dtype=float)
            TL = load["mean_Nm"] + load["amp_Nm"] * np.sin(2 * math.pi * tt / load["period_s"] + load["phase"])
            w = w_fn(tt)
            return -TL * w / np.sqrt(w * w + w_e * w_e)  # the load opposes the motion

        knots = np.linspace(0.0, t_end, 50)
        swing, phi_fn = 2 * (load["mean_Nm"] + load["amp_Nm"]), lambda tt: RATIO * x_fn(tt)
    if len(t) > max_rows:
        t = t[:max_rows]
    fine, T_fine, idx = _step_grid(t, knots, torque, swing)
    T_true = T_fine[idx]
    phi = phi_fn(t) if phi_fn else None
    steps = (fine, T_fine, idx, phi)

    sizes = {f: 1.0 for f in present}
    sizes.update(overrides.get("sizes", {}))
    q = 2 * math.pi / 2 ** prof["quant_bits"] if prof["quant_bits"] else 0.0
    sigma = prof["noise_arcsec"] * ARCSEC
    enforce = overrides.get("enforce_visibility", True)
    for _attempt in range(5):
        laws = _laws(present, seed, k1, sizes)
        clean = _clean_angle(laws, None, steps)
        visible = {f: _visible_rms(clean - _clean_angle(laws, f, steps), T_true) for f in hidden}
        need = min(visible.values(), default=np.inf) / VISIBILITY
        eff = lambda s: math.sqrt(s * s + q * q / 12.0)  # noqa: E731
        if not enforce or eff(sigma) <= need:
            break
        sigma = max(math.sqrt(max(need**2 - q * q / 12.0, 0.0)), NOISE_FLOOR_ARCSEC * ARCSEC)
        if eff(sigma) > need and q > 2 * math.pi / 2**24:
            prof["quant_bits"], q = 24, 2 * math.pi / 2**24
        if eff(sigma) <= need:
            break
        for f, rms in visible.items():  # still hidden in the noise: make the family bigger
            if rms < VISIBILITY * eff(sigma):
                sizes[f] = min(sizes[f] * 1.5 * VISIBILITY * eff(sigma) / max(rms, 1e-12), 4.0)
    noise_eff = math.sqrt(sigma * sigma + q * q / 12.0)
    visibility = {f: (v / noise_eff if noise_eff > 0 else math.inf) for f, v in visible.items()}

    duration = float(t[-1])
    drift = np.zeros_like(t)
    if prof["drift"]:
        d = prof["drift"]
        P = d["period_frac"] * duration
        drift = ARCSEC * (d["linear_arcsec"] * t / duration
                          + d["wave_arcsec"] * (np.sin(2 * math.pi * t / P + d["phase"]) - math.sin(d["phase"])))
    rng = _rng(seed, "noise")
    angle = offset + drift + clean + (phi / RATIO if phi is not None else 0.0)
    angle = angle + (rng.normal(0.0, sigma, t.shape) if sigma > 0 else 0.0)
    if q:
        angle = np.round(angle / q) * q
    T_meas = T_true + (rng.normal(0.0, prof["noise_Nm"], t.shape) if prof["noise_Nm"] > 0 else 0.0)
    if test == "stiffness":
        cols = {"time_s": t, "torque_Nm": T_meas, "angle_rad": angle}
        meta = {"test": "stiffness", "rated_torque_Nm": "87"}
    else:
        wg_q = 2 * math.pi / 2**17  # a motor encoder
        wg = np.round((phi + wg_offset) / wg_q) * wg_q
        cols = {"time_s": t, "wg_angle_rad": wg, "output_angle_rad": angle, "torque_Nm": T_meas}
        meta = {"test": "kinematic_error", "ratio": "100", "rated_torque_Nm": "87"}
    params = {"spring": laws["spring"].params(), "backlash": laws["gap"],
              "friction": laws["friction"].params() if laws["friction"] else None,
              "damping": laws["damping"].params() if laws["damping"] else None,
              "kinematic_error": laws["ke"], "load": load}
    if laws["friction"] is not None:
        params["friction"]["width_rad"] = laws["friction"].width_rad
    secondary = {"damping": "viscous part of coulomb_viscous"} \
        if present.get("friction") == "coulomb_viscous" and "damping" not in present else {}
    truth = {
        "test": test, "seed": int(seed), "profile": {**prof, "rows": int(t.size), "duration_s": duration},
        "hidden": hidden, "baseline": baseline, "families": sorted(present), "params": params,
        "k1": k1, "offset_rad": offset, "wg_offset_rad": wg_offset if test != "stiffness" else None,
        "measurement": {"noise_rad": sigma, "quant_rad": q, "noise_Nm": prof["noise_Nm"],
                        "noise_eff_rad": noise_eff, "drift": prof["drift"]},
        "visibility": visibility, "sizes": {f: sizes[f] for f in hidden}, "secondary": secondary,
        "clean": {"time_s": t, "torque_Nm": T_true, "angle_rad": clean, "drift_rad": drift,
                  "wg_angle_rad": phi, "ke_rad": zf.ke_angle(phi, RATIO, laws["ke"]) if phi is not None else None},
    }
    return cols, meta, truth


# --------------------------------------------------------------------------- files


