"""Hold-out folds and resampling blocks of a bench record, from its torque profile alone.

A *leg* is a monotone stretch of the (smoothed) torque between turning points; a
*cycle* closes with a rising leg that follows a falling one. Folds and blocks are made
of whole legs and cycles, so that every part of the record a fit is judged on holds
complete loops; a kinematic-error test is cut by wave-generator travel instead.
"""

from __future__ import annotations

import math

import numpy as np

from hdsim.io.measurement import Measurement
from hdsim.signals import loading_rates, turning_points

__all__ = ["folds", "one_loading_rate", "blocks", "MIN_BLOCKS"]

#: fewer blocks than this cannot be resampled usefully (3 blocks give 10 distinct resamples)
MIN_BLOCKS = 6
KE_FOLD_REVOLUTIONS = 10


def _legs(meas: Measurement):
    """(start, stop) index pairs of monotone torque legs and their mean |dT/dt|.

    The folds keep their own rule, a moving average over n/200 samples and a dead band of
    5 % of the swing: the battery's hold-out rates were measured with it (the noise-set
    band of `hdsim.signals.torque_legs` moved one backlash case of five).
    """
    T = np.asarray(meas.torque, dtype=float)
    k = max(int(T.size // 200), 1)
    smooth = np.convolve(T, np.ones(2 * k + 1) / (2 * k + 1), mode="same")
    turns = turning_points(smooth, 0.05 * max(float(np.ptp(smooth)), 1e-12))
    legs = [(a, b) for a, b in zip(turns[:-1], turns[1:]) if b - a > 2]
    return legs, loading_rates(meas.time, smooth, turns)  # one rate per leg (the same b - a > 2 rule)


def _wg_travel(meas: Measurement) -> np.ndarray:
    """Wave-generator travel from the record's start at every row [rad], reversals counted."""
    return np.concatenate([[0.0], np.cumsum(np.abs(np.diff(np.asarray(meas.wg_angle, dtype=float))))])


def _cycles(legs, torque):
    """Legs grouped into cycles: a cycle closes with a rising leg that follows a falling
    one; a leftover (the last ramp back to zero) joins the last cycle."""
    out, current, fell = [], [], False
    for a, b in legs:
        current.append((a, b))
        rising = torque[min(b, torque.size - 1)] > torque[a]
        if rising and fell:
            out.append(current)
            current, fell = [], False
        fell = fell or not rising
    if current and out:
        out[-1] += current
    elif current:
        out.append(current)
    return out


def folds(meas: Measurement) -> tuple[list[np.ndarray], str]:
    """Two disjoint row masks that cover the record, and how they were chosen.

    Whole cycles of the torque (pairs of legs), alternated between the folds within each
    loading rate (legs whose rates differ by more than 1.5× are two rates), so that each
    fold holds every rate with a cycle to spare however unequal the rates' shares of the
    record (one slow cycle and ten fast ones), and a drift or a warm-up is shared alike;
    a record of less than two cycles is split into the first and the second half of its
    legs (or of its time, when there are fewer than two legs).
    """
    n = len(meas)
    if meas.wg_driven:
        # both folds need both load directions (else the twist under load is not
        # identified): alternate blocks of ten wave-generator revolutions
        block = (_wg_travel(meas) // (KE_FOLD_REVOLUTIONS * 2 * np.pi)).astype(int)
        if block.max() >= 3:
            return [block % 2 == 0, block % 2 == 1], "alternate blocks of ten wave-generator revolutions"
    legs, rates = _legs(meas)
    halves = [np.arange(n) < n // 2, np.arange(n) >= n // 2], "first and second half of the time"
    masks = [np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)]
    classes = np.zeros(len(legs), dtype=int)
    if len(legs) >= 2 and np.min(rates) > 0 and np.max(rates) / np.min(rates) > 1.5:
        classes = (np.asarray(rates) > math.sqrt(np.min(rates) * np.max(rates))).astype(int)
    T = np.asarray(meas.torque, dtype=float)
    cycles = [_cycles([leg for leg, k in zip(legs, classes) if k == c], T) for c in sorted(set(classes.tolist()))]
    if sum(len(group) for group in cycles) >= 2:
        for group in sorted(cycles, key=len):
            start = int(masks[1].sum() < masks[0].sum())  # the fold with fewer rows first
            for i, cycle in enumerate(group):
                for a, b in cycle:
                    masks[(start + i) % 2][a:b] = True
        how = ("whole cycles alternated within each loading rate" if len(cycles) > 1
               else "whole cycles alternated")
    elif len(legs) >= 2:
        half = len(legs) // 2
        for i, (a, b) in enumerate(legs):
            masks[int(i >= half)][a:b] = True
        how = "first and second half of the loading legs"
    else:
        masks, how = halves
    # rows outside any leg go to the nearer fold in time
    rest = ~(masks[0] | masks[1])
    if np.any(rest):
        owner0, owner1 = np.flatnonzero(masks[0]), np.flatnonzero(masks[1])
        for i in np.flatnonzero(rest):
            d0 = np.min(np.abs(owner0 - i)) if owner0.size else np.inf
            d1 = np.min(np.abs(owner1 - i)) if owner1.size else np.inf
            masks[int(d1 < d0)][i] = True
    if min(m.sum() for m in masks) < 10:
        masks, how = halves
    return masks, how


def one_loading_rate(meas: Measurement) -> bool:
    """True when the legs of the torque profile load at one rate (within 1.5×)."""
    _, rates = _legs(meas)
    rates = np.asarray(rates, dtype=float)
    rates = rates[rates > 0]
    return rates.size < 2 or float(np.max(rates) / np.min(rates)) <= 1.5


def blocks(meas: Measurement) -> tuple[list[int], str]:
    """Row indices where resampling blocks start, and how they were chosen.

    Locked tests: the torque cycles (`_cycles`), or its legs when there are fewer than
    ``MIN_BLOCKS`` cycles. Kinematic-error tests: blocks of ten
    wave-generator revolutions when that gives ten blocks or more, else single revolutions.
    """
    if meas.wg_driven:
        travel = _wg_travel(meas) / (2 * np.pi)
        per = 10 if travel[-1] >= 100 else 1
        index = (travel // per).astype(int)
        starts = np.flatnonzero(np.diff(index) > 0) + 1
        return [0] + starts.tolist(), f"blocks of {per} wave-generator revolution{'s' * (per > 1)}"
    legs, _ = _legs(meas)
    cycles = _cycles(legs, np.asarray(meas.torque, dtype=float))
    if len(cycles) >= MIN_BLOCKS:
        return [0] + [cycle[0][0] for cycle in cycles[1:]], "whole torque cycles"
    # a record of a few cycles has too few blocks to resample: its legs (half cycles) then
    return [0] + [a for a, _ in legs[1:]], "torque legs (fewer than six cycles)"
