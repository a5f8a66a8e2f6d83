"""Independent "truth" generators: bench-like data with hidden effects, for diagnosis tests.

This module is test support. It deliberately imports nothing from ``hdsim``: the data
it makes must not share code, or functional forms, with the library's effect classes
(``reference/sensitivity-and-diagnosis.md`` section 7, "non-circular tests"). Data made
by the library's own effects is a self-consistency test; data made here is a discovery
test. Keep the two apart.

Truth model (SI units inside)
-----------------------------
The flexspline "body" carries the torque ``T(t)`` applied to the output; its twist
``theta_s`` obeys the torque balance of parallel elements::

    T = F_el(theta_s) + H + sum_j v_j + tau_c * sqrt(k1 * F_el'(theta_s)) * dtheta_s/dt

and a dead zone sits in series, so the measured angle is::

    angle = offset + theta_s + theta_b(T) + noise, then quantised by the encoder

The stiffness test drives ``T(t)`` (wave generator locked); ``theta_s`` is integrated
with this module's own ``scipy.integrate.solve_ivp`` call (LSODA), restarted at every
corner of the torque profile. Families and their truth forms; by default none is a form
hdsim has (three-segment or tanh hardening, Dahl, Coulomb, Maxwell-slip, piecewise or
tanh dead zone, constant or stiffness-proportional viscous damping, a Fourier-only KE):

``base`` (always)
    Linear compliance ``F_el = k1 * theta`` with ``k1 = K1 * U(0.85, 1.15)``
    (CSG-25-100: ``K1 = 3.1e4 N·m/rad``) and a random angle offset ``U(-pi, pi)`` rad.
``hardening``
    ``cubic``: ``F_el = k1*theta + k3*theta**3``, or ``exponential``:
    ``F_el = (k1/a) * sinh(a*theta)`` (form drawn per seed). The non-linear term shrinks
    the twist at rated torque by ``h = U(0.20, 0.40)`` of the linear ``T_N/k1`` (the
    catalog three-segment law gives h = 0.35 for CSG-25-100), which fixes ``k3`` or ``a``.
``backlash``
    A dead zone in series with a soft, smooth closure (not a piecewise spring):
    ``theta_b = (b/2) * T / sqrt(T**2 + T_b**2)``, total width
    ``b = U(0.3, 1.0) arcmin``, closing torque ``T_b = T_N * U(0.001, 0.005)``. Seen as a
    near-vertical step of ``b`` in twist where the torque crosses zero.
``friction`` (rate-independent hysteresis, ``H``)
    ``bouc_wen`` (default): one Bouc–Wen torque ``z`` with exponent ``n = U(1.5, 3.0)``
    (Dahl is the n = 1 case, so this is a different loop shape),
    ``dz/dtheta = A - |z|**n * (beta*sign(z*dtheta) + gamma)``, ``A = k1 * U(1.5, 4)``,
    ``beta/(beta+gamma) = U(0.55, 0.9)``. On request only (``friction_form``; the
    library has a Maxwell-slip effect, so this is not a discovery test):
    ``maxwell_slip``, 4–8 regularised elasto-slip elements
    ``dw_i/dtheta = k_i * (1 - [w_i*dtheta > 0] * (|w_i|/f_i)**16)`` with random slip
    torques ``f_i`` and break-away twists ``f_i/k_i`` over 0.05–0.6 of the loop width.
    Saturated friction torque ``z_u`` chosen so that the loop is
    ``W = U(0.5, 1.5) arcmin`` wide at zero torque (``z_u = W*k1/2``).
``damping`` (rate-dependent)
    Kelvin–Voigt viscous term at a constant damping ratio, the gear-mesh convention
    ``c = 2 zeta sqrt(k m)`` (e.g. Kahraman & Singh, J. Sound Vib. 142(1), 1990):
    ``tau_c * sqrt(k1 * F_el'(theta_s)) * dtheta_s/dt``, ``tau_c = U(0.008, 0.020) s``;
    it grows with the square root of the tangent stiffness, which the library's
    constant-plus-proportional law can only approximate. Without hardening this is a
    constant ``c = k1*tau_c``, about 200–700 N·m·s/rad.
    Loop width at zero torque ~ ``2*tau_c*dT/dt/k1``:
    0.2–0.5 arcmin at 87 N·m/s, 0.8–1.9 arcmin at 348 N·m/s. The default torque profile
    has two loading rates (x1 and x4) so damping can be told from friction.
``rate_dependent_unknown`` (outside the library)
    A fractional-order (springpot) element ``c_a * D**alpha theta_s``,
    ``alpha = U(0.25, 0.5)``, realised as 9 Maxwell arms ``dv_j/dt = k_j*dtheta/dt -
    v_j/tau_j`` with ``tau_j`` log-spaced over 1e-2..1e2 s and ``k_j ~ tau_j**-alpha``,
    scaled so the loss stiffness at 1 rad/s is ``eta*k1``, ``eta = U(0.03, 0.06)``. Loop
    width grows like rate**alpha: neither rate-independent nor viscous, and it creeps.
``kinematic_error`` (kinematic-error test only)
    Periodic in the wave-generator angle ``phi`` (and once per output turn), not a
    plain Fourier series:
    ``a1*sin(phi + p1) + a2*vm(2*(phi - p2); kappa) + a4*sin(4*phi + p4)
    + ao*sin(phi/N + po)`` where ``vm(x; kappa) = (exp(kappa*cos x) - I0(kappa)) /
    (2*I1(kappa))`` is a von-Mises bump (first harmonic amplitude 1, plus 4x, 6x, ...
    content), ``a1 = U(3, 10)``, ``a2 = U(10, 30)``, ``a4 = U(2, 6)``, ``ao = U(10, 30)``
    arcsec, ``kappa = U(0.5, 1.5)``, random phases.

Kinematic-error test
    The output turns a little over one revolution each way at constant speed (20 s per
    revolution), reversing smoothly; the load ``T_L = T_N * U(0.15, 0.35)`` opposes the
    motion, so the body families above show up as lost motion on reversal.

Measurement chain (defaults; every one a keyword)
    Angle noise Gaussian ``2e-6 rad`` (0.4 arcsec) rms, then encoder quantisation
    ``2*pi/2**22 = 1.5e-6 rad`` (a 22-bit output encoder); torque-sensor noise Gaussian
    ``0.01 N·m`` rms. The model is driven by the true torque; the file gets the noisy one.
    Kinematic-error test: the wave-generator encoder has its own offset and quantisation
    ``2*pi/2**17`` (a motor encoder), which is ``~5e-7 rad`` at the output for ratio 100.

Random draws use one stream per family, seeded by ``(seed, family)``, so a family's
parameters for a seed are the same whatever other families are present: data with and
without a family differ only by that family.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from truth_files import to_csv_text, write_csv  # noqa: F401  (re-exported: one writer of the file contract)
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import i0, i1

FAMILIES = ("hardening", "backlash", "friction", "damping", "kinematic_error",
            "rate_dependent_unknown")
#: Families the stiffness test can show (the wave generator is locked: no KE).
STIFFNESS_FAMILIES = tuple(f for f in FAMILIES if f != "kinematic_error")

ARCMIN = math.pi / 10800.0  # [rad]
ARCSEC = math.pi / 648000.0  # [rad]

# CSG-25-100 (harmonic-drive.md section 2): rated torque and low-load stiffness.
RATED_TORQUE_NM = 87.0
K1_NM_PER_RAD = 3.1e4

NOISE_RAD = 2e-6  # [rad] rms angle noise
QUANT_RAD = 2.0 * math.pi / 2**22  # [rad] output encoder step (22 bit)
NOISE_NM = 0.01  # [N·m] rms torque-sensor noise
WG_QUANT_RAD = 2.0 * math.pi / 2**17  # [rad] wave-generator (motor) encoder step

_STREAM = {name: i + 1 for i, name in enumerate(("base",) + FAMILIES)}
_STREAM["noise"] = 99
_STREAM["load"] = 98


def _rng(seed: int, stream: str) -> np.random.Generator:
    """An independent random stream per (seed, family) so draws do not shift."""
    return np.random.default_rng([int(seed), _STREAM[stream]])


def _check_families(hidden, baseline, allowed) -> tuple[set, set]:
    hidden, baseline = set(hidden or ()), set(baseline or ())
    unknown = (hidden | baseline) - set(allowed)
    if unknown:
        raise ValueError(f"unknown or inapplicable families {sorted(unknown)}; "
                         f"allowed: {', '.join(allowed)}")
    if hidden & baseline:
        raise ValueError(f"families both hidden and in the baseline: {sorted(hidden & baseline)}")
    return hidden, baseline


# --------------------------------------------------------------------------- draws


def draw_base(seed: int, k1_nominal: float = K1_NM_PER_RAD) -> dict:
    """Linear stiffness ``k1`` [N·m/rad] and angle offset ``offset_rad`` [rad]."""
    rng = _rng(seed, "base")
    return {"k1": k1_nominal * rng.uniform(0.85, 1.15),
            "offset_rad": rng.uniform(-math.pi, math.pi)}


def draw_hardening(seed: int, k1: float, rated_torque: float, form: str | None = None) -> dict:
    """Cubic or exponential (sinh) stiffening; twist at ``rated_torque`` cut by ``h``.

    Returns ``{'form', 'h', 'k3'}`` [N·m/rad³] for cubic or ``{'form', 'h', 'a'}`` [1/rad]
    for exponential.
    """
    rng = _rng(seed, "hardening")
    drawn = rng.choice(["cubic", "exponential"])
    form = form or str(drawn)
    h = rng.uniform(0.20, 0.40)
    theta_n = (1.0 - h) * rated_torque / k1  # twist at rated torque [rad]
    if form == "cubic":
        return {"form": form, "h": h, "k3": (rated_torque - k1 * theta_n) / theta_n**3}
    if form == "exponential":
        # (k1/a) sinh(a theta_n) = T_N  <=>  sinh(x)/x = 1/(1-h), x = a*theta_n
        x = brentq(lambda x: math.sinh(x) / x - 1.0 / (1.0 - h), 1e-6, 20.0)
        return {"form": form, "h": h, "a": x / theta_n}
    raise ValueError(f"unknown hardening form {form!r}; use 'cubic' or 'exponential'")


def draw_backlash(seed: int, rated_torque: float) -> dict:
    """Dead-zone width ``b_rad`` [rad] and closing torque ``T_b`` [N·m]."""
    rng = _rng(seed, "backlash")
    return {"b_rad": rng.uniform(0.3, 1.0) * ARCMIN,
            "T_b": rated_torque * rng.uniform(0.001, 0.005)}


def draw_friction(seed: int, k1: float, form: str | None = None) -> dict:
    """Bouc–Wen (n != 1) or Maxwell-slip hysteresis sized by its zero-torque loop width.

    Returns ``form``, ``width_rad`` (target loop width at zero torque [rad]), ``z_u``
    (saturated friction torque [N·m]) and the form's parameters: Bouc–Wen ``A``
    [N·m/rad], ``beta``, ``gamma`` [N·m^(1-n)/rad], ``n``; Maxwell-slip arrays ``k``
    [N·m/rad] and ``f`` [N·m] and exponent ``p``.
    """
    rng = _rng(seed, "friction")
    rng.choice(["bouc_wen", "maxwell_slip"])  # kept so the stream of later draws is stable
    # Default Bouc-Wen: hdsim has Dahl and a Maxwell-slip effect, so only Bouc-Wen
    # (n != 1) keeps the friction test a discovery test; Maxwell-slip only on request.
    form = form or "bouc_wen"
    width = rng.uniform(0.5, 1.5) * ARCMIN
    z_u = width * k1 / 2.0
    if form == "bouc_wen":
        n = rng.uniform(1.5, 3.0)
        a = k1 * rng.uniform(1.5, 4.0)
        total = a / z_u**n  # beta + gamma: saturation at |z| = z_u
        share = rng.uniform(0.55, 0.9)  # beta >= gamma keeps dz/dtheta >= 0 on reversal
        return {"form": form, "width_rad": width, "z_u": z_u, "A": a, "n": n,
                "beta": share * total, "gamma": (1.0 - share) * total}
    if form == "maxwell_slip":
        m = int(rng.integers(4, 9))
        f = z_u * rng.dirichlet(np.full(m, 2.0))
        # break-away twists spread over 0.05..0.6 of the loop width
        delta = width * np.exp(rng.uniform(np.log(0.05), np.log(0.6), m))
        return {"form": form, "width_rad": width, "z_u": z_u, "f": f, "k": f / delta,
                "p": 16.0}
    raise ValueError(f"unknown friction form {form!r}; use 'bouc_wen' or 'maxwell_slip'")


def draw_damping(seed: int, k1: float) -> dict:
    """Kelvin–Voigt damping at a constant damping ratio: time constant ``tau_c`` [s].

    The damper torque is ``tau_c * sqrt(k1 * F_el'(theta)) * dtheta/dt``; ``c = tau_c * k1``
    [N·m·s/rad] is its value at zero twist (the whole story without hardening).
    """
    rng = _rng(seed, "damping")
    tau = rng.uniform(0.008, 0.020)
    return {"tau_c": tau, "c": tau * k1}


def draw_rate_unknown(seed: int, k1: float, arms: int = 9) -> dict:
    """Fractional-order (springpot) element as a Prony series of Maxwell arms.

    Returns ``alpha``, ``eta``, ``tau`` [s] and ``k`` [N·m/rad] arrays.
    """
    rng = _rng(seed, "rate_dependent_unknown")
    alpha = rng.uniform(0.25, 0.5)
    eta = rng.uniform(0.03, 0.06)
    tau = np.logspace(-2.0, 2.0, arms)
    k = tau**-alpha
    omega = 1.0  # [rad/s] reference frequency of the loss stiffness
    loss = np.sum(k * omega * tau / (1.0 + (omega * tau) ** 2))
    return {"alpha": alpha, "eta": eta, "tau": tau, "k": k * (eta * k1 / loss)}


def draw_ke(seed: int) -> dict:
    """Kinematic-error shape: amplitudes [rad], phases [rad], von-Mises ``kappa``."""
    rng = _rng(seed, "kinematic_error")
    return {"a1": rng.uniform(3, 10) * ARCSEC, "a2": rng.uniform(10, 30) * ARCSEC,
            "a4": rng.uniform(2, 6) * ARCSEC, "ao": rng.uniform(10, 30) * ARCSEC,
            "kappa": rng.uniform(0.5, 1.5),
            "p1": rng.uniform(0, 2 * math.pi), "p2": rng.uniform(0, 2 * math.pi),
            "p4": rng.uniform(0, 2 * math.pi), "po": rng.uniform(0, 2 * math.pi)}


# --------------------------------------------------------------------------- laws


def elastic_torque(theta, k1: float, hardening: dict | None):
    """Spring torque ``F_el`` [N·m] and tangent stiffness [N·m/rad] at twist ``theta``."""
    if not hardening:
        return k1 * theta, k1 + 0.0 * theta
    if hardening["form"] == "cubic":
        k3 = hardening["k3"]
        return k1 * theta + k3 * theta**3, k1 + 3.0 * k3 * theta**2
    a = hardening["a"]
    return k1 / a * np.sinh(a * theta), k1 * np.cosh(a * theta)


def backlash_angle(torque, backlash: dict | None):
    """Series dead-zone angle ``(b/2) T/sqrt(T²+T_b²)`` [rad] at torque ``torque`` [N·m]."""
    if not backlash:
        return 0.0 * np.asarray(torque, dtype=float)
    torque = np.asarray(torque, dtype=float)
    return 0.5 * backlash["b_rad"] * torque / np.sqrt(torque**2 + backlash["T_b"] ** 2)


def _friction_slope(h: np.ndarray, direction: float, friction: dict) -> np.ndarray:
    """d(friction state)/d(theta) [N·m/rad] for the sign of the twist rate."""
    if friction["form"] == "bouc_wen":
        z = h[0]
        slope = friction["A"] - abs(z) ** friction["n"] * (
            friction["beta"] * np.sign(z * direction) + friction["gamma"])
        return np.array([slope])
    w, f, k = h, friction["f"], friction["k"]
    sticking = (w * direction) > 0  # pushed further in its own direction: may saturate
    return k * (1.0 - sticking * (np.abs(w) / f) ** friction["p"])


def ke_angle(wg_angle, ratio: float, ke: dict | None):
    """Kinematic error [rad] at wave-generator angle ``wg_angle`` [rad]."""
    wg_angle = np.asarray(wg_angle, dtype=float)
    if not ke:
        return 0.0 * wg_angle
    kappa = ke["kappa"]
    x = 2.0 * (wg_angle - ke["p2"])
    bump = (np.exp(kappa * np.cos(x)) - i0(kappa)) / (2.0 * i1(kappa))
    return (ke["a1"] * np.sin(wg_angle + ke["p1"]) + ke["a2"] * bump
            + ke["a4"] * np.sin(4.0 * wg_angle + ke["p4"])
            + ke["ao"] * np.sin(wg_angle / ratio + ke["po"]))


# --------------------------------------------------------------------------- body ODE


def _body_rhs(params: dict, torque, torque_rate):
    """RHS of the body: state ``[theta_s, friction states..., Maxwell-arm torques...]``."""
    k1, hard = params["k1"], params.get("hardening")
    fric, unk = params.get("friction"), params.get("rate_dependent_unknown")
    tau_c = params["damping"]["tau_c"] if params.get("damping") else 0.0
    nf = _n_friction(fric)
    kp = unk["k"] if unk else np.zeros(0)
    taup = unk["tau"] if unk else np.ones(0)

    def rhs(t, y):
        theta = y[0]
        h, v = y[1:1 + nf], y[1 + nf:]
        spring, stiff = elastic_torque(theta, k1, hard)
        relax = v / taup
        if tau_c > 0.0:
            # Kelvin-Voigt in parallel: the torque balance gives the twist rate directly.
            # Constant damping ratio: c grows like sqrt(tangent stiffness), not constant.
            rate = (torque(t) - spring - h.sum() - v.sum()) / (tau_c * np.sqrt(k1 * stiff))
            slope = _friction_slope(h, np.sign(rate), fric) if nf else h
        else:
            # No damper: differentiate the balance, dT = (F' + sum slopes + sum k) dtheta - relax.
            drive = torque_rate(t) + relax.sum()
            slope = _friction_slope(h, np.sign(drive), fric) if nf else h
            rate = drive / (stiff + slope.sum() + kp.sum())
        return np.concatenate(([rate], slope * rate, kp * rate - relax))

    return rhs


def _n_friction(fric: dict | None) -> int:
    if not fric:
        return 0
    return 1 if fric["form"] == "bouc_wen" else len(fric["f"])


def simulate_body(params: dict, knots_t, torque, torque_rate, t_eval) -> np.ndarray:
    """Twist ``theta_s`` [rad] of the body at ``t_eval`` under torque ``torque(t)`` [N·m].

    Parameters
    ----------
    params : dict
        ``k1`` and the family parameter dicts (``hardening``, ``friction``, ``damping``,
        ``rate_dependent_unknown``), each absent or None when off.
    knots_t : array_like
        Times [s] where the torque profile has corners; the solver restarts there.
    torque, torque_rate : callable
        ``T(t)`` [N·m] and ``dT/dt(t)`` [N·m/s].
    t_eval : numpy.ndarray
        Sample times [s], inside ``[knots_t[0], knots_t[-1]]``.
    """
    nf = _n_friction(params.get("friction"))
    unk = params.get("rate_dependent_unknown")
    npr = len(unk["k"]) if unk else 0
    y = np.zeros(1 + nf + npr)
    # Twist is ~1e-3 rad, friction and arm torques ~1..10 N·m: scale atol per state.
    atol = np.concatenate(([1e-12], np.full(nf + npr, 1e-8)))
    out = np.empty(len(t_eval))
    knots_t = np.asarray(knots_t, dtype=float)
    for a, b in zip(knots_t[:-1], knots_t[1:]):
        # A corner's rate belongs to both legs; ask for the rate strictly inside this one.
        eps = 1e-9 * (b - a)

        def rate(x, a=a, b=b, eps=eps):
            return torque_rate(min(max(x, a + eps), b - eps))

        rhs = _body_rhs(params, torque, rate)
        inside = (t_eval >= a) & ((t_eval <= b) if b == knots_t[-1] else (t_eval < b))
        # evaluate at the samples and at the corner b, whose state starts the next leg
        times = t_eval[inside]
        times = times if times.size and times[-1] == b else np.append(times, b)
        sol = solve_ivp(rhs, (a, b), y, method="LSODA", t_eval=times,
                        rtol=1e-8, atol=atol, max_step=(b - a) / 20.0)
        if sol.status != 0:
            raise RuntimeError(f"truth ODE failed on [{a}, {b}] s: {sol.message}")
        out[inside] = sol.y[0, : inside.sum()]
        y = sol.y[:, -1]
    return out


# --------------------------------------------------------------------------- profiles


def stiffness_profile(amplitude: float, quarter_s=(1.0, 0.25), cycles: int = 1):
    """Triangular torque cycles ``0 -> +A -> -A -> +A -> 0`` once per loading rate.

    Parameters
    ----------
    amplitude : float
        Peak torque A [N·m].
    quarter_s : sequence of float
        Time [s] of one quarter cycle (0 -> A) for each block; the loading rate of a
        block is ``A / quarter`` [N·m/s]. Two or more values let damping be identified.
    cycles : int
        Full ``+A -> -A -> +A`` cycles per block.

    Returns
    -------
    knots_t, knots_T : numpy.ndarray
        Corner times [s] and torques [N·m] of the piecewise-linear profile.
    """
    times, torques = [0.0], [0.0]
    for q in quarter_s:
        legs = [(amplitude, q)] + [(-amplitude, 2 * q), (amplitude, 2 * q)] * cycles + [(0.0, q)]
        for target, duration in legs:
            times.append(times[-1] + duration)
            torques.append(target)
    return np.array(times), np.array(torques)


def _measure_angle(clean, rng, noise_rad, quant_rad):
    """Encoder reading: jitter then quantisation of the absolute angle [rad]."""
    noisy = clean + rng.normal(0.0, noise_rad, clean.shape) if noise_rad > 0 else clean
    return np.round(noisy / quant_rad) * quant_rad if quant_rad > 0 else noisy


def _family_params(present: set, seed: int, k1_nominal: float, rated_torque: float,
                   forms: dict) -> dict:
    base = draw_base(seed, k1_nominal)
    k1 = base["k1"]
    return {
        "k1": k1,
        "offset_rad": base["offset_rad"],
        "hardening": draw_hardening(seed, k1, rated_torque, forms.get("hardening"))
        if "hardening" in present else None,
        "backlash": draw_backlash(seed, rated_torque) if "backlash" in present else None,
        "friction": draw_friction(seed, k1, forms.get("friction"))
        if "friction" in present else None,
        "damping": draw_damping(seed, k1) if "damping" in present else None,
        "rate_dependent_unknown": draw_rate_unknown(seed, k1)
        if "rate_dependent_unknown" in present else None,
        "kinematic_error": draw_ke(seed) if "kinematic_error" in present else None,
    }


# --------------------------------------------------------------------------- generators


def make_stiffness_data(
    hidden=(),
    baseline=(),
    seed: int = 0,
    n_rows: int = 2000,
    noise_rad: float = NOISE_RAD,
    quant_rad: float = QUANT_RAD,
    noise_Nm: float = NOISE_NM,
    offset_rad: float | None = None,
    rated_torque_Nm: float = RATED_TORQUE_NM,
    k1_Nm_per_rad: float = K1_NM_PER_RAD,
    amplitude_frac: float = 1.0,
    quarter_s=(1.0, 0.25),
    cycles: int = 1,
    friction_form: str | None = None,
    hardening_form: str | None = None,
) -> tuple[dict, dict]:
    """Bench-like stiffness test (wave generator locked): torque in, twist out.

    Parameters
    ----------
    hidden, baseline : iterable of str
        Families present in the data; ``hidden`` is what a diagnosis should find,
        ``baseline`` what it is told about. Both go into the data alike; the split is
        recorded in ``truth``. Any of :data:`STIFFNESS_FAMILIES`.
    seed : int
        Seeds every draw (parameters, offset, noise).
    n_rows : int
        Samples, equally spaced in time over the whole profile.
    noise_rad : float
        Angle noise rms [rad].
    quant_rad : float
        Encoder step [rad]; 0 for none.
    noise_Nm : float
        Torque-sensor noise rms [N·m].
    offset_rad : float, optional
        Encoder zero offset [rad]; drawn ``U(-pi, pi)`` when None.
    rated_torque_Nm : float
        Rated torque T_N [N·m] (default CSG-25-100).
    k1_Nm_per_rad : float
        Nominal low-load stiffness K1 [N·m/rad]; the truth draws ``k1`` within ±15 %.
    amplitude_frac : float
        Peak torque as a fraction of T_N.
    quarter_s : sequence of float
        Quarter-cycle time [s] of each loading-rate block (default two rates, x1 and x4).
    cycles : int
        Full cycles per block.
    friction_form, hardening_form : str, optional
        Force a form (``'bouc_wen'``/``'maxwell_slip'``, ``'cubic'``/``'exponential'``)
        instead of drawing it.

    Returns
    -------
    columns : dict of str to numpy.ndarray
        ``time_s`` [s], ``torque_Nm`` [N·m] (with sensor noise), ``angle_rad`` [rad]
        (offset, noise, quantisation).
    truth : dict
        ``test``, ``seed``, ``hidden``, ``baseline``, ``families`` (sorted lists),
        ``meta`` (the ``#`` keys for a file), ``params`` (per family, None when off, plus
        ``k1`` and ``offset_rad``), ``measurement`` (noise settings), ``profile``
        (``knots_t``, ``knots_T``, ``quarter_s``) and ``clean`` (noise-free
        ``torque_Nm``, ``angle_rad`` incl. offset, ``twist_rad`` without offset and
        ``block`` index of the rate block per sample).
    """
    hidden, baseline = _check_families(hidden, baseline, STIFFNESS_FAMILIES)
    present = hidden | baseline
    params = _family_params(present, seed, k1_Nm_per_rad, rated_torque_Nm,
                            {"friction": friction_form, "hardening": hardening_form})
    if offset_rad is not None:
        params["offset_rad"] = float(offset_rad)
    knots_t, knots_T = stiffness_profile(amplitude_frac * rated_torque_Nm, quarter_s, cycles)
    t = np.linspace(knots_t[0], knots_t[-1], int(n_rows))
    slopes = np.diff(knots_T) / np.diff(knots_t)

    def torque(x):
        return np.interp(x, knots_t, knots_T)

    def torque_rate(x):
        # simulate_body asks strictly inside a leg, so the leg found for x is the right one
        return slopes[min(np.searchsorted(knots_t, x, side="right") - 1, len(slopes) - 1)]

    true_T = torque(t)
    twist = simulate_body(params, knots_t, torque, torque_rate, t) \
        + backlash_angle(true_T, params["backlash"])
    clean_angle = params["offset_rad"] + twist
    rng = _rng(seed, "noise")
    angle = _measure_angle(clean_angle, rng, noise_rad, quant_rad)
    measured_T = true_T + (rng.normal(0.0, noise_Nm, t.shape) if noise_Nm > 0 else 0.0)
    per_block = 2 + 2 * cycles  # legs per block
    block = np.minimum(np.searchsorted(knots_t, t, side="right") - 1,
                       len(knots_t) - 2) // per_block
    columns = {"time_s": t, "torque_Nm": measured_T, "angle_rad": angle}
    truth = {
        "test": "stiffness", "seed": int(seed),
        "hidden": sorted(hidden), "baseline": sorted(baseline), "families": sorted(present),
        "meta": {"test": "stiffness", "rated_torque_Nm": repr(float(rated_torque_Nm))},
        "params": params,
        "measurement": {"noise_rad": noise_rad, "quant_rad": quant_rad, "noise_Nm": noise_Nm},
        "profile": {"knots_t": knots_t, "knots_T": knots_T, "quarter_s": tuple(quarter_s),
                    "cycles": cycles},
        "clean": {"torque_Nm": true_T, "angle_rad": clean_angle, "twist_rad": twist,
                  "block": block},
    }
    return columns, truth


def _log_cosh(x):
    x = np.abs(x)
    return x + np.log1p(np.exp(-2.0 * x)) - math.log(2.0)


def make_ke_data(
    hidden=("kinematic_error",),
    baseline=(),
    seed: int = 0,
    n_rows: int = 8000,
    ratio: float = 100.0,
    revolution_s: float = 20.0,
    reversal_s: float = 0.2,
    load_frac: float | None = None,
    noise_rad: float = NOISE_RAD,
    quant_rad: float = QUANT_RAD,
    wg_quant_rad: float = WG_QUANT_RAD,
    noise_Nm: float = NOISE_NM,
    offset_rad: float | None = None,
    rated_torque_Nm: float = RATED_TORQUE_NM,
    k1_Nm_per_rad: float = K1_NM_PER_RAD,
    friction_form: str | None = None,
    hardening_form: str | None = None,
    load_profile: str = "opposing",
) -> tuple[dict, dict]:
    """Bench-like kinematic-error test: wave generator driven both ways under load.

    The output turns a little more than one revolution forward at constant speed, reverses
    smoothly (``tanh`` speed profile, time constant ``reversal_s``) and turns back. The
    load opposes the output's motion, ``T(t) = -T_L * tanh((t_rev - t)/reversal_s)``
    with ``T_L = load_frac * T_N``; the body twists under it as in
    :func:`make_stiffness_data`, so backlash, friction, hardening and damping show up as
    lost motion on reversal. ``torque_Nm`` is the torque the load applies to the output
    (same sign sense as the stiffness test: positive torque, positive twist).

    Parameters
    ----------
    hidden, baseline : iterable of str
        Families present (any of :data:`FAMILIES`); see :func:`make_stiffness_data`.
    seed : int
        Seeds every draw.
    n_rows : int
        Samples, equally spaced in time. The default gives ~40 samples per
        wave-generator revolution.
    ratio : float
        Transmission ratio [-]; negative turns the wave generator the other way.
    revolution_s : float
        Time of one output revolution [s].
    reversal_s : float
        Time constant of the speed reversal [s].
    load_frac : float, optional
        Load torque as a fraction of T_N; drawn ``U(0.15, 0.35)`` when None.
    noise_rad, quant_rad : float
        Output-angle noise rms and encoder step [rad].
    wg_quant_rad : float
        Wave-generator encoder step [rad].
    noise_Nm : float
        Torque-sensor noise rms [N·m].
    offset_rad : float, optional
        Output-encoder zero offset [rad]; drawn when None. The wave-generator encoder
        gets its own drawn offset (recorded in ``truth``).
    rated_torque_Nm, k1_Nm_per_rad : float
        T_N [N·m] and nominal K1 [N·m/rad].
    friction_form, hardening_form : str, optional
        Force a form instead of drawing it.
    load_profile : str
        ``opposing`` (above: the load flips with the motion); ``sine``: a load that does
        not follow the motion and varies slowly by ±50 % about ``T_L``,
        ``T_L (1 + 0.5 sin(2π t/P + φ))`` with ``P = U(0.3, 0.7)`` of the record and a
        drawn phase; ``ramp``: a load ramping one way over the record, ``T_L (2 t/t_end − 1)``;
        ``windup``: a constant load whose transmitted torque steps by ``±f T_L`` with the
        direction (the friction of an output bearing the sensor sees), ``f = U(0.1, 0.3)``.

    Returns
    -------
    columns : dict of str to numpy.ndarray
        ``time_s``, ``wg_angle_rad``, ``output_angle_rad``, ``torque_Nm``.
    truth : dict
        As :func:`make_stiffness_data`, with ``clean`` holding ``wg_angle_rad`` (true),
        ``output_angle_rad``, ``ke_rad`` (the KE term alone), ``twist_rad`` and
        ``torque_Nm``, and ``params['load_Nm']``, ``params['wg_offset_rad']``.
    """
    hidden, baseline = _check_families(hidden, baseline, FAMILIES)
    present = hidden | baseline
    params = _family_params(present, seed, k1_Nm_per_rad, rated_torque_Nm,
                            {"friction": friction_form, "hardening": hardening_form})
    if offset_rad is not None:
        params["offset_rad"] = float(offset_rad)
    rng_load = _rng(seed, "load")
    drawn_frac = rng_load.uniform(0.15, 0.35)
    load = rated_torque_Nm * (drawn_frac if load_frac is None else load_frac)
    params["load_Nm"] = load
    params["wg_offset_rad"] = rng_load.uniform(-math.pi, math.pi)
    params["ratio"] = float(ratio)

    omega_out = 2.0 * math.pi / revolution_s  # [rad/s], positive in the first half
    t_rev = revolution_s * 1.02 + reversal_s  # a little more than one revolution each way
    t_end = 2.0 * t_rev
    t = np.linspace(0.0, t_end, int(n_rows))
    # output speed omega_out*tanh((t_rev - t)/reversal_s); its integral in closed form
    nominal_out = omega_out * reversal_s * (_log_cosh(t_rev / reversal_s)
                                            - _log_cosh((t_rev - t) / reversal_s))
    wg = ratio * nominal_out

    if load_profile == "opposing":
        def torque(x):
            return -load * np.tanh((t_rev - x) / reversal_s)

        def torque_rate(x):
            return load / reversal_s / np.cosh((t_rev - x) / reversal_s) ** 2
    elif load_profile == "sine":
        period, phase = rng_load.uniform(0.3, 0.7) * t_end, rng_load.uniform(0.0, 2.0 * math.pi)

        def torque(x):
            return load * (1.0 + 0.5 * np.sin(2.0 * math.pi * x / period + phase))

        def torque_rate(x):
            return load * 0.5 * 2.0 * math.pi / period * np.cos(2.0 * math.pi * x / period + phase)
    elif load_profile == "windup":
        # a constant load (gravity, a brake) plus the friction of the drive's output bearing,
        # which the torque sensor sees: the transmitted torque steps by ±T_f with the direction
        friction_share = rng_load.uniform(0.1, 0.3)

        def torque(x):
            return load * (1.0 - friction_share * np.tanh((t_rev - x) / reversal_s))

        def torque_rate(x):
            return load * friction_share / reversal_s / np.cosh((t_rev - x) / reversal_s) ** 2
    elif load_profile == "ramp":
        def torque(x):
            return load * (2.0 * np.asarray(x) / t_end - 1.0)

        def torque_rate(x):
            return np.full_like(np.asarray(x, dtype=float), 2.0 * load / t_end)
    else:
        raise ValueError(f"unknown load profile {load_profile!r}")

    true_T = torque(t)
    twist = simulate_body(params, [0.0, t_rev, t_end], torque, torque_rate, t) \
        + backlash_angle(true_T, params["backlash"])
    ke = ke_angle(wg, ratio, params["kinematic_error"])
    clean_out = params["offset_rad"] + nominal_out + twist + ke
    rng = _rng(seed, "noise")
    out = _measure_angle(clean_out, rng, noise_rad, quant_rad)
    wg_meas = _measure_angle(wg + params["wg_offset_rad"], rng, 0.0, wg_quant_rad)
    measured_T = true_T + (rng.normal(0.0, noise_Nm, t.shape) if noise_Nm > 0 else 0.0)
    columns = {"time_s": t, "wg_angle_rad": wg_meas, "output_angle_rad": out,
               "torque_Nm": measured_T}
    truth = {
        "test": "kinematic_error", "seed": int(seed),
        "hidden": sorted(hidden), "baseline": sorted(baseline), "families": sorted(present),
        "meta": {"test": "kinematic_error", "ratio": repr(float(ratio)),
                 "rated_torque_Nm": repr(float(rated_torque_Nm))},
        "params": params,
        "measurement": {"noise_rad": noise_rad, "quant_rad": quant_rad,
                        "wg_quant_rad": wg_quant_rad, "noise_Nm": noise_Nm},
        "profile": {"revolution_s": revolution_s, "reversal_s": reversal_s, "t_rev": t_rev},
        "clean": {"torque_Nm": true_T, "wg_angle_rad": wg, "output_angle_rad": clean_out,
                  "ke_rad": ke, "twist_rad": twist},
    }
    return columns, truth


# --------------------------------------------------------------------------- files




def write_hdf5(path, columns: dict, meta: dict) -> Path:
    """Write the contract's HDF5 form: one dataset per column, ``#`` keys as attributes."""
    import h5py

    path = Path(path)
    with h5py.File(path, "w") as handle:
        for key, value in meta.items():
            handle.attrs[key] = str(value)
        for name, values in columns.items():
            handle.create_dataset(name, data=np.asarray(values, dtype=float))
    return path


def write_examples(folder) -> list[Path]:
    """(Re)write the small example files of ``tests/data`` (about 80 kB in all).

    ``stiffness_example.csv``/``.h5``: 300 rows, friction + hardening, seed 7, one
    loading rate. ``ke_example.csv``: the first 400 rows (2 s, ~10 wave-generator
    revolutions) of a kinematic-error test with KE, seed 7. ``foreign_bench.csv``: the
    first 200 stiffness rows under another bench's names (``t``, ``T_out``, ``pos`` in
    degrees, plus ``temp_C``), read with ``time_s=t,torque_Nm=T_out,angle_deg=pos``.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    cols, tr = make_stiffness_data({"friction"}, {"hardening"}, seed=7, n_rows=300,
                                   quarter_s=(1.0,))
    written = [write_csv(folder / "stiffness_example.csv", cols, tr["meta"]),
               write_hdf5(folder / "stiffness_example.h5", cols, tr["meta"])]
    n = 200
    foreign = {"t": cols["time_s"][:n], "T_out": cols["torque_Nm"][:n],
               "pos": np.degrees(cols["angle_rad"][:n]), "temp_C": np.full(n, 21.5)}
    written.append(write_csv(folder / "foreign_bench.csv", foreign,
                             {"test": "stiffness", "bench": "another lab, angles in degrees"}))
    cols, tr = make_ke_data({"kinematic_error"}, set(), seed=7)
    head = {name: values[:400] for name, values in cols.items()}
    written.append(write_csv(folder / "ke_example.csv", head, tr["meta"]))
    return written


# --------------------------------------------------------------------------- signatures


def angle_at_torque_crossings(torque, angle, direction: int = +1, band: float | None = None):
    """Angles [rad] where ``torque`` passes through zero rising (+1) or falling (-1).

    A passage counts only when the torque goes from below ``-band`` to above ``+band``
    (or back), so sensor noise around a rest at zero torque gives no false crossings.
    The angle at zero torque is a straight-line fit of angle on torque over the samples
    of the passage (``|T| <= band`` plus one sample each side), which averages the noise.

    Parameters
    ----------
    torque, angle : array_like
        Samples [N·m] and [rad].
    direction : int
        +1 for rising (loading towards +T), -1 for falling passages.
    band : float, optional
        Half-width [N·m] of the band; default 1 % of ``max |torque|``.
    """
    torque = np.asarray(torque, dtype=float)
    angle = np.asarray(angle, dtype=float)
    band = 0.01 * np.max(np.abs(torque)) if band is None else band
    side = np.where(torque > band, 1, np.where(torque < -band, -1, 0))
    outside = np.flatnonzero(side)
    passes = np.flatnonzero(side[outside][1:] != side[outside][:-1])
    found = []
    for p in passes:
        a, b = outside[p], outside[p + 1]
        if side[b] != np.sign(direction):
            continue
        slope, at_zero = np.polyfit(torque[a:b + 1], angle[a:b + 1], 1)
        found.append(at_zero)
    return np.array(found)


def loop_width_at_zero_torque(torque, angle, band: float | None = None) -> float:
    """Mean falling-passage minus mean rising-passage angle at zero torque [rad].

    For a hysteresis loop traversed counter-clockwise in (angle, torque) this is the
    loop's width at zero torque: the "hysteresis loss" reading of the catalog.
    """
    up = angle_at_torque_crossings(torque, angle, +1, band)
    down = angle_at_torque_crossings(torque, angle, -1, band)
    return float(np.mean(down) - np.mean(up))
