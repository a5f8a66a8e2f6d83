"""Wave generator driven: the drive in motion (set-up ``driven_wave_generator``).

The bench (or robot joint)::

    motor + WG (J_in) ─[WG-shaft friction T_f(ω_w, θ_w)]─ WG ═ mesh ═ flexspline (elastic path)
        ─ output + load (J_out + J_load) ─ load torque T_L(t)

Coordinates: WG angle ``θ_w``, output angle ``θ_o`` [rad]. The output is carried as its
**deviation** ``q = θ_o − θ_w/N`` (the contract's kinematic error, ``contracts.md`` §1):
it is arcseconds where θ_o is revolutions, so the solver's tolerances act on the
quantity the metrics read, not on a large angle.

The kinematic error ``e(θ_w, θ_o, T_L/T_N)`` of the model's ``kinematic_error`` slot is a
displacement source in the mesh; the elastic path (`hdsim.simulation.path.ElasticPath`,
with backlash, hardening, damping and series/parallel friction states) sees the twist::

    δ = q − e,   δ̇ = q̇ − e_w ω_w − e_o ω_o − e_f ḟ        (e_x = ∂e/∂x, f = T_L/T_N)

and carries the torque ``τ = τ(δ, δ̇, z)``. Its generalised forces follow from virtual
work (the path stores V(δ)): ``−τ (1 − e_o)`` on the output and ``+τ (1/N + e_w)`` on the
WG shaft, so a conservative drive conserves energy exactly, kinematic error
included (the ``e_w``, ``e_o`` terms are the instantaneous ratio ripple; the brief
``−τ``, ``+τ/N`` is their e = 0 limit)::

    (J_out + J_load) ω̇_o = T_L(t) − τ (1 − e_o)
    J_in ω̇_w             = T_m − T_f(ω_w, θ_w) + τ (1/N + e_w)

Efficiency under load (mesh losses growing with torque) is not modelled; the WG
shaft friction (`hdsim.model.input_friction`) is the only input-side loss. The
load-dependence of the kinematic error follows the *applied* load ``T_L(t)`` (known
in time, equal to the drive torque at steady state), which avoids an algebraic loop
between τ and e.

Input modes (``[input] mode``):

``prescribed``
    The motor follows the profile exactly (an ideally stiff servo): θ_w(t), ω_w(t),
    α_w(t) are known functions, not states. Chosen over a very stiff coupling because
    it is exact and adds no artificial fast mode; the motor torque that the profile
    needs (inverse dynamics, friction included) is an output signal.
    States: ``deviation``, ``deviation_rate``, friction states.
``pi``
    Motor torque from a PI loop on the WG speed, ``T_m = k_p (ω_ref − ω_w) + k_i ∫(ω_ref − ω_w)
    + J_ff α_ref``. States: ``theta_wg``, ``omega_wg``, ``deviation``, ``deviation_rate``,
    ``speed_error_integral``, friction states.
``torque`` (API only)
    Motor torque a given function of time (free vibration, breakaway tests).

All memory (friction, hysteresis, the PI integrator, optional work integrals) is ODE
state. SI inside; rpm, degrees and arcsec only in scenario files and metric names.
"""

from __future__ import annotations

import bisect
import csv
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from hdsim.scenarios import ke_metrics
from hdsim.simulation.path import ElasticPath, ODESystem
from hdsim.errors import InputError, unknown_name
from hdsim.model.input_friction import NO_INPUT_FRICTION, InputFriction, for_unit
from hdsim.model.drive import HarmonicDrive
from hdsim.scenarios.scenario import Scenario
from hdsim.simulation.solver import SimulationResult, SolverOptions, integrate
from hdsim.units import arcsec_to_rad, rad_per_s_to_rpm, rad_to_arcsec, rpm_to_rad_per_s

SETUP = "driven_wave_generator"
TWO_PI = 2.0 * np.pi


# =========================================================================== motion profiles
@dataclass(frozen=True)
class Motion:
    """WG motion (prescribed, or the speed loop's reference): vectorised functions of time.

    ``windows`` names time intervals the metrics read (``forward``, ``reverse``,
    ``constant``, ``dwell``, …); ``max_speed`` [rad/s] sets the sampling.
    """

    angle: Callable
    speed: Callable
    accel: Callable
    t_end: float
    windows: dict = field(default_factory=dict)
    max_speed: float = 0.0
    description: str = ""


def _hold(t_end: float) -> Motion:
    zero = lambda t: np.zeros_like(np.asarray(t, dtype=float))  # noqa: E731
    return Motion(zero, zero, zero, float(t_end), {}, 0.0, "hold")


class SpeedKnots:
    """WG speed through knots ``(times [s], speeds [rad/s])`` with cosine or linear blends.

    Cosine blends start and end every ramp with zero acceleration; linear ones make a
    trapezoidal speed profile. The angle is integrated in closed form.
    """

    def __init__(self, times, speeds, shape: str = "cosine"):
        times = np.asarray(times, dtype=float)
        speeds = np.asarray(speeds, dtype=float)
        keep = np.concatenate([[True], np.diff(times) > 0.0])
        self.times, self.speeds, self.shape = times[keep], speeds[keep], shape
        if len(self.times) < 2:
            raise InputError("a speed profile needs at least one segment of positive duration")
        self.d = np.diff(self.times)
        a, b = self.speeds[:-1], self.speeds[1:]
        self.angles = np.concatenate([[0.0], np.cumsum(self.d * 0.5 * (a + b))])
        # plain lists for the scalar path the solver takes (numpy on scalars costs ~10x)
        self._tlist, self._dlist = self.times.tolist(), self.d.tolist()
        self._vlist, self._alist = self.speeds.tolist(), self.angles.tolist()

    def _scalar(self, t):
        i = min(max(bisect.bisect_right(self._tlist, t) - 1, 0), len(self._tlist) - 2)
        d = self._dlist[i]
        s = min(max((t - self._tlist[i]) / d, 0.0), 1.0)
        return i, s, self._vlist[i], self._vlist[i + 1], d

    def _locate(self, t):
        t = np.asarray(t, dtype=float)
        i = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 2)
        s = np.clip((t - self.times[i]) / self.d[i], 0.0, 1.0)
        return t, i, s, self.speeds[i], self.speeds[i + 1], self.d[i]

    def speed(self, t):
        """WG speed [rad/s] at ``t`` (scalar or array)."""
        if isinstance(t, float):
            i, s, a, b, d = self._scalar(t)
            return a + (b - a) * (s if self.shape == "linear" else 0.5 * (1.0 - math.cos(math.pi * s)))
        t, i, s, a, b, d = self._locate(t)
        blend = s if self.shape == "linear" else 0.5 * (1.0 - np.cos(np.pi * s))
        return a + (b - a) * blend

    def accel(self, t):
        """WG acceleration [rad/s²] at ``t`` (0 outside the knots)."""
        if isinstance(t, float):
            if t < self._tlist[0] or t > self._tlist[-1]:
                return 0.0
            i, s, a, b, d = self._scalar(t)
            return (b - a) / d if self.shape == "linear" else 0.5 * (b - a) * math.pi / d * math.sin(math.pi * s)
        t, i, s, a, b, d = self._locate(t)
        inside = (t >= self.times[0]) & (t <= self.times[-1])
        if self.shape == "linear":
            return np.where(inside, (b - a) / d, 0.0)
        return np.where(inside, 0.5 * (b - a) * np.pi / d * np.sin(np.pi * s), 0.0)

    def angle(self, t):
        """WG angle [rad] at ``t``, 0 at the first knot; the last speed holds after the last knot."""
        if isinstance(t, float):
            i, s, a, b, d = self._scalar(t)
            if self.shape == "linear":
                part = d * (a * s + 0.5 * (b - a) * s * s)
            else:
                part = d * (a * s + 0.5 * (b - a) * (s - math.sin(math.pi * s) / math.pi))
            return self._alist[i] + part + max(t - self._tlist[-1], 0.0) * self._vlist[-1]
        t, i, s, a, b, d = self._locate(t)
        if self.shape == "linear":
            part = d * (a * s + 0.5 * (b - a) * s * s)
        else:
            part = d * (a * s + 0.5 * (b - a) * (s - np.sin(np.pi * s) / np.pi))
        beyond = np.maximum(t - self.times[-1], 0.0) * self.speeds[-1]
        return self.angles[i] + part + beyond

    def motion(self, windows, description) -> Motion:
        """This profile as a `Motion` with metric ``windows``."""
        return Motion(self.angle, self.speed, self.accel, float(self.times[-1]), windows,
                      float(np.max(np.abs(self.speeds))), description)


