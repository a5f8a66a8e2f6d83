"""Checks of a running-torque record (a friction sweep) before any fit, and its plateaus.

A running-torque test turns the drive at constant speeds, both ways, and logs the torque
it needs. Before a fit the record is checked, without any model, against that claim and
against the drive's catalog (docs/measurements.md, "Checks before any fit"):

| check | fail / warn when |
|---|---|
| ``turns_steadily`` (identity) | no plateau of constant speed, or every start follows a torque raised at rest for half a second or more: a locked or breakaway test |
| ``torque_opposes_motion`` | the torque does not change sign with the direction on most plateaus: an offset or a load larger than the friction |
| ``speeds`` | one speed only: a viscous loss cannot be told from a Coulomb level |
| ``reversals`` | one direction only: an asymmetry cannot be seen |
| ``torque_side`` | the level is 30× above or below the catalog running torque on the named side |
| ``temperature`` | the logged temperature spans more than 10 °C (grease friction changes with it) |
| ``torque_noise`` | the torque noise exceeds half the running level |

Speed comes from the WG angle by Savitzky–Golay differentiation (Savitzky & Golay,
Anal. Chem. 36, 1964); the plateaus are runs of one sign within 5 % of their mean on a
speed smoothed over 0.1 s, trimmed to the rows whose speed has settled (`sweep_kinematics`,
`settled_span`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hdsim.io.check import Check, constant_torque
from hdsim.io.data_checks import ratio_consistency
from hdsim.signals import breakaway_episodes, noise_level

__all__ = ["Segment", "shaft_sign", "speed_and_acceleration", "sweep_kinematics", "settled_span",
           "constant_speed_segments", "distinct_speeds",
           "running_checks", "sweep_torque_sign", "turn_speed", "whole_turns", "turn_mean", "running_levels",
           "PLATEAU_TOLERANCE"]

#: a plateau: the speed stays within this fraction of its running mean
PLATEAU_TOLERANCE = 0.05
#: a plateau row has settled when its smoothed speed is within this many standard deviations
#: of the plateau's speed noise (or ripple) of the plateau's speed
SETTLED_SIGMAS = 4.0
#: ... or within this fraction of it, whichever is wider: a noise-free record has no noise to
#: judge by, and an inertia torque J·dω/dt of a tail inside it is a fraction of a per cent
SETTLED_FLOOR = 0.005
#: a plateau turns the wave generator at least this far [rad]
MIN_TRAVEL = 1.0
#: two plateau speeds are distinct when they differ by more than this factor
SPEED_STEP = 1.25
#: the running level may be this many times the catalog's either way before the side is questioned
SIDE_FACTOR = 30.0
#: a torque raised at rest for this long before every start is a breakaway ramp, not a sweep's
#: speed loop winding up against stiction (tens of milliseconds) [s]
BREAKAWAY_RISE_S = 0.5
#: a temperature span above this changes grease friction noticeably [K]
TEMPERATURE_SPAN = 10.0
#: torque noise over the running level above which the record says little
NOISE_SHARE = 0.5
#: a torque against the motion on this share of the plateaus or more was logged with the other sign
SIGN_SHARE = 0.75
RPM_PER_RAD_S = 30.0 / math.pi
#: a gap in the time stamps up to this many sample intervals is bridged by interpolation
#: when differentiating the angle (dropped rows); a longer one is a pause that splits the record
MAX_BRIDGE = 100
#: a sample interval within this of a whole number of the typical one counts as that many
#: (a jittered stamp: one; a dropped row: two) when differentiating the angle
WHOLE_INTERVAL = 0.45


@dataclass(frozen=True)
class Segment:
    """A constant-speed plateau: rows ``start:stop`` at WG speed ``speed`` [rad/s]."""

    start: int
    stop: int
    speed: float


def speed_and_acceleration(time, angle, window_s: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Speed [rad/s] and acceleration [rad/s²] from an angle by Savitzky–Golay derivatives.

    The windows span about ``window_s`` (speed) and twice that (acceleration), at least 7
    and 11 samples: long enough to average encoder steps, short enough to follow a ramp.
    A log with dropped rows is bridged: its clock counts sample intervals, not rows (the
    angle interpolated across each gap), and a log whose intervals are no whole numbers of
    the typical one is read in time; a gap longer than `MAX_BRIDGE` intervals splits it.
    """
    # imported here: scipy.signal costs about 0.4 s, and only a sweep's record needs it (a
    # command on a locked record registers the running-torque kind without running it)
    from scipy.signal import savgol_filter

    t = np.asarray(time, dtype=float)
    x = np.asarray(angle, dtype=float)
    if x.size < 5:  # too few rows for a cubic's derivatives (a stretch between pauses)
        speed = np.gradient(x, t) if x.size > 1 else np.zeros(x.size)
        return speed, (np.gradient(speed, t) if x.size > 1 else np.zeros(x.size))
    dt = float(np.median(np.diff(t)))
    pauses = np.flatnonzero(np.diff(t) > MAX_BRIDGE * dt) + 1
    if pauses.size:  # a logger's pause is not bridged: each stretch between pauses on its own
        parts = [speed_and_acceleration(t[a:b], x[a:b], window_s) if b - a > 1 else (np.zeros(b - a),) * 2
                 for a, b in zip(np.r_[0, pauses], np.r_[pauses, x.size])]
        return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
    # a dropped row is a gap of two or more sample intervals: the clock counts the intervals
    # (jittered stamps round to one each, so an unbroken log stays as it was read, by row), the
    # gaps are bridged by the angle interpolated on it, and the derivatives are read back at
    # each row's count; intervals that are no whole number of the typical one (a log thinned
    # after rows were dropped: 1.5 of them) are read in time, on an even clock of that interval
    # (docs/measurements.md, "Checks before any fit")
    ratio = np.diff(t) / dt
    steps = np.maximum(np.rint(ratio), 1.0)
    if np.all(np.abs(ratio - steps) < WHOLE_INTERVAL):
        count = np.r_[0.0, np.cumsum(steps)]
    else:
        count = (t - t[0]) / dt
    clock = np.arange(math.floor(count[-1]) + 1.0)
    gaps = clock.size != x.size
    xs = np.interp(clock, count, x) if gaps else x
    fs = 1.0 / dt
    w1 = min(max(2 * int(0.5 * window_s * fs) + 1, 7), _odd_below(xs.size))
    w2 = min(max(2 * int(window_s * fs) + 1, 11), _odd_below(xs.size))
    speed = savgol_filter(xs, w1, 3, deriv=1, delta=dt, mode="interp")
    accel = savgol_filter(xs, w2, 3, deriv=2, delta=dt, mode="interp")
    if gaps:
        speed, accel = np.interp(count, clock, speed), np.interp(count, clock, accel)
    return speed, accel


