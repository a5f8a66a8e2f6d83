"""The laws of the truth zoo (``tests/truth_zoo.py``): springs, gaps, friction, damping, KE.

Test support; imports nothing from ``hdsim`` (numpy/scipy only) and shares no code with
it. Every law is written here from its textbook statement; the module docstring of
``tests/truth_zoo.py`` states the laws and ranges, this module implements them. Angles
are in [rad], torques in [N·m], times in [s].

Each friction law is *path-exact* over a monotone twist step: ``path(state, th0, th1, h,
d)`` returns the friction torque after the twist moved monotonically (direction ``d``)
from ``th0`` to ``th1`` in ``h`` seconds, and the new state, without changing ``state``.
The body integrator (:func:`simulate_body`) solves the torque balance for the twist at
the end of each step with a bracketing root finder, so a law with a stick band
(Coulomb) or a kink (piecewise spring) needs no smoothing.
"""

from __future__ import annotations

import bisect
import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

ARCMIN = math.pi / 10800.0  # [rad]
ARCSEC = math.pi / 648000.0  # [rad]


# --------------------------------------------------------------------------- springs


class Spring:
    """Odd elastic law of the flexspline body: ``torque(th)`` [N·m], ``tangent(th)`` [N·m/rad]."""

    form = "linear"

    def __init__(self, k1: float):
        self.k1 = float(k1)

    def torque(self, th: float) -> float:
        return self.k1 * th

    def tangent(self, th: float) -> float:
        return self.k1

    def params(self) -> dict:
        return {"form": self.form, "k1": self.k1}


class Cubic(Spring):
    """``F = k1 th + k3 th**3``."""

    form = "cubic"

    def __init__(self, k1, k3):
        super().__init__(k1)
        self.k3 = float(k3)

    def torque(self, th):
        return self.k1 * th + self.k3 * th * th * th

    def tangent(self, th):
        return self.k1 + 3.0 * self.k3 * th * th

    def params(self):
        return {"form": self.form, "k1": self.k1, "k3": self.k3}


class Sinh(Spring):
    """``F = (k1/a) sinh(a th)``."""

    form = "sinh"

    def __init__(self, k1, a):
        super().__init__(k1)
        self.a = float(a)

    def torque(self, th):
        return self.k1 / self.a * math.sinh(self.a * th)

    def tangent(self, th):
        return self.k1 * math.cosh(self.a * th)

    def params(self):
        return {"form": self.form, "k1": self.k1, "a": self.a}


class Piecewise(Spring):
    """Odd piecewise-linear law: stiffness ``k1*m[i]`` between kink torques ``kinks[i-1], kinks[i]``."""

    form = "piecewise"

    def __init__(self, k1, kinks, mult):
        super().__init__(k1)
        self.kinks = [float(x) for x in kinks]  # [N·m], increasing, > 0
        self.slopes = [k1 * float(m) for m in mult]  # one more than kinks
        th, T, self.th_kinks = 0.0, 0.0, []
        for kink, k in zip(self.kinks, self.slopes):
            th += (kink - T) / k
            T = kink
            self.th_kinks.append(th)

    def torque(self, th):
        x = abs(th)
        i = bisect.bisect_right(self.th_kinks, x)
        t0, T0 = (self.th_kinks[i - 1], self.kinks[i - 1]) if i else (0.0, 0.0)
        return math.copysign(T0 + self.slopes[i] * (x - t0), th)

    def tangent(self, th):
        return self.slopes[bisect.bisect_right(self.th_kinks, abs(th))]

    def params(self):
        return {"form": self.form, "k1": self.k1, "kinks_Nm": self.kinks, "slopes": self.slopes,
                "twist_kinks_rad": self.th_kinks}


