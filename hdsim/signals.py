"""Signal analysis of a bench record, model-free: noise, turning points, loading direction and rates.

Pure numpy functions on arrays, used by the checks of a record (`hdsim.io.data_checks`,
`hdsim.io.running_checks`) and by the identification that fits it (its residual views,
hold-out folds and running-torque fit). They know nothing of a drive or a file, so they
sit at the bottom of the layers with `hdsim.units`.

Noise is estimated from the data alone: the record minus its local cubic fit over seven
samples (a Savitzky-Golay filter) keeps the white noise and removes any signal smooth
over seven samples, curvature included (plain second differences read the curvature of
a coarsely sampled cycle as noise). For white noise of rms σ that residual has rms
``σ √(1 − h₀)``, h₀ the filter's centre weight (1/3); its median absolute value over
0.6745 makes the estimate robust to the few steps (reversals, stick-slip) a record has.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

__all__ = ["NOISE_WINDOW", "RATE_STEP", "EVEN_SAMPLING", "GLITCH_FACTOR", "local_cubic_weights", "noise_level",
           "evenly_sampled", "smoothed", "turning_points", "torque_legs", "loading_direction", "loading_rates",
           "leg_loading", "rate_groups", "Breakaway", "angle_resolution", "breakaway_episodes", "glitches"]

#: samples of the local cubic fit that the noise estimate subtracts
NOISE_WINDOW = 7
#: two loading rates are distinct when they differ by more than this factor
RATE_STEP = 1.5
#: sample intervals within this share of their median count as even (`noise_level`)
EVEN_SAMPLING = 0.01
#: a glitch lies this many times the signal's local scale (its excursions and steps between
#: rows) away from its two neighbours: white noise never gets there
GLITCH_FACTOR = 20.0
#: rows on each side of a candidate glitch that set its local scale
GLITCH_WINDOW = 10


def local_cubic_weights(window: int) -> np.ndarray:
    """Weights that give the centre value of a least-squares cubic through ``window``
    samples (the Savitzky–Golay smoothing coefficients; Savitzky & Golay, 1964): the first
    row of the Vandermonde matrix's pseudo-inverse. Written out because importing
    ``scipy.signal`` for them costs about a second on every ``fit`` and ``diagnose``."""
    offsets = np.arange(window) - window // 2
    return np.linalg.pinv(np.vander(offsets, 4, increasing=True))[0]


def noise_level(x, time=None) -> float:
    """Rms of the white noise on a signal, estimated without a model (module text) [unit of x].

    With ``time`` [s] of a log whose sample intervals spread by more than
    `EVEN_SAMPLING` of their median (a logger's jitter), the local cubic is fitted in time,
    not in row number: a signal sampled unevenly is no smooth function of the row, and
    45 % jitter read a swing's steps as noise (an estimate 2.2 times too high). Below that
    spread the row number is the better clock: a time stamp rounded to its printed digits
    would add its own error.
    """
    x = np.asarray(x, dtype=float)
    if x.size < NOISE_WINDOW:
        return 0.0
    # about a level of its own: the weights' rounding on a large level (a constant 31.2 gave
    # 6e-15 of "noise") would otherwise be read as noise; a constant then has none
    x = x - np.median(x)
    half = NOISE_WINDOW // 2
    if time is not None and not evenly_sampled(time):
        residual, leverage = _local_cubic_in_time(x, np.asarray(time, dtype=float))
        return float(np.median(np.abs(residual) / np.sqrt(1.0 - leverage)) / 0.6745)
    weights = local_cubic_weights(NOISE_WINDOW)
    # centred windows only: the median of |residual| does not miss the few edge samples
    residual = x[half:x.size - half] - np.convolve(x, weights[::-1], mode="valid")
    # white noise of rms σ leaves σ²(1 − w₀) in x minus its local fit (w₀ the centre weight)
    return float(np.median(np.abs(residual)) / 0.6745 / math.sqrt(1.0 - weights[half]))


def evenly_sampled(time) -> bool:
    """Whether every sample interval of ``time`` is within `EVEN_SAMPLING` of their median."""
    steps = np.diff(np.asarray(time, dtype=float))
    if steps.size == 0:
        return True
    typical = float(np.median(steps))
    return bool(typical > 0 and np.max(np.abs(steps - typical)) <= EVEN_SAMPLING * typical)


def _local_cubic_in_time(x: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """At each centred window of `NOISE_WINDOW` samples: the centre value minus the least-squares
    cubic in time through the window, and the centre's leverage h (white noise of rms σ
    leaves σ²(1 − h) there).

    With τ the times from the centre, the normal matrix is ``A_ij = Σ τ^(i+j)`` and the
    centre row of the hat matrix is ``Σ_j (A⁻¹)_0j τ^j``: only sums of powers of τ, no
    design matrix per window. In chunks of a few hundred thousand windows.
    """
    half = NOISE_WINDOW // 2
    centres = np.arange(half, x.size - half)
    residual, leverage = np.empty(centres.size), np.empty(centres.size)
    for chunk in np.array_split(np.arange(centres.size), max(1, centres.size // 200_000)):
        c = centres[chunk]
        window = c[:, None] + np.arange(-half, half + 1)
        tau = t[window] - t[c][:, None]
        tau /= np.max(np.abs(tau), axis=1, keepdims=True)  # conditioning only: the fit is the same
        powers = [np.ones_like(tau), tau]
        for _ in range(5):
            powers.append(powers[-1] * tau)  # τ⁰ … τ⁶
        sums = np.stack([p.sum(axis=1) for p in powers], axis=1)  # (m, 7)
        normal = sums[:, np.add.outer(np.arange(4), np.arange(4))]  # (m, 4, 4): A_ij = S_(i+j)
        first = np.linalg.solve(normal, np.broadcast_to(np.eye(4)[:, :1], (c.size, 4, 1)))[..., 0]
        weights = sum(first[:, k:k + 1] * powers[k] for k in range(4))  # (m, window)
        residual[chunk] = x[c] - np.sum(weights * x[window], axis=1)
        leverage[chunk] = weights[:, half]
    return residual, leverage


def glitches(x) -> np.ndarray:
    """Rows of ``x`` that are isolated one-row glitches (a failed read, a dropped bit).

    A glitch lies four times further from the mean of its two neighbours than they are
    from each other, and more than `GLITCH_FACTOR` times the local scale: the largest of
    the median excursion and the median step between rows over `GLITCH_WINDOW` rows on
    each side, and the record's smallest non-zero step (an encoder's count); it must also
    exceed a quarter of that factor times the whole record's median excursion. A reversal,
    a sharp corner of a ramp, a backlash jump or a load step is a change the neighbours
    share; noise, a ripple sampled coarsely or a coarse encoder's one-count dither move
    the rows around it as much; the steep dip of a twist into the gap at a reversal near
    zero torque (seen in the truth zoo: 1.65 times its neighbours' spread) is not four
    times. Two bad rows in a row are not found.

    Parameters
    ----------
    x : array_like
        One column of a record (non-finite values are never glitches, nor their neighbours).

    Returns
    -------
    numpy.ndarray
        Indices of the glitch rows, ascending.
    """
    x = np.asarray(x, dtype=float)
    if x.size < 2 * GLITCH_WINDOW + 3:
        return np.zeros(0, dtype=int)
    steps = np.abs(np.diff(x))
    moving = steps[np.isfinite(steps) & (steps > 0)]
    count = float(moving.min()) if moving.size else 0.0
    excursion = np.full(x.size, np.nan)  # of each row from the mean of its neighbours
    with np.errstate(invalid="ignore"):
        excursion[1:-1] = np.abs(x[1:-1] - 0.5 * (x[:-2] + x[2:]))
        # a glitch also stands out of the whole record (a quarter of the factor times its median
        # excursion): that keeps the local look below to a few rows of a long noisy log
        typical = GLITCH_FACTOR / 4.0 * float(np.nanmedian(excursion[1:-1]))
        candidates = np.flatnonzero((excursion[1:-1] > 4.0 * np.abs(x[2:] - x[:-2]))
                                    & (excursion[1:-1] > max(GLITCH_FACTOR * count, typical))) + 1
    found = []
    for chunk in np.array_split(candidates, max(1, candidates.size // 100_000)):  # bounded memory
        if not chunk.size:
            continue
        around = np.clip(chunk[:, None] + np.arange(-GLITCH_WINDOW, GLITCH_WINDOW + 1), 1, x.size - 2)
        local = excursion[around]
        local[:, GLITCH_WINDOW] = np.nan  # the row itself does not set its scale
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # an all-NaN window near failed reads
            scale = np.fmax(np.fmax(np.nanmedian(local, axis=1), np.nanmedian(steps[around - 1], axis=1)), count)
            found.append(chunk[excursion[chunk] > GLITCH_FACTOR * scale])
    return np.concatenate(found) if found else np.zeros(0, dtype=int)


def smoothed(x, noise: float) -> tuple[np.ndarray, float]:
    """``x`` through a centred moving average long enough to bring ``noise`` well under its
    swing, and the noise left on it (``noise / √width``) [unit of x]. A signal without swing
    (a constant) is returned as it is."""
    x = np.asarray(x, dtype=float)
    swing = float(np.ptp(x))
    if not swing > 0:
        return x.copy(), noise
    # the window's noise is noise/√w; aim at 1 % of the swing, within 1 … n/50 samples
    longest = max(x.size // 50, 1)
    w = int(min(max(min(noise / (0.01 * swing), math.sqrt(longest)) ** 2, 1.0), longest))
    width = 2 * (w // 2) + 1
    if width <= 1:
        return x.copy(), noise
    padded = np.pad(x, width // 2, mode="edge")
    return np.convolve(padded, np.ones(width) / width, mode="valid"), noise / math.sqrt(width)


def turning_points(x, band: float) -> list[int]:
    """Indices where ``x`` turns back by more than ``band`` [unit of x] (a dead band ignores
    noise wiggles).

    Returns the first index, every turning point and ``len(x)``.
    """
    x = np.asarray(x, dtype=float)
    turns, direction = [0], 0
    extreme, extreme_i = x[0], 0
    for i in range(1, x.size):
        v = x[i]
        if direction == 0:
            if abs(v - x[0]) > band:
                direction, extreme, extreme_i = (1 if v > x[0] else -1), v, i
        elif direction * (v - extreme) > 0:
            extreme, extreme_i = v, i
        elif direction * (extreme - v) > band:
            turns.append(extreme_i)
            direction, extreme, extreme_i = -direction, v, i
    turns.append(x.size)
    return turns


def torque_legs(torque) -> tuple[np.ndarray, list[int]]:
    """The smoothed torque [N·m] and its turning points (`turning_points`), with a dead band set
    by the torque's own noise: five times the noise left after smoothing, at least 2 % of
    the swing, so the noise of a torque computed from motor current does not turn a leg."""
    T = np.asarray(torque, dtype=float)
    smooth, left = smoothed(T, noise_level(T))
    band = max(5.0 * left, 0.02 * float(np.ptp(smooth)), 1e-12)
    return smooth, turning_points(smooth, band)


def _leg_signs(smooth_torque, turns) -> np.ndarray:
    """+1 on rows of a leg loading up, −1 down (0 on a leg of one sample)."""
    sign = np.zeros(smooth_torque.size)
    for a, b in zip(turns[:-1], turns[1:]):
        sign[a:b] = np.sign(smooth_torque[b - 1] - smooth_torque[a]) if b - a > 1 else 0.0
    return sign


def loading_direction(time, torque) -> tuple[np.ndarray, np.ndarray]:
    """(sign, magnitude) of the loading at each sample: +1 loading up, −1 down, the sign of
    the leg between turning points (`torque_legs`), and |dT/dt| of the smoothed torque [N·m/s]."""
    smooth, turns = torque_legs(torque)
    return _leg_signs(smooth, turns), np.abs(np.gradient(smooth, np.asarray(time, dtype=float)))


def _leg_rates(time, smooth_torque, turns):
    """(first row, end row, mean |dT/dt| [N·m/s]) of each monotone leg between turning points
    (legs of more than two samples that take time)."""
    t = np.asarray(time, dtype=float)
    for a, b in zip(turns[:-1], turns[1:]):
        if b - a > 2 and t[b - 1] > t[a]:
            yield a, b, abs(smooth_torque[b - 1] - smooth_torque[a]) / (t[b - 1] - t[a])


def loading_rates(time, smooth_torque, turns) -> np.ndarray:
    """Mean |dT/dt| [N·m/s] of each monotone leg between turning points (legs of more than
    two samples that take time)."""
    return np.array([rate for _, _, rate in _leg_rates(time, smooth_torque, turns)])


def leg_loading(time, torque) -> tuple[np.ndarray, np.ndarray]:
    """(sign, rate) of each row's leg: the sign as `loading_direction` gives it, and the
    leg's mean |dT/dt| [N·m/s] (`loading_rates`), 0 on a leg too short to have one."""
    smooth, turns = torque_legs(torque)
    rate = np.zeros(smooth.size)
    for a, b, leg_rate in _leg_rates(time, smooth, turns):
        rate[a:b] = leg_rate
    return _leg_signs(smooth, turns), rate


def rate_groups(values, step: float = RATE_STEP) -> list[float]:
    """The median of each group ``values`` fall in, neighbours within a factor ``step`` being
    one group [unit of values]; values ≤ 0 are left out."""
    v = np.sort(np.asarray(values, dtype=float)[np.asarray(values) > 0])
    if v.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(np.log(v)) > math.log(step)) + 1
    return [float(np.median(g)) for g in np.split(v, cuts)]