def sweep_kinematics(time, angle) -> tuple[np.ndarray, np.ndarray, list]:
    """Speed, acceleration and plateaus of a sweep.

    The plateaus are found on a smoothed speed, two ways, and the way that finds more
    steady rows is kept: a speed smoothed over 0.1 s (an encoder's steps make a 10 ms
    derivative useless at a few rad/s), and the speed averaged over one wave-generator
    turn centred on each row (a servo's speed ripples at the orders of the WG angle, with
    the torque ripple it fights; within 0.1 s at a few hundred rpm that ripple is not
    averaged out, and the plateau falls into pieces a fraction of a turn long). Each
    plateau is trimmed by 0.05 s at both ends (the reach of the 0.1 s smoothing) and then
    to its settled rows (`settled_span`): a run within 5 % of its mean still holds the
    tail of a ramp, and a slow ramp at speed is itself such a run, where the torque holds
    J·dω/dt. On each plateau the speed is the slope of the angle fitted over the whole
    plateau and the acceleration is zero. Elsewhere (the ramps) the 10 ms derivatives
    stand. A plateau must turn the wave generator by `MIN_TRAVEL` at least.

    Returns
    -------
    tuple
        ``(speed [rad/s], acceleration [rad/s²], list of Segment)``.
    """
    t = np.asarray(time, dtype=float)
    x = np.asarray(angle, dtype=float)
    speed, accel = speed_and_acceleration(t, x)
    smooth, _ = speed_and_acceleration(t, x, window_s=0.1)
    trim = max(int(0.05 / float(np.median(np.diff(t)))), 3)
    best = []
    for averaged in (smooth, np.where(np.isfinite(turn := turn_speed(t, x)), turn, smooth)):
        found = []
        for seg in constant_speed_segments(t, averaged):
            start, stop = settled_span(t, smooth, seg.start + trim, seg.stop - trim)
            if stop - start < 10:
                continue
            slope = float(np.polyfit(t[start:stop] - t[start], x[start:stop], 1)[0])
            if abs(slope) * (t[stop - 1] - t[start]) < MIN_TRAVEL:
                continue  # a slow drift or the crest of a wobble, not a run
            found.append(Segment(start, stop, slope))
        if sum(s.stop - s.start for s in found) > sum(s.stop - s.start for s in best):
            best = found
    for seg in best:
        speed[seg.start:seg.stop] = seg.speed
        accel[seg.start:seg.stop] = 0.0
    return speed, accel, best


