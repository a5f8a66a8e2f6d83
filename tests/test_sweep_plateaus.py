"""A sweep's plateaus hold settled rows only: no ramp's tail, no stretch of a slow ramp.

The records are written here from closed forms (a cosine ramp into a plateau, a linear
ramp at speed), with the inertia torque ``J·dω/dt`` of a motor and wave generator in the
torque: rows where the speed still changes carry it, and the model-free running torque of
a plateau (`hdsim.io.running_checks.running_levels`) would carry it too.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hdsim.io.running_checks import running_levels, sweep_kinematics

LEVEL = 0.1  # running torque [N·m]
INERTIA = 1e-4  # motor and wave generator [kg·m²]


def cosine_ramp(t, start, duration, change):
    """Speed change [rad/s] and acceleration [rad/s²] of a cosine ramp of ``change`` over ``duration``."""
    x = np.clip((t - start) / duration, 0.0, 1.0)
    inside = (t > start) & (t < start + duration)
    return change * 0.5 * (1.0 - np.cos(math.pi * x)), change * 0.5 * math.pi / duration * np.sin(math.pi * x) * inside


def ramp_into_plateau(fs=1000.0, top=300.0, ramp_in=1.5, dwell=0.5, ramp_out=0.1):
    """A slow cosine ramp up to ``top`` [rad/s], a plateau, a fast ramp back to rest; a 16-bit encoder."""
    t = np.arange(0.0, ramp_in + dwell + ramp_out, 1.0 / fs)
    up, a_up = cosine_ramp(t, 0.0, ramp_in, top)
    down, a_down = cosine_ramp(t, ramp_in + dwell, ramp_out, -top)
    w, a = up + down, a_up + a_down
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
    step = 2.0 * math.pi / 2**16
    return t, np.round(theta / step) * step, LEVEL * np.tanh(w / 0.05) + INERTIA * a


def test_a_plateaus_running_torque_holds_no_inertia_torque_of_the_ramp_before_it():
    # the run within 5 % of its mean began 0.22 s before the ramp ended: its running torque
    # was 2.9 % high, the inertia torque of the ramp's tail in it
    t, angle, torque = ramp_into_plateau()
    _, _, segments = sweep_kinematics(t, angle)
    assert len(segments) == 1
    assert running_levels(torque, angle, segments)["forward"] == pytest.approx(LEVEL, rel=2e-3)


def test_a_slow_ramp_at_speed_is_no_plateau():
    # 300 rad/s² from 100 rad/s: runs of 40 ms within 5 % of their mean had been taken for
    # plateaus, whose torque is all inertia torque beside the friction
    t = np.arange(0.0, 1.0, 1e-3)
    assert sweep_kinematics(t, 100.0 * t + 150.0 * t**2)[2] == []


def sweep_both_ways(fs=800.0, rpm=(100.0, 500.0), turns=3.0, seed=10, noise=0.003):
    """A sweep at each speed forward then reverse (cosine ramps of 0.1 s, 0.05 s rests) and its torque."""
    pieces, t0 = [], 0.0
    for v in rpm:
        for d in (1.0, -1.0):
            w = d * v * math.pi / 30.0
            cruise = max(turns * 2.0 * math.pi / abs(w), 0.2)
            for dur, shape in ((0.05, lambda x: 0.0 * x), (0.1, lambda x: 0.5 * (1 - np.cos(math.pi * x))),
                               (cruise, lambda x: 1.0 + 0.0 * x), (0.1, lambda x: 0.5 * (1 + np.cos(math.pi * x)))):
                n = int(round(dur * fs))
                pieces.append((t0 + np.arange(n) / fs, w * shape(np.arange(n) / n)))
                t0 += n / fs
    t = np.concatenate([p[0] for p in pieces])
    w = np.concatenate([p[1] for p in pieces])
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) / fs)])
    torque = LEVEL * np.tanh(w / 0.01) + 7e-4 * w + INERTIA * np.gradient(w, t)
    return t, theta, torque + noise * np.random.default_rng(seed).standard_normal(t.size)


def test_a_few_dropped_rows_leave_the_plateaus_and_running_torque_as_they_were():
    # 25 rows dropped from 19,776 had cut the plateau rows from 17,580 to 6,330 and raised the
    # running torque by 14 % forward and 39 % reverse: the speed was differentiated by row
    t, angle, torque = sweep_both_ways()
    _, _, whole = sweep_kinematics(t, angle)
    keep = np.ones(t.size, dtype=bool)
    keep[np.random.default_rng(3).choice(np.arange(10, t.size - 10), 8, replace=False)] = False
    _, _, gappy = sweep_kinematics(t[keep], angle[keep])
    assert len(gappy) == len(whole) == 4
    assert sum(s.stop - s.start for s in gappy) >= 0.98 * sum(s.stop - s.start for s in whole)
    before, after = running_levels(torque, angle, whole), running_levels(torque[keep], angle[keep], gappy)
    for way in ("forward", "reverse"):
        assert after[way] == pytest.approx(before[way], rel=5e-3)


def test_jittered_time_stamps_are_read_by_row_as_before():
    # the bridge of dropped rows counts sample intervals: stamps jittered by a fifth of an
    # interval count one each, so the record is read by row as an evenly stamped one is
    t, angle, _ = sweep_both_ways()
    jittered = t + 0.2 / 800.0 * np.random.default_rng(4).uniform(-1.0, 1.0, t.size)
    read, even = sweep_kinematics(jittered, angle)[2], sweep_kinematics(t, angle)[2]
    assert len(read) == len(even) == 4
    for a, b in zip(read, even):
        assert abs(a.start - b.start) <= 2 and abs(a.stop - b.stop) <= 2 and a.speed == pytest.approx(b.speed, rel=1e-3)


def test_a_log_thinned_after_rows_were_dropped_is_read_in_time():
    # one row in two kept of a log with dropped rows leaves gaps of 1.5 intervals, which no
    # count of intervals bridges: 25 of them had cut a sweep's plateau rows to a sixth
    t, angle, torque = sweep_both_ways(fs=1600.0)
    whole = running_levels(torque, angle, sweep_kinematics(t, angle)[2])
    keep = np.ones(t.size, dtype=bool)
    keep[np.random.default_rng(5).choice(np.arange(10, t.size - 10), 8, replace=False)] = False
    t, angle, torque = t[keep][::2], angle[keep][::2], torque[keep][::2]
    _, _, segments = sweep_kinematics(t, angle)
    assert len(segments) == 4 and sum(s.stop - s.start for s in segments) > 0.7 * t.size
    thinned = running_levels(torque, angle, segments)
    for way in ("forward", "reverse"):
        assert thinned[way] == pytest.approx(whole[way], rel=5e-3)