class Exponential(Spring):
    """Tangent stiffness saturating with torque: ``k(T) = K - (K - k1) exp(-|T|/T0)``.

    Compliance in closed form: ``th(T) = sign(T)/K * (|T| + T0 ln((K - D e^(-|T|/T0))/k1))``,
    ``D = K - k1``; the spring torque ``F(th)`` is its inverse, read from a dense table.
    """

    form = "exponential"

    def __init__(self, k1, K, T0, t_max):
        super().__init__(k1)
        self.K, self.T0 = float(K), float(T0)
        T = np.linspace(0.0, t_max, 20001)
        self._T, self._th = T, self.twist(T)

    def twist(self, T):
        T = np.asarray(T, dtype=float)
        x = np.abs(T)
        D = self.K - self.k1
        return np.sign(T) / self.K * (x + self.T0 * np.log((self.K - D * np.exp(-x / self.T0)) / self.k1))

    def torque(self, th):
        x = abs(th)
        if x >= self._th[-1]:  # beyond the table: the asymptotic stiffness K
            return math.copysign(self._T[-1] + self.K * (x - self._th[-1]), th)
        return math.copysign(float(np.interp(x, self._th, self._T)), th)

    def tangent(self, th):
        return self.K - (self.K - self.k1) * math.exp(-abs(self.torque(th)) / self.T0)

    def params(self):
        return {"form": self.form, "k1": self.k1, "K_inf": self.K, "T0_Nm": self.T0}


def draw_spring(form: str | None, rng, k1: float, rated: float, size: float = 1.0) -> Spring:
    """A hardening law whose twist at ``rated`` torque is ``(1 - h)`` of the linear ``rated/k1``.

    ``h = U(0.20, 0.40) * size`` (capped at 0.6). ``None`` gives the linear spring.
    """
    if form is None:
        return Spring(k1)
    h = min(rng.uniform(0.20, 0.40) * size, 0.6)
    th_n = (1.0 - h) * rated / k1  # twist at rated torque [rad]
    if form == "cubic":
        return Cubic(k1, (rated - k1 * th_n) / th_n**3)
    if form == "sinh":
        x = brentq(lambda x: math.sinh(x) / x - 1.0 / (1.0 - h), 1e-6, 30.0)
        return Sinh(k1, x / th_n)
    if form == "piecewise":
        kinks = rated * np.array([rng.uniform(0.08, 0.20), rng.uniform(0.30, 0.50), rng.uniform(0.60, 0.80)])
        steps = np.cumsum(rng.uniform(0.5, 1.5, 3))  # stiffness rises at every kink

        def piecewise_twist(s):
            return Piecewise(k1, kinks, np.concatenate(([1.0], 1.0 + s * steps))).th_kinks[-1] + \
                (rated - kinks[-1]) / (k1 * (1.0 + s * steps[-1]))

        s = brentq(lambda s: piecewise_twist(s) - th_n, 0.0, 50.0)
        return Piecewise(k1, kinks, np.concatenate(([1.0], 1.0 + s * steps)))
    if form == "exponential":
        T0 = rated * rng.uniform(0.15, 0.40)
        probe = Exponential(k1, 2.0 * k1, T0, 1.0)

        def exponential_twist(K):
            probe.K = K
            return float(probe.twist(rated))

        K = brentq(lambda K: exponential_twist(K) - th_n, k1 * (1.0 + 1e-9), 200.0 * k1)
        return Exponential(k1, K, T0, 4.0 * rated)
    raise ValueError(f"unknown hardening form {form!r}")


# --------------------------------------------------------------------------- gaps


def draw_gap(form: str, rng, k1: float, rated: float, size: float = 1.0) -> dict:
    """Parameters of a series dead zone of total width ``b = U(0.3, 1.5) arcmin * size``."""
    b = rng.uniform(0.3, 1.5) * ARCMIN * size
    if form == "hard_gap":
        return {"form": form, "b_rad": b, "contact_compliance": rng.uniform(0.03, 0.10) / k1}
    if form == "smooth_gap":
        return {"form": form, "b_rad": b, "T_b": rated * rng.uniform(0.001, 0.005)}
    if form == "asymmetric_gap":
        w = rng.uniform(0.25, 0.40)
        return {"form": form, "b_rad": b, "b_pos": b * w, "b_neg": b * (1.0 - w),
                "T_pos": rated * rng.uniform(0.001, 0.004), "T_neg": rated * rng.uniform(0.006, 0.015),
                "flank_compliance_neg": rng.uniform(0.02, 0.06) / k1}
    if form == "closing_gap":
        return {"form": form, "b_rad": b, "T_c": rated * rng.uniform(0.02, 0.06)}
    raise ValueError(f"unknown backlash form {form!r}")


