"""Independent "truth" generator of breakaway (starting-torque) bench records.

Test support for diagnosing ``# test: breakaway`` files blind. It imports only numpy and
the standard library and shares no code or functional form with ``hdsim``.

The drive is like a CSG-25-100: ratio N = 100, WG (input) shaft driven by the motor, output
shaft free; catalog starting torque on the input ~0.07 N·m. The motor torque ``T_m(t)`` rises
slowly from 0 until the shaft turns, is held briefly, is ramped back to 0 and the drive
stops; then again (1-3 times per direction, reverse = negative torque).

Drawn per seed (U = uniform; every family has its own random stream)
    ``T_s`` forward static (breakaway) level U(0.04, 0.12) N·m; ``J`` = U(1e-5, 5e-5) kg·m²;
    viscous ``b = v T_s / 10`` (rad/s)^-1, i.e. the loss at 10 rad/s is ``v = U(0, 0.05)`` T_s.
Torque profile (controller), shape drawn 50/50 (override ``shape``)
    ``ramp``: ``|T_m| = r t``, ``r = T_s / U(2, 6)`` s (T_s reached after 2-6 s);
    ``steps``: ``|T_m| = D floor(t / P)``, ``D = U(0.005, 0.02) T_s``, ``P = U(0.1, 0.3)`` s.
    After breakaway the rise continues until the WG has turned ``U(2, 5)`` deg, then T_m is
    held ``U(0.2, 0.5)`` s, ramped linearly to 0 over ``U(0.25, 0.35)`` s, kept 0 until the
    shaft sticks, then rests ``U(0.5, 1)`` s (also before the first ramp). Repeats per
    direction ``1..3`` (override ``repeats``); order ``grouped`` (F..F R..R) or
    ``alternating`` (F R F R), 50/50.
Mechanics (fixed step dt = 1e-4 s, semi-implicit Euler, explicit stick/slip)
    Stuck (w = 0): stays at rest while ``|T_m| <= T_s(dir of T_m)``, breaks away when it exceeds
    it. Moving: ``J dw/dt = T_m - F(w)``,
    ``F(w) = sign(w) [T_c + (T_s - T_c) h(|w| / w_s)] + b w``, ``h(x) = 1 / (1 + x**1.5)``
    (T_s, T_c of the direction of w). When w crosses zero with ``|T_m| <= T_s`` it sticks.
Hidden families (``hidden``, any subset of {"asymmetry", "friction"})
    no "friction": ``T_c = T_s`` (pure Coulomb at the static level, no drop; omega_s None);
    "friction" (Stribeck drop): ``T_c = c T_s``, ``c = U(0.4, 0.75)``, ``w_s = U(2, 20)`` rad/s;
    no "asymmetry": reverse T_s = forward T_s; "asymmetry": reverse = forward (1 + a) or
    forward / (1 + a) (50/50), ``a = U(0.2, 0.5)`` (T_c keeps the same ratio c per direction).
Nuisances (always on)
    Torque from the motor current: + white noise ``sigma = U(0.01, 0.04) T_s`` (times
    ``noise_scale``), quantised in steps ``U(0.002, 0.006) T_s``. WG encoder 2**12..2**14
    counts/rev (rest = constant angle, motion = steps), random initial angle. Sample rate drawn
    from {200, 250, 500, 1000} Hz (override ``sample_rate_Hz``).
    ``torque_side="output"``: the logged torque is (input-side logged torque) x N and the
    angle column is ``output_angle_rad`` = quantised WG angle / N (no WG angle column).
Truth: ``starting_torque_forward_Nm`` / ``_reverse_Nm`` = T_s of that direction (x N on the
output side), positive; None for a direction not in ``directions``. ``T_s``/``T_c`` are dicts
{"forward", "reverse"} on the input side; ``breakaway_times`` are the true instants at which
``|T_m|`` first exceeded T_s in each ramp (with ``breakaway_directions``); ``signals`` holds
the noise-free input torque and WG angle at the sample times (numpy arrays: drop before JSON).
"""
from __future__ import annotations

import math
import zlib

import numpy as np

RATIO = 100
DT = 1e-4
FAMILIES = ("asymmetry", "friction")


def _rng(seed: int, stream: str) -> np.random.Generator:
    """Independent generator per (seed, stream name)."""
    return np.random.default_rng([int(seed), zlib.crc32(stream.encode())])


def _h(x: float) -> float:
    return 1.0 / (1.0 + x ** 1.5)