@dataclass(frozen=True)
class Breakaway:
    """One start of a shaft from rest, as `breakaway_episodes` finds it.

    Attributes
    ----------
    direction : int
        +1 or −1: the way the shaft turned.
    rest, onset, stop : int
        First row of the rest before it; the last row at rest (the motion began between
        it and the next row); one past the last row of the motion.
    torque : float
        The torque at the onset, signed: the mean of the rows of the last 20 ms at rest.
    uncertainty : float
        Its standard uncertainty: the torque noise over those rows and the torque's change
        within them (the sampling of a ramp, a step of a staircase).
    held_torque : float
        Span of the smoothed torque while the shaft stood: what the rest held.
    travel : float
        The angle turned, signed [unit of the angle].
    rise_s : float
        How long the torque took, at rest, to rise from a fifth of its value at the onset to
        the onset [s]: seconds for a breakaway ramp, a blink for a speed loop breaking free.
    """

    direction: int
    rest: int
    onset: int
    stop: int
    torque: float
    uncertainty: float
    held_torque: float
    travel: float
    rise_s: float = 0.0


def angle_resolution(angle) -> float:
    """The smallest step of an angle record: an encoder's count, or the noise of an analogue
    angle [unit of the angle]."""
    x = np.asarray(angle, dtype=float)
    steps = np.abs(np.diff(x))
    moved = steps[steps > 0]
    count = float(np.percentile(moved, 10)) if moved.size else 0.0
    return max(count if moved.size > 0.02 * steps.size else 0.0, noise_level(x))