def gap_angle(T, gap: dict | None) -> np.ndarray:
    """Angle [rad] of the series dead zone at torque ``T`` [N·m] (quasi-static, no own dynamics)."""
    T = np.asarray(T, dtype=float)
    if not gap:
        return np.zeros_like(T)
    form, b = gap["form"], gap["b_rad"]
    if form == "hard_gap":  # rigid flanks plus a linear contact compliance
        return 0.5 * b * np.sign(T) + T * gap["contact_compliance"]
    if form == "smooth_gap":
        return 0.5 * b * T / np.sqrt(T * T + gap["T_b"] ** 2)
    if form == "asymmetric_gap":
        pos = gap["b_pos"] * T / np.sqrt(T * T + gap["T_pos"] ** 2)
        neg = gap["b_neg"] * T / np.sqrt(T * T + gap["T_neg"] ** 2) + T * gap["flank_compliance_neg"]
        return np.where(T >= 0.0, pos, neg)
    if form == "closing_gap":  # odd smoothstep: closes linearly-then-softly over |T| < T_c
        x = np.clip(T / gap["T_c"], -1.0, 1.0)
        return 0.5 * b * x * (3.0 - x * x) / 2.0
    raise ValueError(f"unknown backlash form {form!r}")


# --------------------------------------------------------------------------- friction


class BoucWen:
    """``dz/dth = A - |z|**n (beta sign(z dth) + gamma)``, torque ``z``; saturates at ``+-z_u``.

    Path-exact through a reference trajectory: the law is autonomous in the twist, so a
    step is a shift along the trajectory ``Z(s)`` from ``-z_u`` to ``+z_u`` (tabulated
    once with ``solve_ivp``, rtol 1e-10); the descending branch is its mirror image.
    """

    form = "bouc_wen"
    arrangement = "parallel"

    def __init__(self, z_u, A, n, beta, gamma):
        self.z_u, self.A, self.n, self.beta, self.gamma = map(float, (z_u, A, n, beta, gamma))

        def f(s, z):
            return [A - abs(z[0]) ** n * (beta * math.copysign(1.0, z[0]) + gamma)]

        end = lambda s, z: z[0] - z_u * (1.0 - 1e-9)  # noqa: E731
        end.terminal = True
        span = 200.0 * z_u / A
        sol = solve_ivp(f, (0.0, span), [-z_u], method="LSODA", rtol=1e-10, atol=1e-12 * z_u,
                        events=end, dense_output=True)
        s_end = sol.t[-1]
        s = np.concatenate((np.linspace(0.0, 0.2 * s_end, 8000), np.linspace(0.2 * s_end, s_end, 8001)[1:]))
        z = np.maximum.accumulate(sol.sol(s)[0])
        keep = np.concatenate(([True], np.diff(z) > 0))
        self._s, self._z = s[keep], z[keep]

    def initial(self):
        return 0.0

    def torque(self, state):
        return state

    def path(self, z, th0, th1, h, d):
        if d == 0 or th1 == th0:
            return z, z
        zz = z if d > 0 else -z
        s0 = float(np.interp(zz, self._z, self._s))
        z1 = float(np.interp(s0 + abs(th1 - th0), self._s, self._z, right=self._z[-1]))
        z1 = z1 if d > 0 else -z1
        return z1, z1

    def params(self):
        return {"form": self.form, "z_u": self.z_u, "A": self.A, "n": self.n, "beta": self.beta,
                "gamma": self.gamma}


class LuGre:
    """LuGre (Canudas de Wit et al. 1995), no viscous term (that is the damping family).

    ``dz/dt = v - sigma0 |v| z / g(v)``, ``g(v) = Fc + (Fs - Fc) exp(-(v/vs)**2)``,
    torque ``sigma0 z + sigma1 dz/dt``. Over a step the rate is the step's mean twist rate,
    and ``z`` follows the exact solution for constant ``g``.
    """

    form = "lugre"
    arrangement = "parallel"

    def __init__(self, sigma0, sigma1, Fc, Fs, vs):
        self.sigma0, self.sigma1, self.Fc, self.Fs, self.vs = map(float, (sigma0, sigma1, Fc, Fs, vs))

    def initial(self):
        return 0.0

    def torque(self, z):
        return self.sigma0 * z

    def path(self, z, th0, th1, h, d):
        if d == 0 or th1 == th0:
            return self.sigma0 * z, z
        dth = abs(th1 - th0)
        v = dth / h
        g = self.Fc + (self.Fs - self.Fc) * math.exp(-((v / self.vs) ** 2))
        zs = d * g / self.sigma0
        z1 = zs + (z - zs) * math.exp(-self.sigma0 * dth / g)
        return self.sigma0 * z1 + self.sigma1 * (z1 - z) / h, z1

    def params(self):
        return {"form": self.form, "sigma0": self.sigma0, "sigma1": self.sigma1, "Fc": self.Fc,
                "Fs": self.Fs, "vs": self.vs}