def _draw(seed: int, hidden: set, ov: dict) -> dict:
    g = _rng(seed, "drive")
    Ts = g.uniform(0.04, 0.12)
    p = {"T_s_forward": Ts, "J": g.uniform(1e-5, 5e-5), "viscous_frac_at_10rad_s": g.uniform(0, 0.05)}
    p["b"] = p["viscous_frac_at_10rad_s"] * Ts / 10.0
    g = _rng(seed, "asymmetry")
    a, up = g.uniform(0.2, 0.5), bool(g.random() < 0.5)
    p["asymmetry"] = a if "asymmetry" in hidden else 0.0
    p["reverse_larger"] = up if "asymmetry" in hidden else None
    ratio_rf = ((1 + a) if up else 1 / (1 + a)) if "asymmetry" in hidden else 1.0
    p["T_s_reverse"] = Ts * ratio_rf
    g = _rng(seed, "friction")
    c, ws = g.uniform(0.4, 0.75), g.uniform(2, 20)
    p["Tc_over_Ts"] = c if "friction" in hidden else 1.0
    p["omega_s"] = ws if "friction" in hidden else None
    g = _rng(seed, "profile")
    shape = "ramp" if g.random() < 0.5 else "steps"
    p["shape"] = ov.get("shape", shape)
    p["ramp_time_to_Ts_s"] = g.uniform(2, 6)
    p["ramp_rate_Nm_s"] = Ts / p["ramp_time_to_Ts_s"]
    p["step_frac"], p["step_period_s"] = g.uniform(0.005, 0.02), g.uniform(0.1, 0.3)
    p["step_Nm"] = p["step_frac"] * Ts
    p["move_threshold_deg"] = g.uniform(2, 5)
    rep = int(g.integers(1, 4))
    p["repeats"] = int(ov.get("repeats", rep))
    p["order"] = "grouped" if g.random() < 0.5 else "alternating"
    g = _rng(seed, "sensor")
    p["noise_frac"] = g.uniform(0.01, 0.04) * float(ov.get("noise_scale", 1.0))
    p["torque_quant_frac"] = g.uniform(0.002, 0.006)
    p["encoder_counts"] = int(2 ** int(g.integers(12, 15)))
    fs = float(g.choice([200.0, 250.0, 500.0, 1000.0]))
    p["sample_rate_Hz"] = float(ov.get("sample_rate_Hz", fs))
    p["initial_angle_rad"] = g.uniform(0, 2 * math.pi)
    return p


def _rise(p: dict, tau):
    """Rising torque magnitude at time tau since the ramp start (scalar or array)."""
    if p["shape"] == "ramp":
        return p["ramp_rate_Nm_s"] * np.asarray(tau, float)
    return p["step_Nm"] * np.floor(np.asarray(tau, float) / p["step_period_s"] + 1e-12)


def _breakaway_tau(p: dict, Ts: float) -> float:
    if p["shape"] == "ramp":
        return Ts / p["ramp_rate_Nm_s"]
    return (math.floor(Ts / p["step_Nm"]) + 1) * p["step_period_s"]


def _move(p: dict, sgn: int, tau_b: float, thr: float, hold: float, tdown: float):
    """Integrate from breakaway until the torque is back at 0 and the shaft stuck.
    Returns (T_m array, relative angle array) at steps k*DT from breakaway."""
    J, b, dt = p["J"], p["b"], DT
    Tsf, Tsr = p["T_s_forward"], p["T_s_reverse"]
    c = p["Tc_over_Ts"]
    Tcf, Tcr = c * Tsf, c * Tsr
    ws = p["omega_s"] or 1.0
    drop = p["omega_s"] is not None
    damp = 1.0 + dt * b / J
    ramp = p["shape"] == "ramp"
    r, D, P = p["ramp_rate_Nm_s"], p["step_Nm"], p["step_period_s"]
    Tl, th = [], []
    th_now, w, stuck = 0.0, 0.0, True
    state, Th, t_state = 0, 0.0, 0.0  # 0 rise, 1 hold, 2 down, 3 zero
    k, kmax = 0, int(60.0 / dt)
    while k < kmax:
        t = k * dt
        if state == 0:
            tau = tau_b + t
            Tm = sgn * (r * tau if ramp else D * math.floor(tau / P + 1e-12))
            if abs(th_now) > thr:
                state, Th, t_state = 1, Tm, t
        if state == 1:
            Tm = Th
            if t - t_state >= hold:
                state, t_state = 2, t
        if state == 2:
            x = (t - t_state) / tdown
            if x >= 1.0:
                state = 3
            Tm = Th * (1.0 - x) if x < 1.0 else 0.0
        if state == 3:
            Tm = 0.0
            if stuck:
                break
        Tl.append(Tm)
        th.append(th_now)
        k += 1
        if stuck:
            if Tm > Tsf:
                d = 1
            elif Tm < -Tsr:
                d = -1
            else:
                continue
            stuck, Fc = False, (Tsf if d > 0 else Tsr)
        else:
            d = 1 if w > 0 else -1
            Ts_d, Tc_d = (Tsf, Tcf) if d > 0 else (Tsr, Tcr)
            Fc = Tc_d + (Ts_d - Tc_d) * _h(abs(w) / ws) if drop else Ts_d
        w_new = (w + dt * (Tm - d * Fc) / J) / damp
        if w_new * d <= 0.0 and (Tm <= Tsf if Tm >= 0 else -Tm <= Tsr):
            w_new, stuck = 0.0, True
        th_now += dt * w_new
        w = w_new
    return np.array(Tl), np.array(th)