def settled_span(time, speed, start: int, stop: int) -> tuple[int, int]:
    """The settled rows ``start:stop`` of a plateau candidate, model-free; an empty span
    (``start, start``) when it has none: the candidate is a stretch of a ramp.

    Why: the measured torque of a row holds the inertia torque ``J·dω/dt`` while the speed
    still changes, and the mean over a plateau's rows is the running torque reported for
    it (docs/measurements.md, "Checks before any fit"). A run within 5 % of its mean
    (`constant_speed_segments`) holds the tail of the ramp before it, and on a slow ramp
    at speed it is a stretch of the ramp itself.

    ``speed`` is the record's smoothed speed [rad/s]; its acceleration is its slope. What
    the plateau's speed is, and how much its speed and acceleration wander when settled,
    come from the middle half of the candidate (a ramp's tail is at the ends): the median
    speed, and the standard deviations about their straight-line trends of the speed and
    the acceleration there (a servo's speed ripple and an encoder's steps are that
    wander; a median absolute deviation is not used: an encoder's steps leave most rows of
    a slow plateau on one value and their deviation 0). A row has settled when its speed
    is within `SETTLED_SIGMAS` deviations of the plateau's speed and its acceleration
    within as many of zero, or, where the record is quieter than that, when its speed is
    within `SETTLED_FLOOR` of the plateau's speed and its acceleration would change the
    speed by less than that over the candidate. The span runs from the row after the last
    unsettled row of the first half to the first unsettled row of the second half.
    """
    n = stop - start
    if n < 4:
        return start, start
    t = np.asarray(time, dtype=float)[start:stop]
    v = np.asarray(speed, dtype=float)[start:stop]
    accel = np.gradient(v, t)
    core = slice(n // 4, n - n // 4)
    level = float(np.median(v[core]))
    duration = max(float(t[-1] - t[0]), float(np.finfo(float).tiny))
    speed_band = max(SETTLED_SIGMAS * _wander(t[core], v[core]), SETTLED_FLOOR * abs(level))
    accel_band = max(SETTLED_SIGMAS * _wander(t[core], accel[core]), SETTLED_FLOOR * abs(level) / duration)
    unsettled = (np.abs(v - level) > speed_band) | (np.abs(accel) > accel_band)
    half = n // 2
    before = np.flatnonzero(unsettled[:half])
    after = np.flatnonzero(unsettled[half:])
    first = start + (int(before[-1]) + 1 if before.size else 0)
    last = start + half + (int(after[0]) if after.size else n - half)
    return (first, last) if last > first else (start, start)


def _wander(t, values) -> float:
    """Standard deviation of ``values`` about their straight-line trend in ``t``."""
    tau = t - t[0]
    return float(np.std(values - np.polyval(np.polyfit(tau, values, 1), tau)))


def turn_speed(time, angle) -> np.ndarray:
    """The speed averaged over one wave-generator turn centred on each row [rad/s] (NaN where
    the record does not hold half a turn of travel on either side)."""
    t = np.asarray(time, dtype=float)
    x = np.asarray(angle, dtype=float)
    travel = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)))])
    lo = np.searchsorted(travel, travel - math.pi, side="right") - 1
    hi = np.searchsorted(travel, travel + math.pi, side="left")
    inside = (lo >= 0) & (hi < x.size) & (travel - math.pi >= 0)
    out = np.full(x.size, np.nan)
    a, b = lo[inside], hi[inside]
    span = t[b] - t[a]
    ok = span > 0
    out[np.flatnonzero(inside)[ok]] = (x[b] - x[a])[ok] / span[ok]
    return out