class GenMaxwellSlip:
    """Generalised Maxwell-slip (Al-Bender, Lampaert & Swevers 2005), no viscous term.

    Element ``i`` sticks (``dF_i/dt = k_i v``) until ``|F_i|`` reaches ``alpha_i s(v)``,
    ``s(v) = Fc + (Fs - Fc) exp(-(v/vs)**2)``; it then slips, ``F_i`` relaxing towards
    ``sign(v) alpha_i s(v)`` with time constant ``tau_att``, until the twist reverses,
    when every element sticks again. Torque ``sum F_i``.
    """

    form = "gen_maxwell_slip"
    arrangement = "parallel"

    def __init__(self, k, alpha, Fc, Fs, vs, tau_att):
        self.k, self.alpha = np.asarray(k, float), np.asarray(alpha, float)
        self.Fc, self.Fs, self.vs, self.tau = map(float, (Fc, Fs, vs, tau_att))

    def initial(self):
        return (np.zeros_like(self.k), np.ones(self.k.size, bool), 0)

    def torque(self, state):
        return float(state[0].sum())

    def path(self, state, th0, th1, h, d):
        F, stick, last = state
        if d == 0 or th1 == th0:
            return float(F.sum()), (F, np.ones_like(stick), last)
        if d != last:
            stick = np.ones_like(stick)  # a reversal: every element sticks again
        dth = abs(th1 - th0)
        s = self.Fc + (self.Fs - self.Fc) * math.exp(-((dth / h / self.vs) ** 2))
        lim = self.alpha * s
        trial = F + d * self.k * dth
        breaks = stick & (d * trial >= lim)
        relax = d * lim + (F - d * lim) * math.exp(-h / self.tau)
        F1 = np.where(stick, np.where(breaks, d * lim, trial), relax)
        return float(F1.sum()), (F1, stick & ~breaks, d)

    def params(self):
        return {"form": self.form, "k": self.k.tolist(), "alpha": self.alpha.tolist(), "Fc": self.Fc,
                "Fs": self.Fs, "vs": self.vs, "tau_att": self.tau}