def constant_speed_motion(speed, ratio, ramp_s, revolutions, settle_revolutions) -> Motion:
    """Ramp up, cruise ``settle + revolutions`` output turns; window ``constant`` = the last ``revolutions``."""
    cruise = (settle_revolutions + revolutions) * TWO_PI * abs(ratio) / abs(speed)
    knots = SpeedKnots([0.0, ramp_s, ramp_s + cruise], [0.0, speed, speed])
    t1 = ramp_s + cruise
    t0 = t1 - revolutions * TWO_PI * abs(ratio) / abs(speed)
    return knots.motion({"constant": (t0, t1)}, "constant speed")


def reversal_motion(speed, ratio, ramp_s, revolutions, settle_revolutions, dwell_s) -> Motion:
    """Forward and back over the same output angles; windows ``forward`` and ``reverse``.

    Ramp up, cruise, ramp down, dwell, the same reversed, dwell. Both cruises cover the
    same output angles; each window is the last ``revolutions`` of its cruise.
    """
    cruise = (settle_revolutions + revolutions) * TWO_PI * abs(ratio) / abs(speed)
    measured = revolutions * TWO_PI * abs(ratio) / abs(speed)
    steps = [ramp_s, cruise, ramp_s, dwell_s, ramp_s, cruise, ramp_s, dwell_s]
    times = np.concatenate([[0.0], np.cumsum(steps)])
    speeds = [0.0, speed, speed, 0.0, 0.0, -speed, -speed, 0.0, 0.0]
    knots = SpeedKnots(times, speeds)
    windows = {"forward": (times[2] - measured, times[2]), "reverse": (times[6] - measured, times[6])}
    return knots.motion(windows, "reversal")


def trapezoid_motion(speed, ratio, move, ramp_s, dwell_s, back: bool) -> Motion:
    """Point-to-point: trapezoidal WG speed for an output move ``move`` [rad] (triangular if short)."""
    wg_move = abs(move * ratio)
    accel = abs(speed) / ramp_s
    peak = min(abs(speed), np.sqrt(wg_move * accel))
    t_ramp = peak / accel
    t_cruise = max(wg_move - peak * t_ramp, 0.0) / peak
    sign = np.sign(move * ratio) or 1.0
    steps, speeds = [t_ramp, t_cruise, t_ramp, dwell_s], [sign * peak, sign * peak, 0.0, 0.0]
    if back:
        steps += [t_ramp, t_cruise, t_ramp, dwell_s]
        speeds += [-sign * peak, -sign * peak, 0.0, 0.0]
    times = np.concatenate([[0.0], np.cumsum(steps)])
    knots = SpeedKnots(times, [0.0] + speeds, shape="linear")
    move_end = 2.0 * t_ramp + t_cruise
    windows = {"move": (0.0, move_end), "dwell": (move_end, move_end + dwell_s)}
    if back:
        windows.update(move_back=(move_end + dwell_s, 2 * move_end + dwell_s),
                       dwell_back=(2 * move_end + dwell_s, 2 * move_end + 2 * dwell_s))
    return knots.motion(windows, "trapezoid")


def sine_motion(amplitude, frequency, cycles, dwell_s=0.0) -> Motion:
    """θ_w = A (1 − cos 2πft) over ``cycles`` cycles (starts and ends at rest), then dwell."""
    w = TWO_PI * frequency
    t_move = cycles / frequency

    def clip(t):
        return np.clip(np.asarray(t, dtype=float), 0.0, t_move)

    def inside(t):
        t = np.asarray(t, dtype=float)
        return (t >= 0.0) & (t <= t_move)

    angle = lambda t: amplitude * (1.0 - np.cos(w * clip(t)))  # noqa: E731
    speed = lambda t: np.where(inside(t), amplitude * w * np.sin(w * clip(t)), 0.0)  # noqa: E731
    accel = lambda t: np.where(inside(t), amplitude * w * w * np.cos(w * clip(t)), 0.0)  # noqa: E731
    first = 1.0 / frequency
    windows = {"oscillation": (first, first * np.floor(cycles))} if cycles >= 2 else {"oscillation": (0.0, t_move)}
    return Motion(angle, speed, accel, t_move + dwell_s, windows, abs(amplitude * w), "sine")


# ------------------------------------------------------------------ measured profile (CSV)
_ANGLE_UNITS = {"rad": 1.0, "deg": np.pi / 180.0, "arcmin": np.pi / 10800.0, "arcsec": np.pi / 648000.0}
#: columns whose cells must be numbers (others are ignored, NaN if not numeric)
_WANTED = {"time_s", "torque_Nm", "wg_speed_rpm", "wg_speed_rad_per_s"} | {f"wg_angle_{u}" for u in _ANGLE_UNITS}