def whole_turns(angle, segments, direction: int) -> np.ndarray:
    """Rows of whole wave-generator turns on the plateaus of one direction (+1 forward, −1
    reverse): from each plateau's first row, as many whole turns as it holds. Over them a
    ripple at the orders of the WG angle averages out, so their mean torque is the running
    torque whatever the ripple (one definition for the checks, the fit's metrics and the
    figures)."""
    x = np.asarray(angle, dtype=float)
    mask = np.zeros(x.size, dtype=bool)
    for seg in segments:
        if np.sign(seg.speed) != direction:
            continue
        gone = np.maximum.accumulate(np.abs(x[seg.start:seg.stop] - x[seg.start]))
        turns = math.floor(float(gone[-1]) / (2.0 * math.pi)) if gone.size else 0
        if turns >= 1:
            end = seg.start + int(np.searchsorted(gone, turns * 2.0 * math.pi))
            mask[seg.start:end] = True
    return mask


def _odd_below(n: int) -> int:
    return n if n % 2 else n - 1


def constant_speed_segments(time, speed, tolerance: float = PLATEAU_TOLERANCE,
                            min_duration: float = 0.05, min_rows: int = 10) -> list[Segment]:
    """The plateaus of a speed record: runs of one sign within ``tolerance`` of their mean.

    Parameters
    ----------
    time : array_like
        Time [s].
    speed : array_like
        Speed [rad/s].
    tolerance : float
        Largest relative deviation from the running mean of the plateau [-].
    min_duration : float
        Shortest plateau [s].
    min_rows : int
        Fewest rows of a plateau.

    Returns
    -------
    list of Segment
        In time order.
    """
    t = np.asarray(time, dtype=float)
    w = np.asarray(speed, dtype=float)
    top = float(np.max(np.abs(w))) if w.size else 0.0
    out: list[Segment] = []
    start, total = 0, 0.0
    for i in range(w.size):
        n = i - start
        mean = total / n if n else w[i]
        if n and (abs(w[i] - mean) > tolerance * abs(mean) or abs(mean) < 1e-3 * top):
            _close(out, t, start, i, total / n, min_duration, min_rows, top)
            start, total = i, 0.0
        total += w[i]
    if w.size:
        _close(out, t, start, w.size, total / max(w.size - start, 1), min_duration, min_rows, top)
    return out


def _close(out, t, start, stop, mean, min_duration, min_rows, top):
    if stop - start >= min_rows and t[stop - 1] - t[start] >= min_duration and abs(mean) >= 1e-3 * top:
        out.append(Segment(int(start), int(stop), float(mean)))




def shaft_sign(meas) -> float:
    """+1, or −1 for a torque on the output of a drive whose output turns against the wave
    generator (a negative ratio): a torque is signed with the motion of the shaft it is on,
    and ``shaft_sign × torque`` has the sign of the WG's motion."""
    negative = meas.torque_side == "output" and meas.ratio is not None and float(meas.ratio) < 0
    return -1.0 if negative else 1.0


def side_factor(meas) -> float:
    """File torque over WG-shaft torque: the ratio for a torque on the output, else 1."""
    return float(meas.ratio) if meas.torque_side == "output" and meas.ratio is not None else 1.0


def plateau_levels(meas, segments) -> np.ndarray:
    """Each plateau's median torque [N·m, the file's shaft] with the sign of the WG's motion
    (`shaft_sign`: the output turns against the WG for a negative ratio)."""
    torque = np.asarray(meas.torque, dtype=float)
    return shaft_sign(meas) * np.array([float(np.median(torque[s.start:s.stop])) for s in segments])


