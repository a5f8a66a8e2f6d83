"""Pure profile builders: time → input, vectorised over time."""

from __future__ import annotations

import numpy as np


def cosine_ramps(times, levels):
    """Piecewise cosine-blended ramps through ``(times[i], levels[i])``.

    Between two waypoints the value follows ``a + (b − a)(1 − cos πs)/2``: the rate is
    zero at every waypoint, so the turning points of a test cycle are reached without
    a velocity jump (no ringing excited, no damping lag at the reading points).
    Returns a function of time; ``levels`` may have a trailing batch axis.
    """
    times = np.asarray(times, dtype=float)
    levels = np.asarray(levels, dtype=float)
    last = len(times) - 2

    def value(t):
        i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, last)
        s = np.clip((t - times[i]) / (times[i + 1] - times[i]), 0.0, 1.0)
        return levels[i] + (levels[i + 1] - levels[i]) * 0.5 * (1.0 - np.cos(np.pi * s))

    return value


def segment_times(levels, rate):
    """Waypoint times [s] for levels visited at ``rate`` (level units per second on average)."""
    steps = np.abs(np.diff(np.asarray(levels, dtype=float))) / rate
    return np.concatenate([[0.0], np.cumsum(steps)])