def make_breakaway_data(hidden=(), seed: int = 0, **overrides) -> tuple[dict, dict, dict]:
    """-> (columns, meta, truth); see the module docstring for the forms and ranges."""
    hidden = set(hidden)
    bad = hidden - set(FAMILIES)
    if bad:
        raise ValueError(f"unknown hidden families: {sorted(bad)}")
    side = overrides.get("torque_side", "input")
    if side not in ("input", "output"):
        raise ValueError("torque_side must be 'input' or 'output'")
    dirs = tuple(overrides.get("directions", ("forward", "reverse")))
    p = _draw(seed, hidden, overrides)
    n = p["repeats"]
    if p["order"] == "grouped":
        seq = [d for d in dirs for _ in range(n)]
    else:
        seq = [d for _ in range(n) for d in dirs]
    g = _rng(seed, "ramps")
    t = _rng(seed, "rest0").uniform(0.5, 1.0)
    theta = p["initial_angle_rad"]
    segs = [(0.0, t, None, theta)]  # (t0, t1, payload, angle); payload None = rest at 0 torque
    tb_list = []
    for dname in seq:
        hold, tdown, rest = g.uniform(0.2, 0.5), g.uniform(0.25, 0.35), g.uniform(0.5, 1.0)
        sgn = 1 if dname == "forward" else -1
        Ts = p["T_s_forward"] if sgn > 0 else p["T_s_reverse"]
        tau_b = _breakaway_tau(p, Ts)
        segs.append((t, t + tau_b, ("rise", sgn), theta))
        tb_list.append(t + tau_b)
        Tm, th = _move(p, sgn, tau_b, math.radians(p["move_threshold_deg"]), hold, tdown)
        t0 = t + tau_b
        segs.append((t0, t0 + len(Tm) * DT, ("move", Tm, th + theta), theta))
        theta = theta + (th[-1] if len(th) else 0.0)
        t = t0 + len(Tm) * DT
        segs.append((t, t + rest, None, theta))
        t += rest
    fs = p["sample_rate_Hz"]
    ts = np.arange(int(t * fs) + 1) / fs
    T = np.zeros_like(ts)
    A = np.full_like(ts, theta)
    for t0, t1, pay, ang in segs:
        m = (ts >= t0) & (ts < t1)
        if pay is None:
            A[m] = ang
        elif pay[0] == "rise":
            T[m], A[m] = pay[1] * _rise(p, ts[m] - t0), ang
        else:
            i = np.clip(((ts[m] - t0) / DT).astype(int), 0, len(pay[1]) - 1)
            T[m], A[m] = pay[1][i], pay[2][i]
    Ts_ref = p["T_s_forward"]
    gn = _rng(seed, "noise")
    q = p["torque_quant_frac"] * Ts_ref
    Tmeas = np.round((T + gn.normal(0.0, p["noise_frac"] * Ts_ref, ts.size)) / q) * q + 0.0
    lsb = 2 * math.pi / p["encoder_counts"]
    Ameas = np.round(A / lsb) * lsb + 0.0
    cols = {"time_s": ts}
    k = RATIO if side == "output" else 1
    if side == "output":
        cols["output_angle_rad"] = Ameas / RATIO
    else:
        cols["wg_angle_rad"] = Ameas
    cols["torque_Nm"] = Tmeas * k
    meta = {"test": "breakaway", "ratio": RATIO, "torque_side": side}
    c = p["Tc_over_Ts"]
    truth = dict(p)
    truth.update({
        "hidden": sorted(hidden), "torque_side": side, "directions": list(dirs),
        "starting_torque_forward_Nm": p["T_s_forward"] * k if "forward" in dirs else None,
        "starting_torque_reverse_Nm": p["T_s_reverse"] * k if "reverse" in dirs else None,
        "T_s": {"forward": p["T_s_forward"], "reverse": p["T_s_reverse"]},
        "T_c": {"forward": c * p["T_s_forward"], "reverse": c * p["T_s_reverse"]},
        "h": "1/(1+x**1.5)", "dt_s": DT, "breakaway_times": tb_list,
        "breakaway_directions": seq,
        "signals": {"torque_input_Nm": T, "wg_angle_rad": A},  # noise-free, numpy (not JSON)
    })
    return cols, meta, truth


def write_csv(path, columns: dict, meta: dict) -> None:
    """Write ``# key: value`` lines, one header row, then the numbers."""
    names = list(columns)
    data = np.column_stack([np.asarray(columns[k], float) for k in names])
    fmt = ["%.6f"] + ["%.10g"] * (len(names) - 1)
    with open(path, "w", encoding="utf-8") as f:
        for key, val in meta.items():
            f.write(f"# {key}: {val}\n")
        f.write(",".join(names) + "\n")
        np.savetxt(f, data, delimiter=",", fmt=fmt)