def running_levels(torque, angle, segments) -> dict:
    """The running torque of each direction, model-free: the mean torque magnitude over the
    whole WG turns of its plateaus (`whole_turns`), per unit of angle (`turn_mean`) [unit of
    the torque], and the turns it rests on; None for a direction with less than one whole turn."""
    T = np.asarray(torque, dtype=float)
    out = {}
    for name, direction in (("forward", 1), ("reverse", -1)):
        rows = whole_turns(angle, segments, direction)
        turns = sum(math.floor(_turns(angle, s)) for s in segments if np.sign(s.speed) == direction)
        out[name] = turn_mean(direction * T, angle, rows) if rows.any() else None
        out[name + "_turns"] = int(turns)
    return out


def turn_mean(values, angle, rows) -> float:
    """The mean of ``values`` over ``rows`` per unit of WG angle, not per sample: a servo runs
    slower where the torque ripple holds it back, so a time average over whole turns keeps
    part of the ripple; weighted by each row's angle increment it averages out."""
    weights = np.abs(np.gradient(np.asarray(angle, dtype=float)))[rows]
    v = np.asarray(values, dtype=float)[rows]
    return float(np.average(v, weights=weights)) if weights.sum() > 0 else float(np.mean(v))


def _turns(angle, seg) -> float:
    x = np.asarray(angle, dtype=float)
    return float(np.abs(x[seg.stop - 1] - x[seg.start])) / (2.0 * math.pi)


def distinct_speeds(segments) -> list[float]:
    """The distinct plateau speeds [rad/s], ascending (within a factor `SPEED_STEP` they are one)."""
    speeds = sorted(abs(s.speed) for s in segments)
    out: list[float] = []
    for v in speeds:
        if not out or v > SPEED_STEP * out[-1]:
            out.append(v)
    return out


def sweep_torque_sign(meas):
    """The sweep with its torque in the sign docs/measurements.md gives (the torque needed to turn the drive has
    the sign of the motion), and the check that says whether it was turned.

    The friction of a free or evenly loaded drive opposes its motion, so the torque that turns
    it has the motion's sign. A median plateau torque against the motion on `SIGN_SHARE` of the
    plateaus or more was logged with the other sign (the torque the drive delivers back, a
    sensor mounted the other way, a motor current of the other sense), and is negated when that
    reading is the only one: with both directions (the torque reverses with the motion, always
    against it: no load does that), or in one direction when its magnitude grows from the
    slowest plateau to the fastest (a loss grows with speed; a load that drove the shaft would
    leave less torque at speed). In one direction at one speed a torque against the motion may
    be either: the record is refused (`InputError`). Else the record is returned as it is, and
    ``torque_opposes_motion`` of `running_checks` says what it sees.
    """
    torque = np.asarray(meas.torque, dtype=float)
    if meas.wg_angle is None or torque.size < 10 or np.ptp(torque) == 0.0:
        return meas, []
    _, _, segments = sweep_kinematics(meas.time, meas.wg_angle)
    if not segments:
        return meas, []
    levels = plateau_levels(meas, segments)
    speeds = np.array([s.speed for s in segments])
    against = np.sign(levels) == -np.sign(speeds)
    if np.mean(against) < SIGN_SHARE:
        return meas, []
    told = f"the torque is against the motion on {int(against.sum())} of {len(segments)} plateaus"
    if len(set(np.sign(speeds).tolist())) > 1:
        if not all(np.mean(against[np.sign(speeds) == way]) >= SIGN_SHARE for way in (1.0, -1.0)):
            return meas, []  # against one way only: a load larger than the friction; `torque_opposes_motion` says
        why = "it reverses with the direction, always against it"
    elif len(distinct_speeds(segments)) > 1:
        slow, fast = np.argmin(np.abs(speeds)), np.argmax(np.abs(speeds))
        if abs(levels[fast]) <= abs(levels[slow]):
            return meas, []  # a load that drives the shaft, less of it left at speed: `torque_opposes_motion` says
        why = (f"one direction, and its magnitude grows with speed ({abs(levels[slow]):.3g} N·m at "
               f"{abs(speeds[slow]) * RPM_PER_RAD_S:.3g} rpm, {abs(levels[fast]):.3g} N·m at "
               f"{abs(speeds[fast]) * RPM_PER_RAD_S:.3g} rpm) as a loss does")
    else:
        from hdsim.errors import InputError

        raise InputError(f"{meas.source or 'the record'}: {told}, in one direction at one speed: either the "
                         "torque was logged with the other sign or a load drove the shaft, and this sweep cannot "
                         "tell which; record a second speed or the other direction, or negate the torque "
                         "(columns={'torque_Nm': '-1*COLUMN'}) if its sign is the other way")
    return negated_torque(meas, f"{told} ({why})")


