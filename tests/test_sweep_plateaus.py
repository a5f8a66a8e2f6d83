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
