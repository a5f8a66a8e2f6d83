"""Wave-generator motion profiles of the driven bench: angle, speed and acceleration of
the WG as vectorised functions of time.

A `Motion` is either followed exactly (``prescribed`` input) or is the reference of the
speed loop (``pi`` input), see `hdsim.simulation.driven`. Every profile starts and ends
at rest; its ``windows`` name the time intervals the metrics read (docs/tutorial-kinematic-error.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from hdsim.errors import InputError
from hdsim.simulation.profiles import cosine_ramps, segment_of

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class Motion:
    """WG motion (prescribed, or the speed loop's reference).

    Attributes
    ----------
    angle, speed, accel : callable
        WG angle [rad], speed [rad/s] and acceleration [rad/s²] as functions of time [s]
        (a Python float or an array).
    t_end : float
        End of the profile [s].
    windows : dict
        Name → (start, end) [s] of the intervals the metrics read (``forward``,
        ``reverse``, ``constant``, ``dwell``, …).
    max_speed : float
        Largest |WG speed| [rad/s]; sets the output sampling and the solver's step bound.
    description : str
        Short name of the profile, stored with the result.
    kinematics : callable or None
        ``(angle, speed, accel)`` at a float time in one call, for a profile that finds all
        three at once (`SpeedKnots`); None: `at` makes the three calls.
    """

    angle: Callable
    speed: Callable
    accel: Callable
    t_end: float
    windows: dict = field(default_factory=dict)
    max_speed: float = 0.0
    description: str = ""
    kinematics: Callable | None = None

    def at(self, t) -> tuple:
        """WG angle [rad], speed [rad/s] and acceleration [rad/s²] at ``t`` [s] (a float or
        an array); the solver's scalar path asks for all three at every call."""
        if self.kinematics is not None and isinstance(t, float):
            return self.kinematics(t)
        return self.angle(t), self.speed(t), self.accel(t)


def hold_motion(t_end: float) -> Motion:
    """The WG at rest at angle 0.

    Parameters
    ----------
    t_end : float
        Duration [s].

    Returns
    -------
    Motion
        Zero angle, speed and acceleration; no windows.
    """
    zero = lambda t: np.zeros_like(np.asarray(t, dtype=float))  # noqa: E731
    return Motion(zero, zero, zero, float(t_end), {}, 0.0, "hold")


def _segment_angle(s, a, b, d, linear: bool, sin):
    """Angle [rad] gained a fraction ``s`` into a segment of ``d`` [s] from speed ``a`` to ``b``
    [rad/s] (linear or cosine blend); ``sin``: `math.sin` for a float, `numpy.sin` for arrays."""
    if linear:
        return d * (a * s + 0.5 * (b - a) * s * s)
    return d * (a * s + 0.5 * (b - a) * (s - sin(math.pi * s) / math.pi))


def _segment_accel(s, a, b, d, linear: bool, sin):
    """Acceleration [rad/s²] a fraction ``s`` into that segment."""
    if linear:
        return (b - a) / d
    return 0.5 * (b - a) * math.pi / d * sin(math.pi * s)


class SpeedKnots:
    """WG speed through knots with cosine or linear blends; the angle in closed form.

    Cosine blends start and end every ramp with zero acceleration
    (`hdsim.simulation.profiles.cosine_ramps`); linear ones make a trapezoidal speed
    profile. Knots of zero duration are dropped.

    Parameters
    ----------
    times : array_like, shape (n,)
        Knot times [s], non-decreasing.
    speeds : array_like, shape (n,)
        WG speed at each knot [rad/s].
    shape : str
        ``"cosine"`` or ``"linear"``.
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
        self._cosine_speed = cosine_ramps(self.times, self.speeds)
        # plain lists for the scalar path the solver takes (numpy on scalars costs ~10x)
        self._tlist, self._dlist = self.times.tolist(), self.d.tolist()
        self._vlist, self._alist = self.speeds.tolist(), self.angles.tolist()

    def _scalar(self, t):
        i, s = segment_of(self._tlist, t)
        return i, s, self._vlist[i], self._vlist[i + 1], self._dlist[i]

    def _speed_at(self, s, a, b):
        return a + (b - a) * (s if self.shape == "linear" else 0.5 * (1.0 - math.cos(math.pi * s)))

    def kinematics(self, t: float) -> tuple:
        """(angle [rad], speed [rad/s], acceleration [rad/s²]) at the float ``t`` [s], one lookup."""
        i, s, a, b, d = self._scalar(t)
        linear = self.shape == "linear"
        beyond = max(t - self._tlist[-1], 0.0) * self._vlist[-1]
        angle = self._alist[i] + _segment_angle(s, a, b, d, linear, math.sin) + beyond
        inside = self._tlist[0] <= t <= self._tlist[-1]
        return angle, self._speed_at(s, a, b), _segment_accel(s, a, b, d, linear, math.sin) if inside else 0.0

    def _locate(self, t):
        t = np.asarray(t, dtype=float)
        i = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 2)
        s = np.clip((t - self.times[i]) / self.d[i], 0.0, 1.0)
        return t, i, s, self.speeds[i], self.speeds[i + 1], self.d[i]

    def speed(self, t):
        """WG speed [rad/s] at ``t`` [s] (a float or an array)."""
        if isinstance(t, float):
            _, s, a, b, _ = self._scalar(t)
            return self._speed_at(s, a, b)
        if self.shape != "linear":
            return self._cosine_speed(np.asarray(t, dtype=float))
        t, i, s, a, b, d = self._locate(t)
        return a + (b - a) * s

    def accel(self, t):
        """WG acceleration [rad/s²] at ``t`` [s]; 0 outside the knots."""
        if isinstance(t, float):
            return self.kinematics(t)[2]
        t, i, s, a, b, d = self._locate(t)
        inside = (t >= self.times[0]) & (t <= self.times[-1])
        return np.where(inside, _segment_accel(s, a, b, d, self.shape == "linear", np.sin), 0.0)

    def angle(self, t):
        """WG angle [rad] at ``t`` [s], 0 at the first knot; the last speed holds after the last knot."""
        if isinstance(t, float):
            return self.kinematics(t)[0]
        t, i, s, a, b, d = self._locate(t)
        beyond = np.maximum(t - self.times[-1], 0.0) * self.speeds[-1]
        return self.angles[i] + _segment_angle(s, a, b, d, self.shape == "linear", np.sin) + beyond

    def motion(self, windows: dict, description: str) -> Motion:
        """This profile as a `Motion` with the metric ``windows`` {name: (start, end) [s]}."""
        return Motion(self.angle, self.speed, self.accel, float(self.times[-1]), windows,
                      float(np.max(np.abs(self.speeds))), description, self.kinematics)


def constant_speed_motion(speed, ratio, ramp_s, revolutions, settle_revolutions) -> Motion:
    """Ramp up, then cruise for ``settle_revolutions + revolutions`` output turns.

    Parameters
    ----------
    speed : float
        WG cruise speed [rad/s], non-zero.
    ratio : float
        Transmission ratio N (WG turns per output turn).
    ramp_s : float
        Cosine ramp time [s].
    revolutions, settle_revolutions : float
        Measured output turns, and the turns cruised before them.

    Returns
    -------
    Motion
        Window ``constant``: the last ``revolutions`` output turns.
    """
    cruise = (settle_revolutions + revolutions) * TWO_PI * abs(ratio) / abs(speed)
    knots = SpeedKnots([0.0, ramp_s, ramp_s + cruise], [0.0, speed, speed])
    t1 = ramp_s + cruise
    t0 = t1 - revolutions * TWO_PI * abs(ratio) / abs(speed)
    return knots.motion({"constant": (t0, t1)}, "constant speed")


def reversal_motion(speed, ratio, ramp_s, revolutions, settle_revolutions, dwell_s) -> Motion:
    """Forward and back over the same output angles.

    Ramp up, cruise, ramp down, dwell, the same reversed, dwell. Both cruises cover the
    same output angles.

    Parameters
    ----------
    speed : float
        WG cruise speed [rad/s], non-zero.
    ratio : float
        Transmission ratio N.
    ramp_s : float
        Cosine ramp time [s].
    revolutions, settle_revolutions : float
        Measured output turns of each cruise, and the turns cruised before them.
    dwell_s : float
        Standstill after each ramp down [s].

    Returns
    -------
    Motion
        Windows ``forward`` and ``reverse``: the last ``revolutions`` of each cruise.
    """
    cruise = (settle_revolutions + revolutions) * TWO_PI * abs(ratio) / abs(speed)
    measured = revolutions * TWO_PI * abs(ratio) / abs(speed)
    steps = [ramp_s, cruise, ramp_s, dwell_s, ramp_s, cruise, ramp_s, dwell_s]
    times = np.concatenate([[0.0], np.cumsum(steps)])
    speeds = [0.0, speed, speed, 0.0, 0.0, -speed, -speed, 0.0, 0.0]
    knots = SpeedKnots(times, speeds)
    windows = {"forward": (times[2] - measured, times[2]), "reverse": (times[6] - measured, times[6])}
    return knots.motion(windows, "reversal")


def sweep_motion(speeds, ramp_s, revolutions, settle_revolutions, dwell_s) -> Motion:
    """A friction sweep: each speed forward and back, with a standstill between.

    For every speed: ramp up, cruise ``settle_revolutions + revolutions`` WG turns, ramp
    down, dwell, the same reversed, dwell.

    Parameters
    ----------
    speeds : sequence of float
        WG speeds [rad/s], non-zero.
    ramp_s : float
        Cosine ramp time [s].
    revolutions, settle_revolutions : float
        Measured WG turns of each cruise (whole turns average out a ripple), and the turns
        cruised before them.
    dwell_s : float
        Standstill after each ramp down [s].

    Returns
    -------
    Motion
        Windows ``sweep_{i}_forward`` and ``sweep_{i}_reverse``: the last ``revolutions``
        WG turns of each cruise, ``i`` the index into ``speeds``.
    """
    times, values, windows = [0.0], [0.0], {}
    for i, v in enumerate(speeds):
        v = abs(float(v))
        cruise = (settle_revolutions + revolutions) * TWO_PI / v
        measured = revolutions * TWO_PI / v
        for name, sign in (("forward", 1.0), ("reverse", -1.0)):
            t = times[-1]
            times += [t + ramp_s, t + ramp_s + cruise, t + 2 * ramp_s + cruise, t + 2 * ramp_s + cruise + dwell_s]
            values += [sign * v, sign * v, 0.0, 0.0]
            windows[f"sweep_{i}_{name}"] = (t + ramp_s + cruise - measured, t + ramp_s + cruise)
    return SpeedKnots(times, values).motion(windows, "sweep")


def trapezoid_motion(speed, ratio, move, ramp_s, dwell_s, back: bool) -> Motion:
    """Point-to-point: a trapezoidal WG speed profile (triangular if the move is short).

    Parameters
    ----------
    speed : float
        Largest WG speed [rad/s].
    ratio : float
        Transmission ratio N.
    move : float
        Output move [rad], signed.
    ramp_s : float
        Time to reach ``speed`` [s] (sets the acceleration).
    dwell_s : float
        Standstill after the move [s].
    back : bool
        Move back to the start after the dwell, and dwell again.

    Returns
    -------
    Motion
        Windows ``move``, ``dwell`` (and ``move_back``, ``dwell_back``).
    """
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
    """``θ_w = A (1 − cos 2πft)`` over ``cycles`` cycles (starts and ends at rest), then a dwell.

    Parameters
    ----------
    amplitude : float
        WG amplitude A [rad].
    frequency : float
        Frequency f [Hz].
    cycles : float
        Number of cycles.
    dwell_s : float
        Standstill after the last cycle [s].

    Returns
    -------
    Motion
        Window ``oscillation``: from the end of the first cycle to the end of the last
        whole one (the whole motion if fewer than two cycles).
    """
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


def csv_motion(profile: dict) -> Motion:
    """Motion through a measured profile: a C² cubic spline of the angle, zeroed at the start.

    Time is shifted to start at 0; the WG holds its last angle after the record ends.

    Parameters
    ----------
    profile : dict
        ``time`` [s] and either ``angle`` [rad] or ``speed`` [rad/s], arrays of equal
        length (as `hdsim.scenarios.profile_csv.read_profile_csv` returns them).

    Returns
    -------
    Motion
        Window ``record``: the whole record.
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