def negated_torque(meas, told: str) -> tuple:
    """``meas`` with its torque negated, and the ``torque_sign`` warning that says so after
    ``told`` (what showed it): a sweep's and a breakaway ramp's."""
    from dataclasses import replace

    return replace(meas, torque=-np.asarray(meas.torque, dtype=float)), [Check(
        "torque_sign", "warn", f"{told}: the torque was logged with the other sign (the torque the drive "
        "delivers back, or a sensor or current of the other sense); it is negated for the checks and fits")]


def running_checks(meas, drive) -> tuple[list, dict]:
    """The checks of a running-torque record and its data summary.

    Parameters
    ----------
    meas : hdsim.io.measurement.Measurement
        A ``running_torque`` record.
    drive : hdsim.io.data_checks.DriveScale
        The datasheet numbers (catalog running torque on the input, ratio).

    Returns
    -------
    tuple of (list of Check, dict)
        The checks and ``noise_floor_Nm``, ``torque_noise_Nm``, ``plateaus``, ``speeds_rpm``,
        ``reversals`` and, with a temperature column, ``temperature_span_K``.
    """
    torque = np.asarray(meas.torque, dtype=float)
    noise = noise_level(torque, meas.time)
    data = {"noise_floor_Nm": noise, "torque_noise_Nm": noise, "plateaus": 0, "speeds_rpm": [], "reversals": 0}
    if np.ptp(torque) == 0.0:  # nothing to fit: a law of level 0 would leave no residual and no noise
        return [constant_torque(torque[0])], data
    _, _, segments = sweep_kinematics(meas.time, meas.wg_angle)
    checks = []
    starts = breakaway_episodes(meas.time, meas.wg_angle, torque)
    if starts and all(s.rise_s >= BREAKAWAY_RISE_S for s in starts):
        checks.append(Check("turns_steadily", "fail", f"every start from rest ({len(starts)}) follows a torque "
                             f"raised over {min(s.rise_s for s in starts):.2g} s or more while the drive stood: "
                             "this looks like a breakaway test (--test breakaway), not a friction sweep"))
        return checks, {**data, "plateaus": len(segments)}
    if not segments:
        checks.append(Check("turns_steadily", "fail", "the drive never turns at a steady speed: this looks like "
                             "a locked (stiffness) or breakaway test, not a friction sweep"))
        return checks, data
    speeds = distinct_speeds(segments)
    reversals = int(sum(np.sign(a.speed) != np.sign(b.speed) for a, b in zip(segments, segments[1:])))
    data.update(plateaus=len(segments), speeds_rpm=[v * RPM_PER_RAD_S for v in speeds], reversals=reversals)
    steady_rows = sum(s.stop - s.start for s in segments)
    checks.append(Check("turns_steadily", "ok", f"{len(segments)} plateau(s) of constant speed at "
                         f"{', '.join(f'{v * RPM_PER_RAD_S:.3g}' for v in speeds)} rpm of the wave generator: "
                         f"{steady_rows} of {torque.size} rows; the rest (ramps, rests, idle legs) enter the "
                         "fit only where the drive moves"))
    shaft, levels = shaft_sign(meas), plateau_levels(meas, segments)
    follows = [np.sign(level) == np.sign(s.speed) for level, s in zip(levels, segments)]
    directions = {int(np.sign(s.speed)) for s in segments}
    if np.mean(follows) < SIGN_SHARE:
        checks.append(Check("torque_opposes_motion", "warn", f"the torque has the sign of the motion on "
                             f"{sum(follows)} of {len(follows)} plateaus: an offset or a load larger than the "
                             "friction, or the torque's sign convention is the other way"))
    elif len(directions) < 2:
        checks.append(Check("torque_opposes_motion", "ok", "the torque has the sign of the motion (one direction "
                             "recorded: whether it reverses with the direction is not seen)"))
    else:
        checks.append(Check("torque_opposes_motion", "ok", "the torque changes sign with the direction"))
    ratio = ratio_consistency(meas, "warn", drive)  # with both angles logged, a wrong ratio scales an output torque
    if ratio is not None and ratio.status != "ok":
        checks.append(Check(ratio.check, ratio.status, ratio.message + (
            ": the torque on the output is referred to the input by it" if meas.torque_side == "output" else "")))
    run = running_levels(shaft * torque, meas.wg_angle, segments)
    data.update({f"running_torque_{k}_Nm" if not k.endswith("turns") else f"running_torque_{k}": v
                 for k, v in run.items()})
    shown = [f"{run[w]:.4g} N·m {w} over {run[w + '_turns']} whole WG turn(s)" for w in ("forward", "reverse")
             if run[w] is not None]
    short = [w for w, d in (("forward", 1), ("reverse", -1)) if d in directions and run[w] is None]
    checks.append(Check("running_torque", "warn" if short else "ok", "running torque on the "
                         f"{meas.torque_side} shaft: " + ("; ".join(shown) or "none") + (
                             f"; {' and '.join(short)}: less than one whole WG turn of steady motion, so its "
                             "running torque is the fitted law's mean over a turn" if short else "")))
    if len(speeds) < 2:
        checks.append(Check("speeds", "warn", "one running speed: a loss that grows with speed (damping) "
                             "cannot be told from a constant level (friction); record at least three speeds"))
    else:
        checks.append(Check("speeds", "ok", f"{len(speeds)} distinct speeds"))
    checks.append(Check("reversals", "ok" if len(directions) == 2 else "warn",
                         f"{reversals} reversals" if len(directions) == 2 else
                         "one direction only: a level that differs between directions cannot be seen"))
    whole = [abs(v) for w in ("forward", "reverse") if (v := run[w]) is not None]
    checks.append(_sideCheck(meas, drive, whole or [abs(v) for v in levels]))
    if meas.temperature is not None:
        span = float(np.ptp(meas.temperature))
        data["temperature_span_K"] = span
        if span == 0:  # a column that never changes was not read, or is a placeholder
            checks.append(Check("temperature", "warn", f"the temperature column holds one value "
                                 f"({float(meas.temperature[0]):.3g} °C) on every row: a sensor not read?"))
        else:
            checks.append(Check("temperature", "warn" if span > TEMPERATURE_SPAN else "ok",
                                 f"the temperature spans {span:.3g} K" + (": grease friction changes with it; "
                                 "the fit assumes one temperature" if span > TEMPERATURE_SPAN else "")))
    level = float(np.mean(whole)) if whole else float(np.median(np.abs(levels)))
    checks.append(Check("torque_noise", "warn" if noise > NOISE_SHARE * level else "ok",
                         f"torque noise {noise:.3g} N·m against a running level of {level:.3g} N·m"))
    return checks, data


def _sideCheck(meas, drive, levels):
    """Is the running level plausible on the side the file names, for this drive?"""
    catalog = getattr(drive, "running_torque", None)
    ratio = abs(float(meas.ratio)) if meas.ratio is not None else abs(getattr(drive, "ratio", 1.0))
    if not catalog:
        return Check("torque_side", "ok", "no catalog running torque to compare with")
    side = meas.torque_side
    expected = catalog * (ratio if side == "output" else 1.0)
    level = float(np.mean(np.abs(levels)))
    factor = level / expected if expected > 0 else math.inf
    if factor > SIDE_FACTOR or factor < 1.0 / SIDE_FACTOR:
        other = "output" if side == "input" else "input"
        return Check("torque_side", "warn", f"the running level {level:.3g} N·m is {factor:.3g}× the catalog "
                      f"running torque of {drive.name} on the {side} ({expected:.3g} N·m at 2000 rpm): is the "
                      f"torque on the {other} shaft (--meta torque_side={other}), or in other units?")
    return Check("torque_side", "ok", f"the running level {level:.3g} N·m is {factor:.2g}× the catalog running "
                  f"torque of {drive.name} on the {side} shaft")
