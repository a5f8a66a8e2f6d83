"""Independent "truth" generator of running-torque tests (friction sweeps) with hidden effects.

Test support, like ``tests/truth.py`` but for the running-torque test, and on purpose
sharing neither code nor functional forms with ``hdsim`` (nor with ``tests/truth.py``):
the data must make a diagnosis *discover* an effect, not recognise its own law.

The test: a CSG-25-100 (ratio N = 100, rated torque 87 N·m; catalog no-load running
torque ~0.195 N·m on the input at 2000 rpm, starting torque ~0.069 N·m, +20 °C) is
turned by its motor at constant wave-generator (WG) speeds, each level forward and
reverse, output free; the torque comes from the motor current. The WG speed ``w(t)``
[rad/s] is prescribed, the WG angle ``phi`` is its closed-form integral, and the torque
is the law below evaluated along it (no ODE).

Input-side running torque (SI; ``s(w) = w / sqrt(w**2 + w_e**2)`` is the smooth sign,
an algebraic one, ``w_e = U(0.01, 0.05)`` rad/s; ``k(t)`` the temperature factor)::

    T_in = F_c k(t) s(w) + J dw/dt + friction + damping + ripple + cogging

``base`` (always)
    Coulomb level ``F_c = U(0.03, 0.08)`` N·m and motor + WG inertia
    ``J = U(1e-5, 5e-5)`` kg·m²; ``J dw/dt`` is zero on plateaus and shows in the ramps.
``friction`` (rate-independent / low-speed; ``form`` drawn, at least one part)
    ``power``: ``s(w) E exp(-(|w|/w_s)**d)``, ``d = U(0.5, 1.5)`` (never the Gaussian 2);
    ``lorentzian``: ``s(w) E / (1 + (w/w_s)**2)``; either with or without, or only,
    ``asymmetric``: ``side a F_c k(t) (1 + side s(w)) / 2`` (the level of direction
    ``side = ±1`` is ``(1 + a)`` times the other, ``a = U(0.15, 0.40)``). Forms drawn
    among ``power``, ``lorentzian``, ``asymmetric``, ``power+asymmetric``,
    ``lorentzian+asymmetric``. ``E = U(0.8, 1.6) F_c`` (excess at standstill) and ``w_s``
    puts the excess at the slowest plateau at ``q E``, ``q = U(0.4, 0.8)``: always
    >= 0.32 F_c there.
``damping`` (speed-proportional loss; form drawn)
    ``viscous``: ``b w``; ``power`` (churning): ``c s(w) |w|**p``, ``p = U(0.8, 1.2)``.
    Sized so that at the fastest plateau it is ``U(0.5, 2.0) F_c``.
``ripple`` (position-periodic; ``g(phi)`` [N·m], zero mean over a WG revolution except
its output-order term)::

    g = a1 sin(phi + p1) + a2 vm(2 (phi - p2); kappa) + a4 sin(4 phi + p4)
        + ao sin(phi / N + po)

    vm(x; kappa) = (exp(kappa cos x) - I0(kappa)) / (2 I1(kappa))

    The 2x term is a von-Mises bump (first harmonic amplitude 1, plus 4x, 6x ...
    content), ``kappa = U(0.5, 1.5)``; the 4x and output-order (1/N) terms are each
    present with probability 1/2; random phases. Total ``a1 + a2 + a4 + ao =
    U(0.08, 0.30) F_c`` shared by weights 2x ``U(0.45, 0.7)``, 1x ``U(0.1, 0.3)``, 4x and
    1/N ``U(0.05, 0.2)`` each (2x always the largest). Forms (drawn 50/50):
    ``additive``: ``s(w) g(phi)`` (dissipative, fixed amplitude); ``modulated``: the
    rate-independent level (``F_c k(t) s(w)`` plus the friction family) times
    ``1 + g(phi)/F_c``. On request only (``ripple_form='conservative'``): ``g(phi)`` with
    no sign, a position torque that does not reverse with direction (see
    :func:`make_running_data`).

Nuisances (not a family; always on unless switched off by an override)
    Current noise white Gaussian ``sigma = U(0.02, 0.08) F_c``, then current quantisation
    to steps of ``U(0.003, 0.007) F_c``; motor cogging ``ac sin(n phi + pc)``, ``n`` 12 or
    24, ``ac = U(0.005, 0.03) F_c``, in half the seeds (conservative: same sign both
    ways); WG encoder ``2**13 .. 2**16`` counts/rev, output encoder ``2**17 .. 2**20``;
    in half the seeds a temperature drift 20 -> 30 °C (saturating exponential over the
    record, column ``temperature_C`` with 0.02 °C noise, 0.01 °C resolution) with
    ``k(t) = 1 - drop (T - 20)/10``, ``drop = U(0.02, 0.05)``.

Profile
    3-6 levels log-spaced from ``U(20, 40)`` to ``U(1500, 3000)`` rpm (interior levels
    jittered x U(0.9, 1.1)), run in ascending, descending or shuffled order, each forward
    and reverse (first direction drawn), starting and ending at rest. Dwell per plateau
    ``max(n_rev * 2 pi/|w|, t_min)``, ``n_rev = U(0.5, 4)`` and ``t_min = U(0.15, 0.5)``
    s drawn per plateau (so fast plateaus turn many revolutions); ramps ``cosine`` or ``linear`` (drawn) with peak
    acceleration ``U(500, 3000)`` rad/s² (at least 0.05 s). Sample rate ``U(200, 2000)``
    Hz, lowered (and dwells shortened) so that rows <= ``max_rows`` (25,000).

File layouts (drawn): ``wg+output`` (p 1/2) and ``wg`` (1/4) name ``torque_side:
input``; ``output`` (1/4) gives only ``output_angle_rad`` and ``torque_side: output``
with ``torque_Nm = N T_in``: the input running torque referred to the output through
the ideal ratio (no efficiency), signed like the output speed, which has the sign of
the WG speed (``output_angle = wg_angle / N``). Column order is shuffled.

Random draws use one stream per family (and for profile, nuisances, noise), seeded by
``(seed, stream)``: a family's parameters for a seed do not depend on the other
families present. The friction's ``w_s`` and the damping's size depend on the profile,
which depends on the seed only.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from truth_files import to_csv_text, write_csv  # noqa: F401  (re-exported: one writer of the file contract)
from scipy.special import i0, i1

FAMILIES = ("friction", "damping", "ripple")
RATIO = 100.0
RATED_TORQUE_NM = 87.0
CATALOG_RUNNING_NM = 0.195  # [N·m] input, no load, 2000 rpm, +20 °C
CATALOG_STARTING_NM = 0.069  # [N·m] input
RPM = 2.0 * math.pi / 60.0  # [rad/s per rpm]
MAX_ROWS = 25_000
FRICTION_FORMS = ("power", "lorentzian", "asymmetric", "power+asymmetric", "lorentzian+asymmetric")
LAYOUTS = ("wg+output", "wg", "output")

_STREAM = {"base": 1, "profile": 2, "friction": 3, "damping": 4, "ripple": 5, "nuisance": 6,
           "noise": 7}

#: Overrides of :func:`make_running_data`; None means "drawn".
DEFAULTS = {
    "noise": True,  # current noise and current quantisation
    "quantise_angles": True,
    "cogging": None,  # bool
    "temperature": None,  # bool: drift and temperature_C column
    "layout": None,  # one of LAYOUTS
    "friction_form": None,  # one of FRICTION_FORMS
    "damping_form": None,  # 'viscous' or 'power'
    "ripple_form": None,  # 'additive', 'modulated' or 'conservative'
    "ripple_4x": None,  # bool
    "ripple_output": None,  # bool: the 1/N (output-order) term
    "inertia": None,  # J [kg·m²]
    "n_levels": None,
    "speeds_rpm": None,  # explicit levels, in run order
    "order": None,  # 'ascending', 'descending', 'shuffled'
    "ramp": None,  # 'cosine' or 'linear'
    "fs": None,  # [Hz] before the row limit
    "max_rows": MAX_ROWS,
    "shuffle_columns": True,
}


def _rng(seed: int, stream: str) -> np.random.Generator:
    """One independent stream per (seed, stream) so adding a family shifts no draw."""
    return np.random.default_rng([int(seed), _STREAM[stream]])


def smooth_sign(w, w_e: float):
    """Algebraic smooth sign ``w / sqrt(w² + w_e²)`` of a speed ``w`` [rad/s]."""
    w = np.asarray(w, dtype=float)
    return w / np.sqrt(w * w + w_e * w_e)


def von_mises_bump(x, kappa: float):
    """Zero-mean periodic bump ``(exp(kappa cos x) - I0) / (2 I1)``; 1st harmonic amplitude 1."""
    return (np.exp(kappa * np.cos(x)) - i0(kappa)) / (2.0 * i1(kappa))


# --------------------------------------------------------------------------- draws


def draw_base(seed: int) -> dict:
    """Coulomb level ``F_c`` [N·m], inertia ``J`` [kg·m²], sign width ``w_e`` [rad/s]."""
    rng = _rng(seed, "base")
    return {"F_c": rng.uniform(0.03, 0.08), "J": rng.uniform(1e-5, 5e-5),
            "w_e": rng.uniform(0.01, 0.05), "wg_start_rad": rng.uniform(-math.pi, math.pi)}


def draw_profile(seed: int, ov: dict) -> dict:
    """Speed levels [rad/s] in run order, dwells [s], ramp shape, acceleration, rate."""
    rng = _rng(seed, "profile")
    n = int(rng.integers(3, 7))
    lo, hi = rng.uniform(20.0, 40.0), rng.uniform(1500.0, 3000.0)
    order = str(rng.choice(["ascending", "descending", "shuffled"]))
    first = float(rng.choice([1.0, -1.0]))
    ramp = str(rng.choice(["cosine", "linear"]))
    a_max = rng.uniform(500.0, 3000.0)
    t_min = rng.uniform(0.15, 0.5, size=(6, 2))  # floor of each dwell [s]
    fs = rng.uniform(200.0, 2000.0)
    n_rev = rng.uniform(0.5, 4.0, size=(6, 2))  # per level and direction (drawn for 6)
    jitter = rng.uniform(0.9, 1.1, size=6)
    perm = rng.permutation(6)
    if ov["speeds_rpm"] is not None:
        rpm = np.abs(np.asarray(ov["speeds_rpm"], dtype=float))
        order = "given"
    else:
        n = int(ov["n_levels"] or n)
        rpm = np.geomspace(lo, hi, n)
        rpm[1:-1] *= jitter[1:n - 1]
        order = ov["order"] or order
        if order == "descending":
            rpm = rpm[::-1]
        elif order == "shuffled":
            rpm = rpm[np.argsort(perm[:n])]
        elif order != "ascending":
            raise ValueError(f"unknown order {order!r}")
    n = len(rpm)
    if not 1 <= n <= 6:
        raise ValueError(f"1 to 6 speed levels, got {n}")
    levels = rpm * RPM
    dwell = np.maximum(n_rev[:n] * 2.0 * math.pi / levels[:, None], t_min[:n])
    return {"levels_rad_s": levels, "order": order, "first_direction": first,
            "ramp": ov["ramp"] or ramp, "a_max": a_max, "t_min": t_min[:n], "n_rev": n_rev[:n],
            "dwell_s": dwell, "fs_drawn": float(ov["fs"] or fs)}


def draw_friction(seed: int, w_min: float, F_c: float, form: str | None = None) -> dict:
    """Low-speed friction: Stribeck excess of power or Lorentzian shape and/or asymmetry.

    ``E`` [N·m] excess at standstill, ``w_s`` [rad/s], ``d`` exponent (power form),
    ``a`` level ratio - 1 and ``side`` (+1 forward stronger) for the asymmetric part.
    ``excess_at_slowest`` [N·m] is the Stribeck excess at ``w_min`` [rad/s].
    """
    rng = _rng(seed, "friction")
    drawn = str(rng.choice(FRICTION_FORMS))
    form = form or drawn
    if form not in FRICTION_FORMS:
        raise ValueError(f"unknown friction form {form!r}; use one of {FRICTION_FORMS}")
    E, q, d = F_c * rng.uniform(0.8, 1.6), rng.uniform(0.4, 0.8), rng.uniform(0.5, 1.5)
    a, side = rng.uniform(0.15, 0.40), float(rng.choice([1.0, -1.0]))
    out = {"form": form, "shape": form.split("+")[0] if form != "asymmetric" else None,
           "E": 0.0, "w_s": 1.0, "d": None, "a": 0.0, "side": side, "excess_at_slowest": 0.0}
    if out["shape"] == "power":
        x = (-math.log(q)) ** (1.0 / d)  # exp(-x**d) = q at the slowest plateau
        out.update(E=E, d=d, w_s=w_min / x, excess_at_slowest=q * E)
    elif out["shape"] == "lorentzian":
        x = math.sqrt(1.0 / q - 1.0)  # 1/(1+x**2) = q
        out.update(E=E, w_s=w_min / x, excess_at_slowest=q * E)
    if "asymmetric" in form:
        out["a"] = a
    return out


def draw_damping(seed: int, w_max: float, F_c: float, form: str | None = None) -> dict:
    """Viscous ``b`` [N·m·s/rad] or power law ``c`` [N·m·(s/rad)^p], ``p``; sized at ``w_max``."""
    rng = _rng(seed, "damping")
    drawn = str(rng.choice(["viscous", "power"]))
    share, p = rng.uniform(0.5, 2.0), rng.uniform(0.8, 1.2)
    form = form or drawn
    if form == "viscous":
        return {"form": form, "p": 1.0, "c": share * F_c / w_max, "share_at_fastest": share}
    if form == "power":
        return {"form": form, "p": p, "c": share * F_c / w_max**p, "share_at_fastest": share}
    raise ValueError(f"unknown damping form {form!r}; use 'viscous' or 'power'")


def draw_ripple(seed: int, F_c: float, ov: dict) -> dict:
    """Amplitudes ``a1, a2, a4, ao`` [N·m], phases [rad], ``kappa``, form, total/F_c."""
    rng = _rng(seed, "ripple")
    total = rng.uniform(0.08, 0.30) * F_c
    w = {"a1": rng.uniform(0.1, 0.3), "a2": rng.uniform(0.45, 0.7),
         "a4": rng.uniform(0.05, 0.2), "ao": rng.uniform(0.05, 0.2)}
    has4, has_o = rng.random() < 0.5, rng.random() < 0.5
    form = str(rng.choice(["additive", "modulated"]))
    phases = {k: rng.uniform(0.0, 2.0 * math.pi) for k in ("p1", "p2", "p4", "po")}
    kappa = rng.uniform(0.5, 1.5)
    has4 = has4 if ov["ripple_4x"] is None else bool(ov["ripple_4x"])
    has_o = has_o if ov["ripple_output"] is None else bool(ov["ripple_output"])
    w["a4"] *= has4
    w["ao"] *= has_o
    norm = sum(w.values())
    form = ov["ripple_form"] or form
    if form not in ("additive", "modulated", "conservative"):
        raise ValueError(f"unknown ripple form {form!r}")
    return {"form": form, "total": total, "total_frac": total / F_c, "kappa": kappa,
            **{k: total * v / norm for k, v in w.items()}, **phases}


def draw_nuisance(seed: int, F_c: float, ov: dict) -> dict:
    """Noise, quantisation, cogging, temperature drift and file layout."""
    rng = _rng(seed, "nuisance")
    d = {"sigma": rng.uniform(0.02, 0.08) * F_c, "q": rng.uniform(0.003, 0.007) * F_c,
         "cog_on": rng.random() < 0.5, "cog_order": int(rng.choice([12, 24])),
         "cog_a": rng.uniform(0.005, 0.03) * F_c, "cog_p": rng.uniform(0.0, 2.0 * math.pi),
         "temp_on": rng.random() < 0.5, "drop": rng.uniform(0.02, 0.05),
         "tau_frac": rng.uniform(0.5, 2.0),
         "wg_counts": 2 ** int(rng.integers(13, 17)), "out_counts": 2 ** int(rng.integers(17, 21)),
         "layout": str(rng.choice(LAYOUTS, p=[0.5, 0.25, 0.25])),
         "column_order": rng.permutation(5)}
    if ov["cogging"] is not None:
        d["cog_on"] = bool(ov["cogging"])
    if ov["temperature"] is not None:
        d["temp_on"] = bool(ov["temperature"])
    d["layout"] = ov["layout"] or d["layout"]
    if d["layout"] not in LAYOUTS:
        raise ValueError(f"unknown layout {d['layout']!r}; use one of {LAYOUTS}")
    if not ov["noise"]:
        d["sigma"], d["q"] = 0.0, 0.0
    return d


# --------------------------------------------------------------------------- profile


def build_segments(profile: dict, max_rows: int) -> tuple[list, list, float, float]:
    """Segments ``(kind, t0, T, w0, w1)``, plateaus, duration [s] and sample rate [Hz].

    Dwells are shortened (all by one factor) when even 200 Hz would exceed ``max_rows``.
    """
    speeds = []
    for lvl in profile["levels_rad_s"]:
        speeds += [profile["first_direction"] * lvl, -profile["first_direction"] * lvl]
    dwell = profile["dwell_s"].ravel()
    stops = [0.0] + speeds + [0.0]
    factor = (math.pi / 2.0) if profile["ramp"] == "cosine" else 1.0  # peak/mean acceleration
    ramps = [max(0.05, factor * abs(b - a) / profile["a_max"]) for a, b in zip(stops[:-1], stops[1:])]
    budget = (max_rows - 1) / 200.0 - sum(ramps)
    if budget <= 0:
        raise ValueError(f"max_rows={max_rows} leaves no time for plateaus at 200 Hz")
    dwell = dwell * min(1.0, budget / dwell.sum())
    segments, plateaus, t = [], [], 0.0
    for i, w in enumerate(speeds):
        segments.append(("ramp", t, ramps[i], stops[i], w))
        t += ramps[i]
        plateaus.append({"t0": t, "t1": t + dwell[i], "omega": w, "level": i // 2,
                         "direction": int(np.sign(w)), "revs": dwell[i] * abs(w) / (2 * math.pi)})
        segments.append(("plateau", t, dwell[i], w, w))
        t += dwell[i]
    segments.append(("ramp", t, ramps[-1], speeds[-1], 0.0))
    t += ramps[-1]
    fs = min(profile["fs_drawn"], (max_rows - 1) / t)
    return segments, plateaus, t, fs


def kinematics(t: np.ndarray, segments: list, shape: str, phi0: float):
    """WG speed [rad/s], acceleration [rad/s²] and angle [rad] at times ``t`` [s] (closed form)."""
    starts = np.array([s[1] for s in segments])
    idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(segments) - 1)
    w, acc, dphi = (np.zeros_like(t) for _ in range(3))
    phi_at = [phi0]  # angle at each segment start
    for k, (kind, t0, T, w0, w1) in enumerate(segments):
        m = idx == k
        for tau, out in ((t[m] - t0, m), (np.array([T]), None)):
            dw = w1 - w0
            if kind == "plateau" or dw == 0.0:
                ww, aa, pp = w0 + 0 * tau, 0 * tau, w0 * tau
            elif shape == "cosine":
                x = math.pi * tau / T
                ww = w0 + 0.5 * dw * (1.0 - np.cos(x))
                aa = 0.5 * dw * math.pi / T * np.sin(x)
                pp = w0 * tau + 0.5 * dw * (tau - T / math.pi * np.sin(x))
            elif shape == "linear":
                ww, aa, pp = w0 + dw * tau / T, dw / T + 0 * tau, w0 * tau + 0.5 * dw * tau**2 / T
            else:
                raise ValueError(f"unknown ramp {shape!r}; use 'cosine' or 'linear'")
            if out is None:
                phi_at.append(phi_at[-1] + float(pp[0]))
            else:
                w[m], acc[m], dphi[m] = ww, aa, pp
    phi = np.array(phi_at[:-1])[idx] + dphi
    return w, acc, phi


# --------------------------------------------------------------------------- law


def ripple_shape(phi, rip: dict, ratio: float = RATIO):
    """Position-periodic ripple ``g(phi)`` [N·m] at WG angle ``phi`` [rad]."""
    phi = np.asarray(phi, dtype=float)
    return (rip["a1"] * np.sin(phi + rip["p1"]) + rip["a2"] * von_mises_bump(2.0 * (phi - rip["p2"]), rip["kappa"])
            + rip["a4"] * np.sin(4.0 * phi + rip["p4"]) + rip["ao"] * np.sin(phi / ratio + rip["po"]))


def running_torque(w, acc, phi, k_T, params: dict, ratio: float = RATIO) -> dict:
    """Input-side running torque [N·m] and its parts, from speed, acceleration, angle.

    ``k_T`` is the temperature factor of the Coulomb level (1 without drift). Returns
    ``coulomb``, ``inertia``, ``friction``, ``damping``, ``ripple``, ``cogging`` and
    ``total`` arrays.
    """
    b = params["base"]
    s = smooth_sign(w, b["w_e"])
    parts = {"coulomb": b["F_c"] * k_T * s, "inertia": b["J"] * acc}
    zero = 0.0 * s
    fr = params["friction"]
    fric = zero
    if fr:
        x = np.abs(w) / fr["w_s"]
        if fr["shape"] == "power":
            fric = s * fr["E"] * np.exp(-x ** fr["d"])
        elif fr["shape"] == "lorentzian":
            fric = s * fr["E"] / (1.0 + x * x)
        if fr["a"]:
            fric = fric + fr["side"] * fr["a"] * b["F_c"] * k_T * 0.5 * (1.0 + fr["side"] * s)
    parts["friction"] = fric
    dm = params["damping"]
    parts["damping"] = zero if not dm else (
        dm["c"] * w if dm["form"] == "viscous" else dm["c"] * s * np.abs(w) ** dm["p"])
    rp = params["ripple"]
    if not rp:
        parts["ripple"] = zero
    else:
        g = ripple_shape(phi, rp, ratio)
        parts["ripple"] = {"additive": s * g, "conservative": g,
                           "modulated": (parts["coulomb"] + fric) * g / b["F_c"]}[rp["form"]]
    nz = params["nuisance"]
    parts["cogging"] = nz["cog_a"] * np.sin(nz["cog_order"] * phi + nz["cog_p"]) if nz["cog_on"] else zero
    parts["total"] = sum(parts.values())
    return parts


# --------------------------------------------------------------------------- generator


def make_running_data(hidden=(), seed: int = 0, **overrides) -> tuple[dict, dict, dict]:
    """Bench-like running-torque test (friction sweep) of a CSG-25-100 with hidden families.

    Parameters
    ----------
    hidden : iterable of str
        Families present beyond the base, any of :data:`FAMILIES`.
    seed : int
        Seeds every draw (parameters, profile, nuisances, noise).
    **overrides
        Keys of :data:`DEFAULTS`: ``noise`` (False: no current noise, no quantisation),
        ``quantise_angles``, ``cogging``, ``temperature``, ``layout``,
        ``friction_form``, ``damping_form``, ``ripple_form`` (incl. the on-request
        ``'conservative'``: a position torque that does not reverse with direction,
        which a model whose ripple flips sign with speed cannot fit), ``ripple_4x``,
        ``ripple_output``, ``inertia`` [kg·m²], ``n_levels``, ``speeds_rpm`` (levels in
        run order [rpm]), ``order``, ``ramp``, ``fs`` [Hz], ``max_rows``,
        ``shuffle_columns``.

    Returns
    -------
    columns : dict of str to numpy.ndarray
        ``time_s`` [s], ``torque_Nm`` [N·m] (side per ``meta``), ``wg_angle_rad`` and/or
        ``output_angle_rad`` [rad] (encoder-quantised), optionally ``temperature_C``.
    meta : dict of str to str
        The ``#`` keys: ``test``, ``ratio``, ``rated_torque_Nm``, ``torque_side``.
    truth : dict
        ``seed``, ``hidden`` (sorted), ``params`` (``base``, one dict or None per family,
        ``nuisance``), ``profile`` (draws, ``plateaus`` with ``t0``, ``t1`` [s],
        ``omega`` [rad/s], ``level``, ``direction``, ``revs``; ``duration_s``, ``fs``),
        ``layout``, ``torque_factor`` (file torque / input torque) and ``clean`` (``time_s``,
        ``omega``, ``acc``, ``wg_angle_rad`` (true), ``temperature_C`` (true),
        ``k_T`` and ``parts``: input-side torque per part and ``total`` [N·m]).
    """
    unknown = set(overrides) - set(DEFAULTS)
    if unknown:
        raise ValueError(f"unknown overrides {sorted(unknown)}; known: {', '.join(DEFAULTS)}")
    ov = {**DEFAULTS, **overrides}
    hidden = set(hidden or ())
    if hidden - set(FAMILIES):
        raise ValueError(f"unknown families {sorted(hidden - set(FAMILIES))}; allowed: {FAMILIES}")
    base = draw_base(seed)
    if ov["inertia"] is not None:
        base["J"] = float(ov["inertia"])
    prof = draw_profile(seed, ov)
    F_c, levels = base["F_c"], prof["levels_rad_s"]
    params = {
        "base": base,
        "friction": draw_friction(seed, levels.min(), F_c, ov["friction_form"]) if "friction" in hidden else None,
        "damping": draw_damping(seed, levels.max(), F_c, ov["damping_form"]) if "damping" in hidden else None,
        "ripple": draw_ripple(seed, F_c, ov) if "ripple" in hidden else None,
        "nuisance": draw_nuisance(seed, F_c, ov),
    }
    nz = params["nuisance"]
    segments, plateaus, duration, fs = build_segments(prof, int(ov["max_rows"]))
    t = np.arange(int(math.floor(duration * fs)) + 1) / fs
    w, acc, phi = kinematics(t, segments, prof["ramp"], base["wg_start_rad"])
    tau = nz["tau_frac"] * duration
    temp = 20.0 + 10.0 * (1.0 - np.exp(-t / tau)) / (1.0 - math.exp(-duration / tau)) if nz["temp_on"] \
        else np.full_like(t, 20.0)
    k_T = 1.0 - nz["drop"] * (temp - 20.0) / 10.0 if nz["temp_on"] else np.ones_like(t)
    parts = running_torque(w, acc, phi, k_T, params)

    rng = _rng(seed, "noise")
    measured = parts["total"] + (rng.normal(0.0, nz["sigma"], t.shape) if nz["sigma"] > 0 else 0.0)
    if nz["q"] > 0:
        measured = np.round(measured / nz["q"]) * nz["q"]  # current (ADC) resolution
    factor = RATIO if nz["layout"] == "output" else 1.0
    quant = bool(ov["quantise_angles"])

    def encoder(angle, counts):
        step = 2.0 * math.pi / counts
        return np.round(angle / step) * step if quant else angle

    cols = {"time_s": t, "torque_Nm": factor * measured}
    if nz["layout"] != "output":
        cols["wg_angle_rad"] = encoder(phi, nz["wg_counts"])
    if nz["layout"] != "wg":
        cols["output_angle_rad"] = encoder(phi / RATIO, nz["out_counts"])
    if nz["temp_on"]:
        temp_meas = temp + rng.normal(0.0, 0.02, t.shape) if ov["noise"] else temp
        cols["temperature_C"] = np.round(temp_meas, 2)
    if ov["shuffle_columns"]:
        names = list(cols)
        cols = {names[i]: cols[names[i]] for i in np.argsort(nz["column_order"][:len(names)])}
    meta = {"test": "running_torque", "ratio": "100", "rated_torque_Nm": "87",
            "torque_side": "output" if nz["layout"] == "output" else "input"}
    truth = {"seed": int(seed), "hidden": sorted(hidden), "params": params, "layout": nz["layout"],
             "torque_factor": factor,
             "profile": {**prof, "segments": segments, "plateaus": plateaus, "duration_s": duration, "fs": fs},
             "clean": {"time_s": t, "omega": w, "acc": acc, "wg_angle_rad": phi, "temperature_C": temp,
                       "k_T": k_T, "parts": parts}}
    return cols, meta, truth


# --------------------------------------------------------------------------- files




def read_csv(path) -> tuple[dict, dict]:
    """Read a file written by :func:`write_csv` back: ``(columns, meta)`` (test support only)."""
    meta, header, rows = {}, None, []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        if line.startswith("#"):
            key, _, value = line[1:].partition(":")
            meta[key.strip()] = value.strip()
        elif header is None:
            header = line.split(",")
        elif line:
            rows.append([float(x) for x in line.split(",")])
    data = np.array(rows)
    return {name: data[:, i] for i, name in enumerate(header)}, meta
