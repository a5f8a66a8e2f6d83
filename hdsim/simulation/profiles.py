"""Ramps through waypoints: the shape shared by the locked bench's torque cycle and the
driven bench's WG speed profiles (`hdsim.simulation.motion.SpeedKnots`).

Pure functions of time, vectorised over time.
"""

from __future__ import annotations

import bisect
import math

import numpy as np


def cosine_ramps(times, levels):
    """Piecewise cosine-blended ramps through the waypoints ``(times[i], levels[i])``.

    Between two waypoints the value follows ``a + (b − a)(1 − cos πs)/2``: the rate is
    zero at every waypoint, so the turning points of a test cycle are reached without
    a velocity jump (no ringing excited, no damping lag at the reading points).

    Parameters
    ----------
    times : array_like, shape (n,)
        Strictly increasing waypoint times [s].
    levels : array_like, shape (n,)
        Value at each waypoint (any unit; the result has the same).

    Returns
    -------
    callable
        ``value(t)`` for ``t`` [s] of any shape; before the first and after the last
        waypoint the end values hold.
    """
    times = np.asarray(times, dtype=float)
    levels = np.asarray(levels, dtype=float)
    last = len(times) - 2
    # plain lists for the solver's scalar path (numpy on a float costs ~10x)
    time_list, level_list = times.tolist(), levels.tolist()

    def value(t):
        if isinstance(t, float):
            i, s = segment_of(time_list, t)
            return level_list[i] + (level_list[i + 1] - level_list[i]) * 0.5 * (1.0 - math.cos(math.pi * s))
        i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, last)
        s = np.clip((t - times[i]) / (times[i + 1] - times[i]), 0.0, 1.0)
        return levels[i] + (levels[i + 1] - levels[i]) * 0.5 * (1.0 - np.cos(np.pi * s))

    return value


def segment_of(times: list, t: float) -> tuple[int, float]:
    """The segment of the waypoint ``times`` (a list) holding the float ``t`` and how far
    through it ``t`` lies: ``(i, s)``, ``times[i] <= t <= times[i + 1]`` clamped to the first
    and last segment, ``s`` in [0, 1]. The solver's scalar path: `bisect` and plain floats,
    where numpy's search costs ten times more on one number.
    """
    i = min(max(bisect.bisect_right(times, t) - 1, 0), len(times) - 2)
    return i, min(max((t - times[i]) / (times[i + 1] - times[i]), 0.0), 1.0)


def segment_times(levels, rate):
    """Waypoint times for levels visited at a mean rate.

    Parameters
    ----------
    levels : array_like, shape (n,)
        The waypoint levels (any unit).
    rate : float
        Mean rate of change [level unit/s].

    Returns
    -------
    numpy.ndarray, shape (n,)
        Waypoint times [s], starting at 0.
    """
    steps = np.abs(np.diff(np.asarray(levels, dtype=float))) / rate
    return np.concatenate([[0.0], np.cumsum(steps)])