def read_profile_csv(path) -> dict[str, np.ndarray]:
    """A measured input profile: ``time_s`` plus ``wg_angle_<rad|deg|arcmin|arcsec>`` or
    ``wg_speed_rpm`` / ``wg_speed_rad_per_s``; optional ``torque_Nm`` (load applied to the
    output, as in the contract's kinematic-error files, which are accepted as they are).

    ``#`` lines are skipped; other columns are ignored. Returns SI arrays
    ``time``, ``angle`` or ``speed``, and ``torque`` if present.
    """
    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except FileNotFoundError:
        raise InputError(f"{path}: profile file not found") from None
    except (UnicodeDecodeError, IsADirectoryError):
        raise InputError(f"{path}: not a text CSV file") from None
    rows = [(n + 1, line) for n, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise InputError(f"{path}: no header row")
    header = [h.strip() for h in next(csv.reader([rows[0][1]]))]
    body = rows[1:]
    if len(body) < 4:
        raise InputError(f"{path}: a profile needs at least 4 rows, found {len(body)}")
    columns = {}
    for name in header:
        columns[name] = np.empty(len(body))
    for r, (lineno, line) in enumerate(body):
        cells = next(csv.reader([line]))
        if len(cells) != len(header):
            raise InputError(f"{path}: line {lineno}: expected {len(header)} cells, found {len(cells)}")
        for name, cell in zip(header, cells):
            try:
                columns[name][r] = float(cell)
            except ValueError:
                if name in _WANTED:
                    raise InputError(f"{path}: line {lineno}, column {name}: '{cell.strip()[:30]}' is not a "
                                     "number") from None
                columns[name][r] = np.nan
    if "time_s" not in columns:
        raise InputError(f"{path}: missing column time_s (columns: {', '.join(header)})")
    out = {"time": columns["time_s"]}
    for unit, factor in _ANGLE_UNITS.items():
        if f"wg_angle_{unit}" in columns:
            out["angle"] = columns[f"wg_angle_{unit}"] * factor
            break
    else:
        if "wg_speed_rpm" in columns:
            out["speed"] = rpm_to_rad_per_s(columns["wg_speed_rpm"])
        elif "wg_speed_rad_per_s" in columns:
            out["speed"] = columns["wg_speed_rad_per_s"]
        else:
            raise InputError(f"{path}: missing the input column: wg_angle_rad (or _deg, _arcmin, _arcsec), "
                             "wg_speed_rpm or wg_speed_rad_per_s")
    if "torque_Nm" in columns:
        out["torque"] = columns["torque_Nm"]
    for name, values in out.items():
        if not np.all(np.isfinite(values)):
            raise InputError(f"{path}: column for {name} has a non-finite value at data row "
                             f"{int(np.flatnonzero(~np.isfinite(values))[0]) + 1}")
    if np.any(np.diff(out["time"]) <= 0.0):
        k = int(np.flatnonzero(np.diff(out["time"]) <= 0.0)[0])
        raise InputError(f"{path}: time_s is not strictly increasing at data row {k + 2}")
    return out


def csv_motion(profile: dict) -> Motion:
    """Motion through a measured profile: a C² cubic spline of the angle (zeroed at the start).

    Time is shifted to start at 0; the WG holds its last angle after the record ends.
    """
    from scipy.interpolate import CubicSpline, make_interp_spline

    t = profile["time"] - profile["time"][0]
    if "angle" in profile:
        spline = CubicSpline(t, profile["angle"] - profile["angle"][0])
    else:
        speed = make_interp_spline(t, profile["speed"], k=3)
        spline = speed.antiderivative()
    d1, d2 = spline.derivative(1), spline.derivative(2)
    t_end = float(t[-1])

    def clip(x):
        return np.clip(np.asarray(x, dtype=float), 0.0, t_end)

    def inside(x):
        x = np.asarray(x, dtype=float)
        return (x >= 0.0) & (x <= t_end)

    angle = lambda x: spline(clip(x))  # noqa: E731
    speed = lambda x: np.where(inside(x), d1(clip(x)), 0.0)  # noqa: E731
    accel = lambda x: np.where(inside(x), d2(clip(x)), 0.0)  # noqa: E731
    grid = np.linspace(0.0, t_end, 4 * len(t))
    return Motion(angle, speed, accel, t_end, {"record": (0.0, t_end)}, float(np.max(np.abs(d1(grid)))),
                  "measured (csv)")


# =========================================================================== load profiles
@dataclass(frozen=True)
class Load:
    """Torque applied by the load to the output [N·m] (per sample) and its rate, functions of time."""

    torque: Callable
    rate: Callable
    t_end: float = 0.0
    windows: dict = field(default_factory=dict)
    operating_point: float | None = None  # fraction of T_N before a sweep starts
    #: lowest frequency of a sweep [Hz]: the response is compared from 1.5× this up, past the
    #: start taper, where the excitation still builds up and hysteretic loops are not yet periodic
    sweep_start: float = 0.0
    #: [(t_start, t_end, highest frequency in the load [Hz])] covering the run (a sweep's octaves)
    frequency_schedule: list = field(default_factory=list)


def _smoothstep(t, t0, width):
    """0 before ``t0``, cosine blend over ``width``, 1 after; and its time derivative."""
    if isinstance(t, float):
        s = (t - t0) / width
        if s <= 0.0:
            return 0.0, 0.0
        if s >= 1.0:
            return 1.0, 0.0
        return 0.5 * (1.0 - math.cos(math.pi * s)), 0.5 * math.pi / width * math.sin(math.pi * s)
    s = np.clip((np.asarray(t, dtype=float) - t0) / width, 0.0, 1.0)
    value = 0.5 * (1.0 - np.cos(np.pi * s))
    inside = (s > 0.0) & (s < 1.0)
    return value, np.where(inside, 0.5 * np.pi / width * np.sin(np.pi * s), 0.0)


def constant_load(torque) -> Load:
    """A constant torque [N·m] from t = 0 (no ramp): used for linearisation."""
    T = _param(torque)
    return Load(lambda t: np.zeros_like(np.asarray(t, dtype=float)) + T,
                lambda t: np.zeros_like(np.asarray(t, dtype=float)) + 0.0 * T)


def ramped_load(torque, ramp_s) -> Load:
    """A constant torque [N·m] (per sample) reached through a cosine ramp over ``ramp_s`` [s]."""
    T = _param(torque)

    def value(t):
        s, _ = _smoothstep(t, 0.0, ramp_s)
        return _outer(s, T)

    def rate(t):
        _, ds = _smoothstep(t, 0.0, ramp_s)
        return _outer(ds, T)

    return Load(value, rate)


def _outer(shape, scale):
    """shape(t) × per-sample scale: scalar t → (M,), t of shape (nt, 1) → (nt, M)."""
    return shape * scale if isinstance(shape, float) else np.asarray(shape) * scale


def _param(x):
    """A float for a single value (the solver's scalar path), else the array."""
    a = np.asarray(x, dtype=float)
    return float(a) if a.size == 1 else a


def opposing_load(torque, motion: Motion, smoothing_speed) -> Load:
    """A load that opposes the commanded direction: ``−T tanh(ω_ref / ω_s)`` (a brake, friction-like)."""
    T = _param(torque)

    def value(t):
        return _outer(-np.tanh(motion.speed(t) / smoothing_speed), T)

    def rate(t):
        x = motion.speed(t) / smoothing_speed
        return _outer(-(1.0 - np.tanh(x) ** 2) * motion.accel(t) / smoothing_speed, T)

    return Load(value, rate)


def step_load(initial, final, ramp_s, step_time, rise_s) -> Load:
    """``initial`` [N·m] ramped in over ``ramp_s``, then a cosine step to ``final`` at ``step_time``
    rising over ``rise_s``; windows ``before_step`` and ``after_step``."""
    T0, T1 = _param(initial), _param(final)

    def value(t):
        a, _ = _smoothstep(t, 0.0, ramp_s)
        b, _ = _smoothstep(t, step_time, rise_s)
        return _outer(a, T0) + _outer(b, T1 - T0)

    def rate(t):
        _, da = _smoothstep(t, 0.0, ramp_s)
        _, db = _smoothstep(t, step_time, rise_s)
        return _outer(da, T0) + _outer(db, T1 - T0)

    windows = {"before_step": (ramp_s, step_time), "after_step": (step_time, np.inf)}
    return Load(value, rate, windows=windows)


def sweep_load(preload, amplitude, f_start, f_stop, ramp_s, settle_s, sweep_s, tail_s) -> Load:
    """Preload ramped in, rest, exponential sine sweep ``f_start → f_stop`` (tapered ends), rest.

    Window ``sweep`` = from the sweep start to the end (the response has decayed by then),
    the record the frequency response is estimated from.
    """
    P, A = _param(preload), _param(amplitude)
    t_s = ramp_s + settle_s
    tau = sweep_s / np.log(f_stop / f_start)
    taper = min(0.1 * sweep_s, 3.0 / f_start)

    def parts(t):
        t = np.asarray(t, dtype=float)
        x = np.clip(t - t_s, 0.0, sweep_s)
        phase = TWO_PI * f_start * tau * (np.exp(x / tau) - 1.0)
        dphase = TWO_PI * f_start * np.exp(x / tau)
        up, dup = _smoothstep(t, t_s, taper)
        down, ddown = _smoothstep(t, t_s + sweep_s - taper, taper)
        w, dw = up * (1.0 - down), dup * (1.0 - down) - up * ddown
        on = (t >= t_s) & (t <= t_s + sweep_s)
        return np.where(on, w * np.sin(phase), 0.0), np.where(on, dw * np.sin(phase) + w * np.cos(phase) * dphase, 0.0)

    def value(t):
        s, _ = _smoothstep(t, 0.0, ramp_s)
        c, _ = parts(t)
        return _outer(s, P) + _outer(c, A)

    def rate(t):
        _, ds = _smoothstep(t, 0.0, ramp_s)
        _, dc = parts(t)
        return _outer(ds, P) + _outer(dc, A)

    t_end = t_s + sweep_s + tail_s
    return Load(value, rate, t_end, {"sweep": (t_s, t_end), "before_sweep": (ramp_s, t_s)})


def csv_load(profile: dict) -> Load:
    """Measured load torque [N·m] through a smoothing spline (the rate enters the KE load term)."""
    from scipy.interpolate import make_smoothing_spline

    t = profile["time"] - profile["time"][0]
    spline = make_smoothing_spline(t, profile["torque"])
    d1 = spline.derivative(1)
    t_end = float(t[-1])

    def clip(x):
        return np.clip(np.asarray(x, dtype=float), 0.0, t_end)

    return Load(lambda x: spline(clip(x)) + 0.0, lambda x: np.where(
        (np.asarray(x) >= 0) & (np.asarray(x) <= t_end), d1(clip(x)), 0.0), t_end)


def _zero(t):
    return 0.0 if isinstance(t, float) else np.zeros_like(np.asarray(t, dtype=float))


NO_LOAD = Load(_zero, _zero)


# =========================================================================== controller
@dataclass(frozen=True)
class PIController:
    """PI speed loop on the WG: ``T_m = k_p (ω_ref − ω_w) + k_i ∫(ω_ref − ω_w) dt + J_ff α_ref``.

    The integral of the speed error is the WG angle error, so the loop also holds
    position (a PD-like position stiffness ``k_i``).
    """

    kp: float
    ki: float
    feedforward_inertia: float = 0.0
    #: optional outer position loop [1/s]: the speed command becomes
    #: ``ω_ref + k_pos (θ_ref − θ_w)``, so the integrator removes the position error a
    #: holding torque (friction, load) leaves with the speed loop alone (0 = speed loop only)
    position_gain: float = 0.0

    @classmethod
    def tuned(cls, inertia: float, bandwidth_Hz: float, feedforward: bool = True,
              position_loop: bool = False) -> "PIController":
        """Crossover at ``bandwidth_Hz`` on the rigid inertia, PI zero a quarter below it;
        with ``position_loop`` a position gain of a sixth of the crossover (≈ 55° phase margin)."""
        wc = TWO_PI * bandwidth_Hz
        kp = inertia * wc
        return cls(kp=kp, ki=kp * wc / 4.0, feedforward_inertia=inertia if feedforward else 0.0,
                   position_gain=wc / 6.0 if position_loop else 0.0)

    def command(self, w_ref, th_ref, th_w):
        """Speed command [rad/s] of the inner loop."""
        return w_ref + self.position_gain * (th_ref - th_w) if self.position_gain else w_ref


# =========================================================================== kinematic error
class _KinematicError:
    """e(θ_w, θ_o, f) and its partial derivatives, analytic for the Fourier effect."""

    def __init__(self, effect):
        self.effect = effect
        self.kind = effect.id
        if self.kind == "fourier":
            e = effect
            self.wg = [(k, _param(a), _param(p))
                       for k, a, p in ((1.0, e.a1, e.p1), (2.0, e.a2, e.p2), (4.0, e.a4, e.p4))]
            self.out = [(1.0, _param(e.a_out), _param(e.p_out))]
            self.gain = _param(e.load_gain)

    def __call__(self, th_w, th_o, frac):
        """(e, ∂e/∂θ_w, ∂e/∂θ_o, ∂e/∂f)."""
        if self.kind == "none":
            return 0.0, 0.0, 0.0, 0.0
        if self.kind == "fourier":
            base, d_w, d_o = 0.0, 0.0, 0.0
            for k, a, p in self.wg:
                arg = k * th_w + p
                base = base + a * np.sin(arg)
                d_w = d_w + a * k * np.cos(arg)
            for k, a, p in self.out:
                arg = k * th_o + p
                base = base + a * np.sin(arg)
                d_o = d_o + a * k * np.cos(arg)
            scale = 1.0 + self.gain * np.abs(frac)
            return scale * base, scale * d_w, scale * d_o, self.gain * np.sign(frac) * base
        f = self.effect.displacement
        h, hf = 1e-6, 1e-6
        e = f(th_w, th_o, frac)
        return (e, (f(th_w + h, th_o, frac) - f(th_w - h, th_o, frac)) / (2 * h),
                (f(th_w, th_o + h, frac) - f(th_w, th_o - h, frac)) / (2 * h),
                (f(th_w, th_o, frac + hf) - f(th_w, th_o, frac - hf)) / (2 * hf))


# =========================================================================== the system
def _scalar_ratio(model: HarmonicDrive) -> float:
    ratio = np.atleast_1d(np.asarray(model.drive.ratio, dtype=float))
    if not np.allclose(ratio, ratio[0]):
        raise InputError("driven scenarios need one transmission ratio for the whole batch")
    return float(ratio[0])


def driven_wave_generator(model: HarmonicDrive, motion: Motion, load: Load = NO_LOAD, *,
                          mode: str = "prescribed", controller: PIController | None = None,
                          motor_torque: Callable | None = None,
                          input_friction: InputFriction = NO_INPUT_FRICTION, load_inertia: float = 0.0,
                          track_energy: bool = False) -> ODESystem:
    """The driven drive as an `hdsim.simulation.path.ODESystem` (batched, sample-major).

    ``motion`` is the prescribed WG motion (``mode="prescribed"``) or the speed loop's
    reference (``"pi"``); ``motor_torque(t)`` drives the WG in ``"torque"`` mode.
    ``track_energy`` adds the work integrals ``work_motor``, ``work_load`` and
    ``work_ke`` (done by a time-varying, load-dependent kinematic error) as states.
    """
    if mode not in ("prescribed", "pi", "torque"):
        raise unknown_name("input mode", mode, ("prescribed", "pi", "torque"))
    if mode == "pi" and controller is None:
        raise InputError("input mode 'pi' needs a controller")
    if mode == "torque" and motor_torque is None:
        raise InputError("input mode 'torque' needs a motor torque function")
    path = ElasticPath(model)
    ke = _KinematicError(model.kinematic_error)
    M = model.batch_size
    N = _scalar_ratio(model)
    TN = _param(model.drive.rated_torque)
    J_in = _param(model.drive.J_in)
    J_out = _param(np.asarray(model.drive.J_out, dtype=float) + float(load_inertia))
    fr = input_friction
    friction_on = fr is not NO_INPUT_FRICTION
    prescribed = mode == "prescribed"

    mech = ("deviation", "deviation_rate") if prescribed else ("theta_wg", "omega_wg", "deviation",
                                                               "deviation_rate")
    extra = ("speed_error_integral",) if mode == "pi" else ()
    energy = ("work_motor", "work_load", "work_ke") if track_energy else ()
    names = mech + extra + path.states + energy
    n = len(names)
    iq = 0 if prescribed else 2
    i_fric = len(mech) + len(extra)
    n_fric = len(path.states)
    i_work = i_fric + n_fric

    def core(t, x):
        """All quantities at time ``t`` for states ``x`` (sequence of arrays, (M,) or (nt, M))."""
        if prescribed:
            th_w, w_w, a_ref = motion.angle(t), motion.speed(t), motion.accel(t)
        else:
            th_w, w_w = x[0], x[1]
        q, qd = x[iq], x[iq + 1]
        th_o = th_w / N + q
        w_o = w_w / N + qd
        T_L = load.torque(t)
        frac = T_L / TN
        e, e_w, e_o, e_f = ke(th_w, th_o, frac)
        frac_rate = load.rate(t) / TN
        delta = q - e
        delta_rate = qd - e_w * w_w - e_o * w_o - e_f * frac_rate
        fstates = x[i_fric:i_fric + n_fric]
        tau, rates, hyst = path.evaluate(delta, delta_rate, fstates)
        out_force = tau * (1.0 - e_o)
        wg_force = tau * (1.0 / N + e_w)
        acc_o = (T_L - out_force) / J_out
        T_f = fr.torque(w_w, th_w) if friction_on else 0.0 * w_w
        w_cmd = None
        if prescribed:
            acc_w = a_ref
            T_m = J_in * a_ref + T_f - wg_force
        else:
            if mode == "pi":
                w_cmd = controller.command(motion.speed(t), motion.angle(t), th_w)
                T_m = (controller.kp * (w_cmd - w_w) + controller.ki * x[len(mech)]
                       + controller.feedforward_inertia * motion.accel(t))
            else:
                T_m = motor_torque(t) + 0.0 * w_w
            acc_w = (T_m - T_f + wg_force) / J_in
        return dict(th_w=th_w, w_w=w_w, acc_w=acc_w, q=q, qd=qd, th_o=th_o, w_o=w_o, acc_o=acc_o,
                    T_L=T_L, e=e, e_f=e_f, frac_rate=frac_rate, delta=delta, delta_rate=delta_rate, tau=tau,
                    rates=rates, hyst=hyst, T_m=T_m, T_f=T_f, w_cmd=w_cmd)

    def rhs(t, y):
        t = float(t)
        # one sample: Python floats through the laws (numpy on 1-element arrays costs ~4x)
        x = y.tolist() if M == 1 else y.reshape(M, n).T
        c = core(t, x)
        dx = np.empty((n, M))
        if not prescribed:
            dx[0] = c["w_w"]
            dx[1] = c["acc_w"]
        dx[iq] = c["qd"]
        dx[iq + 1] = c["acc_o"] - c["acc_w"] / N
        if mode == "pi":
            dx[len(mech)] = c["w_cmd"] - c["w_w"]
        for i, r in enumerate(c["rates"]):
            dx[i_fric + i] = r
        if track_energy:
            dx[i_work] = c["T_m"] * c["w_w"]
            dx[i_work + 1] = c["T_L"] * c["w_o"]
            dx[i_work + 2] = -c["tau"] * c["e_f"] * c["frac_rate"]
        return dx.T.ravel()

    def outputs(t, states):
        tt = np.asarray(t, dtype=float)[:, None]
        x = [states[name].T for name in names]
        c = core(tt, x)
        shape = (len(t), M)
        signals = {
            "wg_angle_rad": c["th_w"], "wg_speed_rad_per_s": c["w_w"], "output_angle_rad": c["th_o"],
            "output_speed_rad_per_s": c["w_o"], "deviation_rad": c["q"], "ke_source_rad": c["e"],
            "twist_rad": c["delta"], "drive_torque_Nm": c["tau"], "load_torque_Nm": c["T_L"],
            "motor_torque_Nm": c["T_m"], "input_friction_Nm": c["T_f"],
            "reference_angle_rad": motion.angle(tt), "reference_speed_rad_per_s": motion.speed(tt),
            "hysteretic_twist_rad": c["hyst"],
        }
        return {k: np.ascontiguousarray(np.broadcast_to(v, shape).T) for k, v in signals.items()}

    # typical magnitudes for the absolute tolerances
    K = np.asarray(model.base_stiffness, dtype=float)
    theta_scale = float(np.max(1e-2 * TN / K))
    wn = float(np.max(np.sqrt(K / J_out)))
    speed_scale = max(float(motion.max_speed), 1.0)
    scales = {"theta_wg": TWO_PI, "omega_wg": speed_scale, "deviation": theta_scale,
              "deviation_rate": theta_scale * wn, "speed_error_integral": 1e-3,
              "work_motor": float(np.max(TN)) * theta_scale, "work_load": float(np.max(TN)) * theta_scale,
              "work_ke": float(np.max(TN)) * theta_scale}
    state_scales = np.array([scales.get(nm, 1e-2 * float(np.max(TN)) if nm.endswith("torque") else theta_scale)
                             for nm in names])

    # consistent start: WG at the profile's start, no twist (q = e), no friction memory
    y0 = np.zeros((M, n))
    th_w0 = float(motion.angle(0.0))
    w_w0 = float(motion.speed(0.0))
    if not prescribed:
        y0[:, 0], y0[:, 1] = th_w0, w_w0
    frac0 = np.broadcast_to(load.torque(0.0) / TN, (M,))
    e0, e_w0, e_o0, _ = ke(th_w0, th_w0 / N, frac0)
    y0[:, iq] = np.broadcast_to(e0, (M,))
    y0[:, iq + 1] = np.broadcast_to(e_w0 * w_w0 + e_o0 * w_w0 / N, (M,))
    system = ODESystem(SETUP, names, M, rhs, y0.ravel(), outputs, state_scales)
    system.path = path  # for energy_balance
    system.J = (J_in, J_out)
    return system


# =========================================================================== energy
def spring_energy(path: ElasticPath, twist, nodes: int = 6, panels: int = 48):
    """Energy stored in the spring behind the dead zone at elastic twist ``twist`` [J].

    ``V(δ) = ∫₀^δ T_spring(dead_zone(x)) dx`` by composite Gauss-Legendre (the smoothed
    knees are resolved by the panels); works element-wise on arrays.
    """
    twist = np.asarray(twist, dtype=float)
    xi, wi = np.polynomial.legendre.leggauss(nodes)
    edges = np.linspace(0.0, 1.0, panels + 1)
    s = (0.5 * (edges[:-1, None] + edges[1:, None]) + 0.5 * (edges[1:, None] - edges[:-1, None]) * xi).ravel()
    w = (0.5 * (edges[1:, None] - edges[:-1, None]) * wi).ravel()
    x = twist[..., None] * s
    engaged, _ = path.model.backlash.engage(x)
    torque = path.model.hardening.torque(engaged, path.c_struct[..., None] if np.ndim(path.c_struct) else
                                         path.c_struct, path.c_mesh[..., None] if np.ndim(path.c_mesh)
                                         else path.c_mesh)
    return twist * np.sum(torque * w, axis=-1)


def energy_balance(system: ODESystem, result: SimulationResult) -> dict[str, np.ndarray]:
    """Mechanical energy, work done on the drive and the energy dissipated, (M, nt) each.

    Needs ``track_energy=True``. ``dissipated = work_motor + work_load + work_ke − ΔE`` with
    ``E = ½ J_in ω_w² + ½ J_out ω_o² + V(δ − hysteretic twist)``. Energy held by a
    friction element (presliding, end stops) counts as dissipated here, so a passive
    model gives ``dissipated ≥ 0`` at all times, and exactly 0 without losses.
    """
    J_in, J_out = system.J
    s = result.signals
    kinetic = 0.5 * np.asarray(J_in)[..., None] * s["wg_speed_rad_per_s"] ** 2 \
        + 0.5 * np.asarray(J_out)[..., None] * s["output_speed_rad_per_s"] ** 2
    elastic = s["twist_rad"] - s["hysteretic_twist_rad"]
    potential = np.array([spring_energy(ElasticPath(_sample_model(system.path.model, m)), elastic[m])
                          for m in range(elastic.shape[0])])
    energy = kinetic + potential
    work = result.states["work_motor"] + result.states["work_load"] + result.states["work_ke"]
    return {"energy": energy, "kinetic": kinetic, "potential": potential, "work": work,
            "dissipated": work - (energy - energy[:, :1])}


# =========================================================================== scenario → bench
@dataclass
class Bench:
    """Everything a driven scenario asks for, in SI, for one (batch) model."""

    motion: Motion
    load: Load
    mode: str
    controller: PIController | None
    input_friction: InputFriction
    load_inertia: float
    t_end: float
    sample_rate: float
    metrics: list

    def system(self, model, track_energy=False) -> ODESystem:
        """The ODE system of this bench for ``model`` (see `driven_wave_generator`)."""
        return driven_wave_generator(model, self.motion, self.load, mode=self.mode, controller=self.controller,
                                     input_friction=self.input_friction, load_inertia=self.load_inertia,
                                     track_energy=track_energy)

    def sample_times(self) -> np.ndarray:
        """Uniform output times over the run at ``sample_rate`` [Hz]."""
        n = int(np.ceil(self.t_end * self.sample_rate)) + 1
        return np.linspace(0.0, self.t_end, n)


_PROFILES = ("hold", "constant", "reversal", "trapezoid", "sine", "csv")
_LOADS = ("none", "constant", "opposing", "step", "sweep", "csv")
DRIVEN_METRICS = ("transmission_accuracy", "lost_motion_on_reversal", "windup", "order_spectrum",
                  "running_torque", "starting_torque", "linearisation", "frequency_response", "tracking",
                  "settling", "load_step", "oscillation")


def _positive(table, key, default, where, allow_zero=False):
    value = float(table.get(key, default))
    if not np.isfinite(value) or value < 0.0 or (value == 0.0 and not allow_zero):
        raise InputError(f"{where}: {key} must be {'>= 0' if allow_zero else '> 0'}, got {value:g}")
    return value


def _yes(value, key, where) -> bool:
    if value not in ("yes", "no"):
        raise InputError(f"{where}: {key} must be \"yes\" or \"no\", got {value!r}")
    return value == "yes"


def bench_from_scenario(model: HarmonicDrive, scenario: Scenario) -> Bench:
    """Read a driven scenario's tables into motion, load, controller and friction (checks ranges)."""
    src = scenario.source
    data = scenario.data
    for name in scenario.metrics:
        if name not in DRIVEN_METRICS:
            raise unknown_name(f"metric in scenario {scenario.name}", name, DRIVEN_METRICS)
    N = _scalar_ratio(model)
    TN = np.asarray(model.drive.rated_torque, dtype=float)
    inp, ld = data.get("input", {}), data.get("load", {})
    mode = inp["mode"]
    if mode not in ("prescribed", "pi"):
        raise unknown_name(f"input.mode in {src}", mode, ("prescribed", "pi"))
    profile = inp["profile"]
    if profile not in _PROFILES:
        raise unknown_name(f"input.profile in {src}", profile, _PROFILES)
    load_kind = ld.get("profile", "none")
    if load_kind not in _LOADS:
        raise unknown_name(f"load.profile in {src}", load_kind, _LOADS)

    csv_data = None
    if profile == "csv" or load_kind == "csv":
        if "csv" not in inp:
            raise InputError(f"{src}: input.csv (the measured profile file) is required for a csv profile")
        csv_path = Path(inp["csv"])
        if not csv_path.is_absolute() and src != "<dict>":
            csv_path = Path(src).resolve().parent / csv_path
        csv_data = read_profile_csv(csv_path)
        if load_kind == "csv" and "torque" not in csv_data:
            raise InputError(f"{csv_path}: load.profile = \"csv\" needs a torque_Nm column")

    # ---------------------------------------------------------------- motion
    speed = rpm_to_rad_per_s(float(inp.get("speed_rpm", 0.0)))
    ramp = _positive(inp, "ramp_s", 0.2, src)
    if profile in ("constant", "reversal", "trapezoid") and speed == 0.0:
        raise InputError(f"{src}: input.speed_rpm must be non-zero for a {profile} profile")
    if profile == "constant":
        motion = constant_speed_motion(speed, N, ramp, _positive(inp, "output_revolutions", 1.0, src),
                                       _positive(inp, "settle_revolutions", 0.05, src, allow_zero=True))
    elif profile == "reversal":
        motion = reversal_motion(speed, N, ramp, _positive(inp, "output_revolutions", 1.0, src),
                                 _positive(inp, "settle_revolutions", 0.05, src, allow_zero=True),
                                 _positive(inp, "dwell_s", 0.1, src, allow_zero=True))
    elif profile == "trapezoid":
        back = _yes(inp.get("return", "yes"), "input.return", src)
        move = np.deg2rad(float(inp.get("move_deg", 90.0)))
        if move == 0.0:
            raise InputError(f"{src}: input.move_deg must be non-zero")
        motion = trapezoid_motion(speed, N, move, ramp, _positive(inp, "dwell_s", 0.2, src), back)
    elif profile == "sine":
        motion = sine_motion(np.deg2rad(_positive(inp, "amplitude_deg", 1.0, src)) * N,
                             _positive(inp, "frequency_Hz", 1.0, src), _positive(inp, "cycles", 3.0, src),
                             _positive(inp, "dwell_s", 0.0, src, allow_zero=True))
    elif profile == "csv":
        motion = csv_motion(csv_data)
    else:
        motion = _hold(_positive(inp, "hold_s", 0.5, src))

    # ---------------------------------------------------------------- load
    torque = float(ld.get("torque", 0.0))
    if abs(torque) > 5.0:
        raise InputError(f"{src}: load.torque is a fraction of T_N and must be within ±5")
    load_ramp = _positive(ld, "ramp_s", 0.05, src)
    if load_kind == "none":
        load = NO_LOAD
    elif load_kind == "constant":
        load = ramped_load(torque * TN, load_ramp)
    elif load_kind == "opposing":
        cruise = motion.max_speed
        if cruise == 0.0:
            raise InputError(f"{src}: an opposing load needs a moving input profile")
        load = opposing_load(abs(torque) * TN, motion, _positive(ld, "smoothing", 0.05, src) * cruise)
    elif load_kind == "step":
        step_time = _positive(ld, "step_time_s", 0.2, src)
        load = step_load(torque * TN, float(ld.get("step_to", 0.5)) * TN, load_ramp, step_time,
                         _positive(ld, "rise_s", 0.002, src))
        if step_time <= load_ramp:
            raise InputError(f"{src}: load.step_time_s must come after the load ramp (load.ramp_s)")
    elif load_kind == "sweep":
        f0, f1 = _positive(ld, "f_start_Hz", 20.0, src), _positive(ld, "f_stop_Hz", 1500.0, src)
        if f1 <= f0:
            raise InputError(f"{src}: load.f_stop_Hz must exceed load.f_start_Hz")
        load = sweep_load(torque * TN, _positive(ld, "sweep_amplitude", 0.01, src) * TN, f0, f1, load_ramp,
                          _positive(ld, "settle_s", 0.1, src), _positive(ld, "sweep_s", 1.0, src),
                          _positive(ld, "tail_s", 0.2, src))
        t_s, t_e = load.windows["sweep"][0], load.t_end
        sweep_s = float(ld.get("sweep_s", 1.0))
        octaves = max(int(np.ceil(np.log2(f1 / f0))), 1)
        edges = t_s + sweep_s * np.arange(octaves + 1) / octaves
        schedule = [(0.0, t_s, 1.0 / load_ramp)]
        schedule += [(a, b, f0 * (f1 / f0) ** ((b - t_s) / sweep_s)) for a, b in zip(edges[:-1], edges[1:])]
        schedule.append((t_s + sweep_s, t_e, f1))
        load = replace(load, operating_point=torque, sweep_start=f0, frequency_schedule=schedule)
    else:
        load = csv_load(csv_data)
    load_inertia = _positive(ld, "inertia", 0.0, src, allow_zero=True)

    # ---------------------------------------------------------------- controller, friction
    controller = None
    ctl = data.get("controller", {})
    if mode == "pi":
        J_total = float(np.max(model.drive.J_in)) + (float(np.max(model.drive.J_out)) + load_inertia) / N**2
        base = PIController.tuned(J_total, _positive(ctl, "bandwidth_Hz", 30.0, src),
                                  _yes(ctl.get("feedforward", "yes"), "controller.feedforward", src),
                                  _yes(ctl.get("position_loop", "no"), "controller.position_loop", src))
        controller = PIController(kp=_positive(ctl, "kp", base.kp, src), ki=_positive(ctl, "ki", base.ki, src,
                                                                                      allow_zero=True),
                                  feedforward_inertia=base.feedforward_inertia,
                                  position_gain=_positive(ctl, "position_gain_per_s", base.position_gain, src,
                                                          allow_zero=True))
    elif ctl:
        raise InputError(f"{src}: [controller] applies to input.mode = \"pi\" only")
    friction = for_unit(model, data.get("input_friction"))

    t_end = max(motion.t_end, load.t_end)
    if load_kind == "step" and step_time >= t_end:
        raise InputError(f"{src}: load.step_time_s ({step_time:g} s) must come before the end of the "
                         f"input profile ({t_end:g} s)")
    if profile == "hold" and load.t_end and "hold_s" not in inp:
        motion = _hold(t_end)
    windows = {**motion.windows, **{k: (a, min(b, t_end)) for k, (a, b) in load.windows.items()}}
    motion = replace(motion, windows=windows)
    out = data.get("output", {})
    per_rev = int(out.get("samples_per_wg_rev", 64))
    rate = max(_positive(out, "sample_rate_Hz", 1000.0, src), per_rev * motion.max_speed / TWO_PI)
    return Bench(motion, load, mode, controller, friction, load_inertia, t_end, rate, scenario.metrics)


# =========================================================================== linearisation
def operating_point(model: HarmonicDrive, bench: Bench, load_fraction, settle_s: float = 0.3) -> np.ndarray:
    """State at rest under a constant load (WG held): ramp the load in, let it settle, take the end state."""
    TN = np.asarray(model.drive.rated_torque, dtype=float)
    hold = _hold(settle_s)
    system = driven_wave_generator(model, hold, ramped_load(load_fraction * TN, 0.3 * settle_s),
                                   mode=bench.mode, controller=bench.controller,
                                   input_friction=bench.input_friction, load_inertia=bench.load_inertia)
    result = integrate(system, (0.0, settle_s), np.array([0.0, settle_s]), SolverOptions(rtol=1e-8,
                                                                                        atol_scale=1e-8))
    return np.array([result.states[name][:, -1] for name in system.state_names]).T  # (M, n)


def linear_model(model: HarmonicDrive, bench: Bench, load_fraction: float, x_op=None):
    """``control.StateSpace`` from load torque [N·m] to output angle [rad] (and WG angle), about a
    standstill operating point at ``load_fraction`` × T_N, with the tangent stiffness there.

    Built by `hdsim.simulation.linearize.linearize` on the same right-hand side the simulator
    integrates. Outputs: ``output_angle`` (= θ_w/N + q; in prescribed mode the WG is held,
    so it is the deviation) and, for a free WG, ``wg_angle``.
    """
    import control

    from hdsim.simulation.linearize import linearize

    if model.batch_size != 1:
        raise InputError("linearisation needs a single model, not a batch")
    TN = float(model.drive.rated_torque)
    if x_op is None:
        x_op = operating_point(model, bench, load_fraction)[0]
    hold = _hold(1.0)

    def build(u):  # linearize renames friction.slip → friction_slip for python-control
        return driven_wave_generator(model, hold, constant_load(u), mode=bench.mode,
                                     controller=bench.controller, input_friction=bench.input_friction,
                                     load_inertia=bench.load_inertia)

    full = linearize(build, x_op, load_fraction * TN, input_name="load_torque_Nm", input_scale=TN)
    names = list(full.state_labels)
    N = _scalar_ratio(model)
    C = np.zeros((1 if bench.mode == "prescribed" else 2, len(names)))
    C[0, names.index("deviation")] = 1.0
    outputs = ["output_angle"]
    if bench.mode != "prescribed":
        C[0, names.index("theta_wg")] = 1.0 / N
        C[1, names.index("theta_wg")] = 1.0
        outputs.append("wg_angle")
    return control.ss(full.A, full.B, C, np.zeros((C.shape[0], 1)), states=names, inputs=["load_torque_Nm"],
                      outputs=outputs)


def linear_summary(sys) -> dict:
    """Natural frequencies [Hz] and damping ratios of the oscillatory modes, lowest first, and the
    quasi-static stiffness at the output [N·m/rad]: 1/|H| a thousand times below the lowest
    mode (a neutral micro-slip mode the load cannot excite makes ``dcgain`` ill-conditioned).

    For the drive's own tangent stiffness use a ``prescribed`` (WG held) model, as
    `drive_tangent_stiffness` does; in ``pi`` mode this value includes the servo.
    """
    import control

    from hdsim.simulation.linearize import natural_frequencies

    wn, zeta = natural_frequencies(sys)
    w_low = 1e-3 * (wn[0] if len(wn) else 1.0)
    H = np.asarray(control.frequency_response(sys[0, 0], [w_low]).complex).reshape(-1)[0]
    return {"natural_frequencies_Hz": wn / TWO_PI, "damping_ratios": zeta,
            "tangent_stiffness": 1.0 / abs(H) if H else np.inf}


def drive_tangent_stiffness(model: HarmonicDrive, bench: Bench, load_fraction: float) -> float:
    """Tangent stiffness of the drive [N·m/rad] at ``load_fraction`` × T_N with the WG held
    (spring, micro-slip and backlash in series), whatever the scenario's input mode."""
    held = replace(bench, mode="prescribed", controller=None)
    return linear_summary(linear_model(model, held, load_fraction))["tangent_stiffness"]


def frequency_response_check(t, load_torque, output_angle, sys, window, band_fraction=0.8, f_min=None):
    """Simulated sine-sweep response against the linear model, per sample.

    Returns ``(f [Hz], H_sim, H_lin, errors)``: H by the ratio of the Fourier transforms of
    the output angle and load torque deviations over ``window`` (starting at rest at the
    operating point, ending after the response has decayed), compared on the bins where
    the sweep has energy, up to ``band_fraction`` of the first natural frequency.
    """
    import control

    from hdsim.simulation.linearize import natural_frequencies

    wn, _ = natural_frequencies(sys)
    f1 = wn[0] / TWO_PI if len(wn) else np.inf
    f, H = ke_metrics.sweep_frequency_response(t, load_torque, output_angle, window)
    U = ke_metrics.sweep_input_spectrum(t, load_torque, window)
    strong = np.abs(U) > 0.2 * np.max(np.abs(U))
    keep = strong & (f <= band_fraction * f1) & (f > 0) & (f >= (f_min or 0.0))
    fk = f[keep]
    H_lin = np.asarray(control.frequency_response(sys[0, 0], TWO_PI * fk).complex).reshape(-1)
    H_sim = H[keep]
    mag_err = np.abs(np.abs(H_sim) / np.abs(H_lin) - 1.0)
    phase_err = np.abs(np.angle(H_sim / H_lin))
    return fk, H_sim, H_lin, {"magnitude": mag_err, "phase": phase_err, "f1_Hz": f1,
                              "complex": np.abs(H_sim / H_lin - 1.0)}


# =========================================================================== starting torque
def starting_torque(model: HarmonicDrive, friction: InputFriction, ramp_rate: float | None = None,
                    threshold_rpm: float = 1.0) -> np.ndarray:
    """Motor torque at which the WG breaks away [N·m], per sample, from a slow torque ramp.

    The unloaded drive is driven by a motor torque rising at ``ramp_rate`` [N·m/s] (default:
    the starting torque per 0.5 s); breakaway is when the WG speed passes ``threshold_rpm``.
    """
    F = float(friction.starting_torque)
    if F == 0.0:
        return np.zeros(model.batch_size)
    rate = ramp_rate or 2.0 * F
    t_end = 1.5 * F / rate
    hold = _hold(t_end)
    system = driven_wave_generator(model, hold, NO_LOAD, mode="torque", motor_torque=lambda t: rate * t,
                                   input_friction=friction)
    t = np.linspace(0.0, t_end, 3001)
    result = integrate(system, (0.0, t_end), t, SolverOptions(rtol=1e-7, atol_scale=1e-7))
    w = result.states["omega_wg"]
    out = np.full(w.shape[0], np.nan)
    for m in range(w.shape[0]):
        above = np.flatnonzero(np.abs(w[m]) > rpm_to_rad_per_s(threshold_rpm))
        if above.size:
            out[m] = rate * t[above[0]]
    return out


# =========================================================================== runner
def run_driven(model: HarmonicDrive, scenario: Scenario, *, samples_per_segment: int | None = None,
               options: SolverOptions | None = None):
    """Runner of the ``driven_wave_generator`` set-up (registered in `hdsim.scenarios.run.RUNNERS`).

    ``samples_per_segment``, if given, overrides ``output.samples_per_wg_rev``.
    """
    from hdsim.scenarios.run import Run, solver_options

    if samples_per_segment:
        scenario = scenario.with_updates({"output.samples_per_wg_rev": int(samples_per_segment)})
    bench = bench_from_scenario(model, scenario)
    system = bench.system(model)
    t_eval = bench.sample_times()
    result = integrate_segments(system, step_schedule(bench, solver_options(scenario, options)), t_eval)
    result.metadata.update(windows={k: [float(a), float(b)] for k, (a, b) in bench.motion.windows.items()},
                           input_mode=bench.mode, profile=bench.motion.description)
    metrics = driven_metrics(model, scenario, bench, result)
    return Run(model, scenario, result, metrics)


#: steps per WG revolution (and per period of a load sweep's top frequency) that bound the
#: solver's step when the scenario sets no max_step: Radau steps over the kinematic error's
#: 4× harmonic otherwise, and its dense output between steps is then off by ~0.1 arcsec;
#: with 32 steps per WG turn it is within ~0.01 arcsec (tests/test_driven_numerics.py)
STEPS_PER_WG_REV = 32
STEPS_PER_SWEEP_PERIOD = 8


def step_schedule(bench: Bench, options: SolverOptions) -> list[tuple[float, float, SolverOptions]]:
    """Time segments and their solver options: ``max_step`` bounded by the WG speed and, during a
    load sweep, by the sweep's frequency in that segment (one segment per octave), unless the
    options set ``max_step``. Radau's error estimate does not see a forcing it steps over."""
    if np.isfinite(options.max_step):
        return [(0.0, bench.t_end, options)]
    motion_limit = (TWO_PI / (STEPS_PER_WG_REV * bench.motion.max_speed) if bench.motion.max_speed > 0.0
                    else np.inf)
    pieces = bench.load.frequency_schedule or [(0.0, bench.t_end, 0.0)]
    out = []
    for a, b, f in pieces:
        limit = min(motion_limit, 1.0 / (STEPS_PER_SWEEP_PERIOD * f) if f > 0.0 else np.inf)
        out.append((a, b, options.replace(max_step=limit) if np.isfinite(limit) else options))
    return out


def integrate_segments(system: ODESystem, schedule, t_eval) -> SimulationResult:
    """`hdsim.simulation.solver.integrate` over consecutive segments, each with its own options,
    the state carried across; one result on ``t_eval``."""
    if len(schedule) == 1:
        a, b, options = schedule[0]
        return integrate(system, (a, b), t_eval, options)
    y0 = system.y0.copy()
    times, parts, solver = [], [], {}
    try:
        for k, (a, b, options) in enumerate(schedule):
            last = k == len(schedule) - 1
            inside = t_eval[(t_eval >= a) & ((t_eval <= b) if last else (t_eval < b))]
            sub = integrate(system, (a, b), np.concatenate([inside, [b]]) if not last else inside, options)
            system.y0 = np.array([sub.states[name][:, -1] for name in system.state_names]).T.ravel()
            times.append(inside)
            parts.append({name: values[:, :inside.size] for name, values in sub.states.items()})
            for key in ("nfev", "njev", "nlu"):
                solver[key] = solver.get(key, 0) + sub.solver[key]
            solver.update(method=sub.solver["method"], rtol=sub.solver["rtol"], message=sub.solver["message"])
    finally:
        system.y0 = y0
    t = np.concatenate(times)
    states = {name: np.concatenate([p[name] for p in parts], axis=1) for name in system.state_names}
    solver["segments"] = len(schedule)
    return SimulationResult(t=t, states=states, signals=system.outputs(t, states), setup=system.setup,
                            solver=solver)


def driven_metrics(model, scenario, bench: Bench, result: SimulationResult) -> dict[str, np.ndarray]:
    """The metric groups a driven scenario lists, each as arrays of shape (M,) in contract units."""
    s = result.signals
    t = result.t
    windows = bench.motion.windows
    M = result.batch
    N = _scalar_ratio(model)
    data = scenario.data
    analysis = data.get("analysis", {})
    out: dict[str, np.ndarray] = {}
    q = s["deviation_rad"]
    wg = s["wg_angle_rad"]

    def need(*names):
        missing = [w for w in names if w not in windows]
        if missing:
            raise InputError(f"{scenario.source}: these metrics need a profile with window(s) "
                             f"{', '.join(missing)} (have: {', '.join(windows) or 'none'})")
        return [windows[w] for w in names]

    def passes():
        if "forward" in windows:
            return [windows["forward"], windows["reverse"]]
        if "constant" in windows:
            return [windows["constant"]]
        raise InputError(f"{scenario.source}: this metric needs a constant or reversal profile")

    for group in bench.metrics:
        if group == "transmission_accuracy":
            values = [ke_metrics.transmission_accuracy(t, wg, q, w, N) for w in passes()]
            out["transmission_accuracy_arcsec"] = rad_to_arcsec(np.max(values, axis=0))
            if len(values) == 2:
                out["transmission_accuracy_forward_arcsec"] = rad_to_arcsec(values[0])
                out["transmission_accuracy_reverse_arcsec"] = rad_to_arcsec(values[1])
        elif group == "lost_motion_on_reversal":
            fwd, rev = need("forward", "reverse")
            out["lost_motion_on_reversal_arcsec"] = rad_to_arcsec(
                ke_metrics.lost_motion_on_reversal(t, wg, q, fwd, rev))
        elif group == "windup":
            values = [ke_metrics.window_mean(t, s["twist_rad"], w) for w in passes()]
            out["windup_arcsec"] = rad_to_arcsec(np.mean(np.abs(values), axis=0))
            out["windup_load_Nm"] = np.mean([np.abs(ke_metrics.window_mean(t, s["load_torque_Nm"], w))
                                             for w in passes()], axis=0)
        elif group == "order_spectrum":
            window = passes()[0]
            orders = [float(o) for o in analysis.get("orders", [1, 2, 4])]
            amps = ke_metrics.order_amplitudes(t, wg, q, window, N, orders + [1.0 / N])
            for o, a in zip(orders, amps[:-1]):
                out[f"ke_order_{ke_metrics.order_label(o)}_arcsec"] = rad_to_arcsec(a)
            out["ke_output_order_1_arcsec"] = rad_to_arcsec(amps[-1])
        elif group == "running_torque":
            (window,) = need("constant")
            out["running_torque_mNm"] = 1e3 * ke_metrics.window_mean(t, s["motor_torque_Nm"], window)
            out["running_speed_rpm"] = np.full(M, rad_per_s_to_rpm(bench.motion.max_speed))
        elif group == "starting_torque":
            out["starting_torque_mNm"] = 1e3 * starting_torque(model, bench.input_friction)
        elif group in ("linearisation", "frequency_response"):
            _linear_metrics(model, scenario, bench, result, group, out)
        elif group == "tracking":
            ref = bench.motion.angle(t)[None, :] / N
            error = s["output_angle_rad"] - ref
            out["max_following_error_arcsec"] = rad_to_arcsec(np.max(np.abs(error), axis=1))
            out["final_error_arcsec"] = rad_to_arcsec(np.abs(error[:, -1]))
            out["max_wg_tracking_error_deg"] = np.rad2deg(np.max(np.abs(wg - bench.motion.angle(t)[None, :]), axis=1))
            out["peak_motor_torque_Nm"] = np.max(np.abs(s["motor_torque_Nm"]), axis=1)
        elif group == "settling":
            (window,) = need("dwell")
            band = arcsec_to_rad(float(analysis.get("settle_band_arcsec", 1.0)))
            ref = bench.motion.angle(t)[None, :] / N
            settle, residual = ke_metrics.settling(t, s["output_angle_rad"] - ref, window, band)
            out["settling_time_s"] = settle
            out["dwell_error_p2p_arcsec"] = rad_to_arcsec(residual)
        elif group == "load_step":
            before, after = need("before_step", "after_step")
            band = arcsec_to_rad(float(analysis.get("settle_band_arcsec", 1.0)))
            ref = bench.motion.angle(t)[None, :] / N
            err = s["output_angle_rad"] - ref
            step = ke_metrics.load_step(t, err, before, after, band)
            out["load_step_deflection_arcsec"] = rad_to_arcsec(step["deflection"])
            out["load_step_peak_arcsec"] = rad_to_arcsec(step["peak"])
            out["load_step_settling_time_s"] = step["settling_time"]
            out["load_step_twist_arcsec"] = rad_to_arcsec(
                ke_metrics.window_mean(t, s["twist_rad"], (after[1] - 0.1 * (after[1] - after[0]), after[1]))
                - ke_metrics.window_mean(t, s["twist_rad"], before))
        elif group == "oscillation":
            (window,) = need("oscillation")
            ref = bench.motion.angle(t) / N
            gain, phase, p2p = ke_metrics.oscillation(t, ref, s["output_angle_rad"], window,
                                                      float(data["input"].get("frequency_Hz", 1.0)))
            out["oscillation_gain"] = gain
            out["oscillation_phase_deg"] = np.rad2deg(phase)
            out["oscillation_deviation_p2p_arcsec"] = rad_to_arcsec(p2p)
    return out


def _linear_metrics(model, scenario, bench, result, group, out):
    lin = scenario.data.get("linearise", {})
    M = result.batch
    load_fraction = float(lin.get("load", bench.load.operating_point or 0.0))
    keys = ["natural_frequency_1_Hz", "damping_ratio_1", "tangent_stiffness_Nm_per_rad"]
    if bench.mode != "prescribed":  # motor loop and drive: two modes
        keys += ["natural_frequency_2_Hz", "damping_ratio_2"]
    if group == "frequency_response":
        keys += ["bode_magnitude_error_pct", "bode_phase_error_deg", "bode_compared_up_to_Hz"]
    values = {k: np.full(M, np.nan) for k in keys}
    for m in range(M):
        single = _sample_model(model, m)
        x_op = None
        if group == "frequency_response":
            window = bench.motion.windows.get("sweep")
            if window is None:
                raise InputError(f"{scenario.source}: frequency_response needs load.profile = \"sweep\"")
            k0 = int(np.searchsorted(result.t, window[0]))
            x_op = np.array([result.states[nm][m, k0] for nm in result.states])
            load_fraction = float(bench.load.operating_point or 0.0)
        sys = linear_model(single, bench, load_fraction, x_op=x_op)
        summary = linear_summary(sys)
        if len(summary["natural_frequencies_Hz"]):
            values["natural_frequency_1_Hz"][m] = summary["natural_frequencies_Hz"][0]
            values["damping_ratio_1"][m] = summary["damping_ratios"][0]
        if "natural_frequency_2_Hz" in values and len(summary["natural_frequencies_Hz"]) > 1:
            values["natural_frequency_2_Hz"][m] = summary["natural_frequencies_Hz"][1]
            values["damping_ratio_2"][m] = summary["damping_ratios"][1]
        values["tangent_stiffness_Nm_per_rad"][m] = (summary["tangent_stiffness"] if bench.mode == "prescribed"
                                                     else drive_tangent_stiffness(single, bench, load_fraction))
        if group == "frequency_response":
            f, _, _, err = frequency_response_check(
                result.t, result.signals["load_torque_Nm"][m], result.signals["output_angle_rad"][m], sys,
                window, float(lin.get("compare_below", 0.8)), lin.get("f_min_Hz", 1.5 * bench.load.sweep_start))
            if f.size:
                values["bode_magnitude_error_pct"][m] = 100.0 * np.max(err["magnitude"])
                values["bode_phase_error_deg"][m] = np.rad2deg(np.max(err["phase"]))
                values["bode_compared_up_to_Hz"][m] = f[-1]
    out.update(values)


def _sample_model(model: HarmonicDrive, m: int) -> HarmonicDrive:
    if model.batch_size == 1:
        return model
    return model.with_updates({k: np.atleast_1d(v)[m] for k, v in model.params().items() if np.size(v) > 1})