def breakaway_episodes(time, angle, torque, rest_s: float = 0.1) -> list[Breakaway]:
    """Every start of the shaft from a rest of at least ``rest_s`` [s] that turns it by five
    angle resolutions or more.

    A row is at rest when the angle spans at most three resolutions over ``rest_s``
    around it; the onset is the last row whose angle is within one resolution of the
    rest's. Model-free: the torque at the onset is the static friction the rest held
    for a breakaway, and an elastic unloading for a locked drive (whose angle then moves
    with the torque: ``held_torque`` and the torque change over the motion tell them apart).
    """
    t = np.asarray(time, dtype=float)
    x = np.asarray(angle, dtype=float)
    T = np.asarray(torque, dtype=float)
    n = x.size
    dt = float(np.median(np.diff(t))) if n > 1 else 1.0
    half = max(int(0.5 * rest_s / dt), 1)
    if n < 2 * half + 3:
        return []
    res = angle_resolution(x)
    # the angle's span over the centred window, in O(n) whatever the window (a 10 kHz record
    # has a thousand rows in 0.1 s)
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    width = 2 * half + 1
    span = maximum_filter1d(x, width, mode="nearest") - minimum_filter1d(x, width, mode="nearest")
    at_rest = np.zeros(n, dtype=bool)
    at_rest[half:n - half] = span[half:n - half] <= 3.0 * res
    # the rests: [first row, one past the last) of each run of rows at rest, in time order
    starts = np.flatnonzero(at_rest & ~np.r_[False, at_rest[:-1]])
    ends = np.flatnonzero(at_rest & ~np.r_[at_rest[1:], False]) + 1
    noise = noise_level(T, t)
    smooth, _ = smoothed(T, noise)
    average = max(int(0.02 / dt), 3)
    out = []
    for k, (r0, r1) in enumerate(zip(starts.tolist(), ends.tolist())):
        if r1 >= n - 1:
            continue  # rests to the end
        anchor = float(np.median(x[r0:r1]))
        # the angle leaves the rest within a window's half after the rest ends (the window is centred)
        look = min(n, r1 + 2 * half + 2)
        away = np.flatnonzero(np.abs(x[r0:look] - anchor) > res) + r0
        if away.size == 0:
            continue
        onset = int(away[0]) - 1
        stop = n
        if k + 1 < starts.size:  # one past the last row off the next rest's angle: the shaft stood from there
            nxt = int(starts[k + 1])
            settled = float(x[min(nxt + half, n - 1)])
            off = np.flatnonzero(np.abs(x[onset:nxt + half + 1] - settled) > res)
            stop = onset + int(off[-1]) + 1 if off.size else nxt
        travel = float(x[stop - 1] - anchor)
        if abs(travel) < 5.0 * res or onset < r0:
            continue
        rows = slice(max(r0, onset - average + 1), onset + 1)
        span = float(np.ptp(smooth[rows]))
        m = onset + 1 - rows.start
        level = float(np.mean(T[rows]))
        low = np.flatnonzero(np.abs(smooth[r0:onset + 1]) < 0.2 * abs(level))
        rise = float(t[onset] - t[r0 + low[-1]]) if low.size else float(t[onset] - t[r0])
        out.append(Breakaway(int(np.sign(travel)), r0, onset, stop, level,
                             math.hypot(noise / math.sqrt(m), span / math.sqrt(12.0)), float(np.ptp(smooth[r0:onset + 1])),
                             travel, rise))
    return out