class Preisach:
    """Preisach hysteresis: a series slip twist driven by the torque through the body.

    Relays ``(a >= b)`` in torque switch up at ``a`` and down at ``b``; density
    ``mu ~ N(u_i; 0, sig_i) * LogNormal(u_c; ln c_med, s_c)`` in the interaction
    ``u_i = (a+b)/2`` and coercive ``u_c = (a-b)/2`` coordinates (not a function of
    ``a - b`` alone, so not a Prandtl-Ishlinskii / Maxwell-slip law). The slip twist is
    ``scale (2 S+ - 1)``, ``S+`` the share of relays up, from the Everett function
    (tabulated, bilinear) and the stack of dominant extrema with the wiping-out rule
    (Mayergoyz 1991). Torque is the input and twist the output, so the loop is
    dissipative (a relay loop runs counter-clockwise in its input-output plane); as a
    torque of the twist it would give energy back. Starts demagnetised (a decaying
    alternating pre-history). ``scale`` makes the saturated loop ``W`` wide at zero torque.
    """

    form = "preisach"
    arrangement = "series"

    def __init__(self, W, sig_i, c_med, s_c, grid=241):
        self.W, self.sig_i, self.c_med, self.s_c = map(float, (W, sig_i, c_med, s_c))
        L = 4.0 * sig_i + c_med * math.exp(3.0 * s_c)
        x = np.linspace(-L, L, grid)
        a, b = np.meshgrid(x, x, indexing="ij")
        ui, uc = 0.5 * (a + b), 0.5 * (a - b)
        with np.errstate(divide="ignore", invalid="ignore"):
            mu = np.exp(-0.5 * (ui / sig_i) ** 2) * np.exp(-0.5 * (np.log(uc / c_med) / s_c) ** 2) / uc
        mu = np.where(a > b, np.nan_to_num(mu), 0.0)
        E = np.cumsum(mu, axis=0)[:, ::-1].cumsum(axis=1)[:, ::-1]  # sum over a' <= a, b' >= b
        self.L, self.dx, self.n = L, x[1] - x[0], grid
        self._E = E / E[-1, 0]
        # down from saturation to zero torque the output is 1 - 2 E(L, 0): the half-width
        self.scale = 0.5 * W / (1.0 - 2.0 * self._everett(L, 0.0))

    def _everett(self, a, b):
        if a <= b:
            return 0.0
        L, n = self.L, self.n
        x = (min(max(a, -L), L) + L) / self.dx
        y = (min(max(b, -L), L) + L) / self.dx
        i, j = min(int(x), n - 2), min(int(y), n - 2)
        fx, fy = x - i, y - j
        E = self._E
        return ((1 - fx) * ((1 - fy) * E[i, j] + fy * E[i, j + 1])
                + fx * ((1 - fy) * E[i + 1, j] + fy * E[i + 1, j + 1]))

    def _output(self, ext, u):
        area, m_prev = 0.0, -self.L
        k = len(ext)
        for p in range(0, k - 1, 2):  # completed (max, min) pairs
            M, m = ext[p], ext[p + 1]
            area += self._everett(M, m_prev) - self._everett(M, m)
            m_prev = m
        if k % 2 == 0:  # rising from the last min
            area += self._everett(u, m_prev)
        else:  # falling from the last max
            area += self._everett(ext[-1], m_prev) - self._everett(ext[-1], u)
        return self.scale * (2.0 * area - 1.0)

    def series(self, T) -> np.ndarray:
        """Slip twist [rad] along the torque sequence ``T`` [N·m] (its turning points included)."""
        u0 = 1.5 * self.L
        ext = [u0 * 0.8**i * (1 if i % 2 == 0 else -1) for i in range(40)]
        u = 0.0
        out = np.empty(len(T))
        for n, x in enumerate(np.asarray(T, dtype=float)):
            x = float(x)
            if x != u:
                rising = len(ext) % 2 == 0
                if (x > u) != rising:
                    ext.append(u)  # the turning point becomes a minimum (or a maximum)
                if x > u:  # wipe out every (max, min) pair the input now exceeds
                    while len(ext) >= 2 and x >= ext[-2]:
                        del ext[-2:]
                else:
                    while len(ext) >= 3 and x <= ext[-2]:
                        del ext[-2:]
                u = x
            out[n] = self._output(ext, u)
        return out

    def params(self):
        return {"form": self.form, "W": self.W, "sig_i": self.sig_i, "c_med": self.c_med, "s_c": self.s_c,
                "scale": self.scale}


class CoulombViscous:
    """Coulomb plus viscous: ``Fc sign(v) + c_v v``; sticks while ``|T - F(th) - ...| <= Fc``."""

    form = "coulomb_viscous"
    arrangement = "parallel"

    def __init__(self, Fc, c_v):
        self.Fc, self.c_v = float(Fc), float(c_v)

    def initial(self):
        return 0.0

    def torque(self, state):
        return state

    def path(self, state, th0, th1, h, d):
        if d == 0:  # stuck: the torque is whatever balances; keep the last one (in the band)
            return state, state
        f = d * self.Fc + self.c_v * (th1 - th0) / h
        return f, d * self.Fc

    def params(self):
        return {"form": self.form, "Fc": self.Fc, "c_v": self.c_v}


