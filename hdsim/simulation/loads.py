"""Load torques on the output of the driven bench, as vectorised functions of time.

A `Load` gives the torque the load applies to the output [N·m] and its rate [N·m/s]
(the rate enters the load-dependent kinematic error, `hdsim.simulation.driven`). Torques
may be per sample: a scalar ``t`` then gives shape ``(M,)`` and ``t`` of shape
``(nt, 1)`` gives ``(nt, M)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from hdsim.physics.elementary import tanh

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class Load:
    """Torque applied by the load to the output, and its rate, as functions of time.

    Attributes
    ----------
    torque, rate : callable
        Load torque [N·m] and its time derivative [N·m/s] at time ``t`` [s].
    t_end : float
        Duration the load profile asks for [s] (0: set by the motion).
    windows : dict
        Name → (start, end) [s] of the intervals the metrics read.
    operating_point : float or None
        Load before a sweep starts, as a fraction of the rated torque T_N.
    sweep_start : float
        Lowest frequency of a sweep [Hz]. The response is compared from 1.5× this up,
        past the start taper, where the excitation still builds up and hysteretic loops
        are not yet periodic.
    frequency_schedule : list
        ``[(t_start [s], t_end [s], highest frequency in the load [Hz])]`` covering the
        run (a sweep's octaves): bounds the solver's step, `hdsim.simulation.solver.step_schedule`.
    at_output_speed : callable or None
        For a load that depends on how the output actually moves (a brake):
        ``at_output_speed(ω_o)`` is the torque it applies [N·m] at output speed ω_o
        [rad/s]. ``torque`` and ``rate`` are then its values along the commanded motion,
        which the load-dependent kinematic error follows (known in time, and equal at
        steady state). None: the load is ``torque(t)`` whatever the output does.
    torque_and_rate : callable or None
        Both at a float time in one call, for a load that finds them together; None:
        `at` makes the two calls.
    """

    torque: Callable
    rate: Callable
    t_end: float = 0.0
    windows: dict = field(default_factory=dict)
    operating_point: float | None = None
    sweep_start: float = 0.0
    frequency_schedule: list = field(default_factory=list)
    at_output_speed: Callable | None = None
    torque_and_rate: Callable | None = None

    def at(self, t) -> tuple:
        """Load torque [N·m] and its rate [N·m/s] at ``t`` [s] (a float or an array); the
        solver's scalar path asks for both at every call."""
        if self.torque_and_rate is not None and isinstance(t, float):
            return self.torque_and_rate(t)
        return self.torque(t), self.rate(t)


def per_sample(x):
    """A Python float for a single value (the solver's scalar path is ~4x faster on floats),
    else the array of per-sample values."""
    a = np.asarray(x, dtype=float)
    return float(a) if a.size == 1 else a


def _outer(shape, scale):
    """shape(t) × per-sample scale: scalar t → (M,), t of shape (nt, 1) → (nt, M)."""
    return shape * scale if isinstance(shape, float) else np.asarray(shape) * scale


def smoothstep(t, t0, width):
    """0 before ``t0`` [s], a cosine blend over ``width`` [s], 1 after; and its time derivative [1/s].

    Parameters
    ----------
    t : float or numpy.ndarray
        Time [s]; a float takes the scalar path and returns floats.
    t0, width : float
        Start and duration of the blend [s].

    Returns
    -------
    tuple
        (value, rate) with the shape of ``t``.
    """
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
    """A constant torque from t = 0, without a ramp (the input of a linearisation).

    Parameters
    ----------
    torque : float or array_like
        Load torque [N·m], per sample.
    """
    T = per_sample(torque)
    return Load(lambda t: np.zeros_like(np.asarray(t, dtype=float)) + T,
                lambda t: np.zeros_like(np.asarray(t, dtype=float)) + 0.0 * T)


def ramped_load(torque, ramp_s) -> Load:
    """A constant torque reached through a cosine ramp.

    Parameters
    ----------
    torque : float or array_like
        Final load torque [N·m], per sample.
    ramp_s : float
        Ramp time from 0 [s].
    """
    T = per_sample(torque)

    def both(t):
        s, ds = smoothstep(t, 0.0, ramp_s)
        return _outer(s, T), _outer(ds, T)

    return Load(lambda t: both(t)[0], lambda t: both(t)[1], torque_and_rate=both)


def opposing_load(torque, motion, smoothing_speed, ratio) -> Load:
    """A brake on the output: ``−T tanh(|N| ω_o / ω_s)``, opposing the output's actual motion.

    The brake acts on the output's own speed ω_o, so its power ``T_L ω_o`` is never
    positive: it only takes energy out, also while the output lags, overshoots or rings
    through a reversal of the command, and whatever the sign of the ratio. Its value along
    the commanded motion, ``−T tanh(|N| (ω_ref / N) / ω_s)``, is the known-in-time load
    the load-dependent kinematic error follows (`Load.at_output_speed`).

    Parameters
    ----------
    torque : float or array_like
        Magnitude T [N·m], per sample.
    motion : hdsim.simulation.motion.Motion
        The commanded WG motion (speed ω_ref [rad/s]).
    smoothing_speed : float
        ω_s, a WG speed [rad/s]: the sign switches over about this speed.
    ratio : float
        Transmission ratio N (negative when the output turns the other way).
    """
    T = per_sample(torque)
    gain = abs(ratio) / smoothing_speed  # output speed -> argument of tanh

    def at_output_speed(w_o):
        return -tanh(gain * w_o) * T

    def both(t):
        _, speed, accel = motion.at(t)
        x = gain * speed / ratio
        return _outer(-tanh(x), T), _outer(-(1.0 - tanh(x) ** 2) * gain * accel / ratio, T)

    return Load(lambda t: both(t)[0], lambda t: both(t)[1], at_output_speed=at_output_speed, torque_and_rate=both)


def step_load(initial, final, ramp_s, step_time, rise_s) -> Load:
    """A ramped-in load, then a cosine step to another value.

    Parameters
    ----------
    initial, final : float or array_like
        Load before and after the step [N·m], per sample.
    ramp_s : float
        Ramp time of the initial load [s].
    step_time : float
        Start of the step [s].
    rise_s : float
        Rise time of the step [s].

    Returns
    -------
    Load
        Windows ``before_step`` (end of the ramp to the step) and ``after_step``.
    """
    T0, T1 = per_sample(initial), per_sample(final)

    def value(t):
        a, _ = smoothstep(t, 0.0, ramp_s)
        b, _ = smoothstep(t, step_time, rise_s)
        return _outer(a, T0) + _outer(b, T1 - T0)

    def rate(t):
        _, da = smoothstep(t, 0.0, ramp_s)
        _, db = smoothstep(t, step_time, rise_s)
        return _outer(da, T0) + _outer(db, T1 - T0)

    windows = {"before_step": (ramp_s, step_time), "after_step": (step_time, np.inf)}
    return Load(value, rate, windows=windows)


def sweep_load(preload, amplitude, f_start, f_stop, ramp_s, settle_s, sweep_s, tail_s) -> Load:
    """Preload ramped in, rest, exponential sine sweep ``f_start → f_stop`` with tapered ends, rest.

    Parameters
    ----------
    preload, amplitude : float or array_like
        Operating-point load and sweep amplitude [N·m], per sample.
    f_start, f_stop : float
        Sweep frequencies [Hz].
    ramp_s, settle_s, sweep_s, tail_s : float
        Preload ramp, rest before the sweep, sweep and rest after it [s].

    Returns
    -------
    Load
        Window ``sweep`` (from the sweep start to the end: the response has decayed by
        then; the record the frequency response is estimated from) and ``before_sweep``.
    """
    P, A = per_sample(preload), per_sample(amplitude)
    t_s = ramp_s + settle_s
    tau = sweep_s / np.log(f_stop / f_start)
    taper = min(0.1 * sweep_s, 3.0 / f_start)

    def parts(t):
        t = np.asarray(t, dtype=float)
        x = np.clip(t - t_s, 0.0, sweep_s)
        phase = TWO_PI * f_start * tau * (np.exp(x / tau) - 1.0)
        dphase = TWO_PI * f_start * np.exp(x / tau)
        up, dup = smoothstep(t, t_s, taper)
        down, ddown = smoothstep(t, t_s + sweep_s - taper, taper)
        w, dw = up * (1.0 - down), dup * (1.0 - down) - up * ddown
        on = (t >= t_s) & (t <= t_s + sweep_s)
        return np.where(on, w * np.sin(phase), 0.0), np.where(on, dw * np.sin(phase) + w * np.cos(phase) * dphase, 0.0)

    def value(t):
        s, _ = smoothstep(t, 0.0, ramp_s)
        c, _ = parts(t)
        return _outer(s, P) + _outer(c, A)

    def rate(t):
        _, ds = smoothstep(t, 0.0, ramp_s)
        _, dc = parts(t)
        return _outer(ds, P) + _outer(dc, A)

    t_end = t_s + sweep_s + tail_s
    return Load(value, rate, t_end, {"sweep": (t_s, t_end), "before_sweep": (ramp_s, t_s)})


def csv_load(profile: dict) -> Load:
    """Measured load torque through a smoothing spline (its rate enters the kinematic error).

    Parameters
    ----------
    profile : dict
        ``time`` [s] and ``torque`` [N·m] arrays (as
        `hdsim.scenarios.profile_csv.read_profile_csv` returns them).
    """
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


#: no load: zero torque and rate
NO_LOAD = Load(_zero, _zero)