def draw_friction(form: str, rng, k1: float, rated: float, size: float = 1.0):
    """A friction law sized by its nominal zero-torque loop width ``W = U(0.5, 1.5) arcmin * size``.

    The saturated friction torque is ``W k1 / 2`` [N·m] (``Fc``, ``z_u``, ``M``).
    """
    W = rng.uniform(0.5, 1.5) * ARCMIN * size
    Fc = W * k1 / 2.0
    if form == "bouc_wen":
        n = rng.uniform(1.5, 3.0)
        A = k1 * rng.uniform(1.5, 4.0)
        share = rng.uniform(0.55, 0.9)
        total = A / Fc**n
        law = BoucWen(Fc, A, n, share * total, (1.0 - share) * total)
    elif form == "lugre":
        sigma0 = k1 * rng.uniform(1.5, 4.0)
        law = LuGre(sigma0, sigma0 * rng.uniform(5e-5, 2e-4), Fc, Fc * rng.uniform(1.1, 1.4),
                    rng.uniform(5e-5, 2e-4))
    elif form == "gen_maxwell_slip":
        m = int(rng.integers(4, 9))
        alpha = rng.dirichlet(np.full(m, 2.0))
        delta = W * np.exp(rng.uniform(math.log(0.05), math.log(0.6), m))  # break-away twists
        law = GenMaxwellSlip(alpha * Fc / delta, alpha, Fc, Fc * rng.uniform(1.05, 1.3),
                             rng.uniform(5e-5, 2e-4), rng.uniform(1e-3, 5e-3))
    elif form == "preisach":  # thresholds in torque: a series slip, see Preisach
        law = Preisach(W, rated * rng.uniform(0.03, 0.10), rated * rng.uniform(0.08, 0.20),
                       rng.uniform(0.3, 0.6))
    elif form == "coulomb_viscous":
        ratio = rng.uniform(0.02, 0.05)  # viscous share of the loop width at 1 T_N/s
        law = CoulombViscous(Fc, ratio * k1 * Fc / rated)
    else:
        raise ValueError(f"unknown friction form {form!r}")
    law.width_rad = W
    return law


# --------------------------------------------------------------------------- damping


class Damping:
    """Rate-dependent loss: a dashpot ``coefficient(T, th, spring)`` [N·m·s/rad] plus Maxwell arms."""

    def __init__(self, form, tau_c, k1, **kw):
        self.form, self.tau_c, self.k1 = form, float(tau_c), float(k1)
        self.kw = kw
        self.arm_k = np.asarray(kw.get("arm_k", []), float)
        self.arm_tau = np.asarray(kw.get("arm_tau", []), float)

    def coefficient(self, T, th, spring) -> float:
        if self.form == "kelvin_voigt":  # constant damping ratio: c ~ sqrt(tangent stiffness)
            return self.tau_c * math.sqrt(self.k1 * spring.tangent(th))
        if self.form == "load_dependent":
            return self.tau_c * self.k1 * (1.0 + self.kw["q"] * (abs(T) / self.kw["rated"]) ** self.kw["p"])
        return 0.0

    def params(self):
        out = {"form": self.form, "tau_c": self.tau_c, "c0": self.tau_c * self.k1}
        out.update({k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.kw.items()})
        return out


def draw_damping(form: str, rng, k1: float, rated: float, size: float = 1.0) -> Damping:
    """Damping whose zero-load, low-frequency coefficient is ``k1 * tau_c``, ``tau_c = U(0.008, 0.020) s * size``."""
    tau_c = rng.uniform(0.008, 0.020) * size
    if form == "kelvin_voigt":
        return Damping(form, tau_c, k1)
    if form == "load_dependent":
        return Damping(form, tau_c * 0.6, k1, q=rng.uniform(1.0, 3.0), p=rng.uniform(1.0, 2.0), rated=rated)
    if form == "frequency_dependent":
        tau = np.array([rng.uniform(0.01, 0.04), rng.uniform(0.1, 0.4)])  # [s]
        share = rng.uniform(0.5, 0.8)
        c = tau_c * k1 * np.array([share, 1.0 - share])
        return Damping(form, tau_c, k1, arm_k=c / tau, arm_tau=tau)
    raise ValueError(f"unknown damping form {form!r}")


# --------------------------------------------------------------------------- kinematic error


def draw_ke(rng, size: float = 1.0) -> dict:
    """Harmonics at 1x, 2x, 4x WG and 1x output, plus small 3x, 6x, 8x WG terms (amplitudes [rad])."""
    e2 = rng.uniform(10, 30) * ARCSEC * size
    out = {"e1": rng.uniform(3, 10) * ARCSEC * size, "e2": e2, "e4": rng.uniform(2, 6) * ARCSEC * size,
           "eo": rng.uniform(10, 30) * ARCSEC * size}
    out.update({f"x{m}": rng.uniform(0.03, 0.12) * e2 for m in (3, 6, 8)})
    out.update({f"p{m}": rng.uniform(0.0, 2.0 * math.pi) for m in ("1", "2", "4", "o", "x3", "x6", "x8")})
    return out


def ke_angle(phi, ratio: float, ke: dict | None) -> np.ndarray:
    """Kinematic error [rad] at wave-generator angle ``phi`` [rad]."""
    phi = np.asarray(phi, dtype=float)
    if not ke:
        return np.zeros_like(phi)
    out = (ke["e1"] * np.sin(phi + ke["p1"]) + ke["e2"] * np.sin(2 * phi + ke["p2"])
           + ke["e4"] * np.sin(4 * phi + ke["p4"]) + ke["eo"] * np.sin(phi / ratio + ke["po"]))
    for m in (3, 6, 8):
        out = out + ke[f"x{m}"] * np.sin(m * phi + ke[f"px{m}"])
    return out


# --------------------------------------------------------------------------- body integrator


def simulate_body(spring: Spring, friction, damping: Damping | None, t_steps, T_steps) -> np.ndarray:
    """Twist [rad] of the body at the step times ``t_steps`` under the torque ``T_steps`` [N·m].

    Torque balance ``T = F(th) + H + c (th - th_n)/h + sum v_j`` at the end of every step,
    the dashpot implicit (exact for a torque ramp once its transient has decayed), the
    Maxwell arms ``dv_j/dt = k_j dth/dt - v_j/tau_j`` integrated exactly for a twist
    linear in the step, the friction torque ``H`` path-exact. The balance is monotone in
    the twist, so the root is bracketed and found with ``brentq`` (xtol 1e-13 rad); when
    the torque lies inside a stick band (Coulomb) the twist stays. A series friction law
    (Preisach) adds its slip twist, driven by the same torque.
    """
    t = np.asarray(t_steps, dtype=float)
    T = np.asarray(T_steps, dtype=float)
    if friction is not None and friction.arrangement == "series":  # the same torque runs through it
        return simulate_body(spring, None, damping, t, T) + friction.series(T)
    if friction is None and damping is None and spring.form == "linear":
        return T / spring.k1  # nothing to integrate: the closed form
    out = np.empty(t.size)
    th = 0.0
    state = friction.initial() if friction else None
    arms_k = damping.arm_k if damping is not None else np.zeros(0)
    arms_tau = damping.arm_tau if damping is not None else np.ones(0)
    v = np.zeros(arms_k.size)
    out[0] = th
    for n in range(1, t.size):
        h, T1 = t[n] - t[n - 1], T[n]
        c = damping.coefficient(T1, th, spring) / h if damping is not None else 0.0
        a = np.exp(-h / arms_tau)
        gain = arms_k * arms_tau * (1.0 - a) / h  # arm torque per unit twist of the step
        v_rest = float((v * a).sum())
        g_sum = float(gain.sum())
        th0 = th

        def resid(x, d):
            f = friction.path(state, th0, x, h, d)[0] if friction else 0.0
            return spring.torque(x) + f + c * (x - th0) + v_rest + g_sum * (x - th0) - T1

        r_up, r_down = resid(th0, 1), resid(th0, -1)
        if r_up < 0.0:
            d = 1
        elif r_down > 0.0:
            d = -1
        else:
            d = 0
        if d:
            r0 = r_up if d > 0 else r_down
            step = abs(r0) / (spring.tangent(th0) + c + g_sum)
            hi = th0 + d * step * 1.01 + d * 1e-15
            while d * resid(hi, d) < 0.0:
                step *= 2.0
                hi = th0 + d * step
            lo, hi = (th0, hi) if d > 0 else (hi, th0)
            th = brentq(resid, lo, hi, args=(d,), xtol=1e-13, rtol=1e-12)
        if friction:
            state = friction.path(state, th0, th, h, d)[1]
        v = v * a + gain * (th - th0)
        out[n] = th
    return out
