"""A channel that holds one value on every row (a column that was not logged, or another one
mapped by mistake) is named as such, and the signal analysis never overflows on it."""

from __future__ import annotations

import numpy as np
import pytest

from hdsim.identification.workflow import examine
from hdsim.io.data_checks import DriveScale
from hdsim.io.measurement import make_measurement
from hdsim.model.catalog import load_unit
from hdsim.signals import noise_level, smoothed, torque_legs

DRIVE = DriveScale.of(load_unit("CSG-25-100"))


@pytest.mark.parametrize("level", [0.0, 5.0, 31.2, -1e6])
def test_a_constant_signal_has_no_noise_and_stays_as_it_is(level):
    """The local cubic's weights round on a level (31.2 gave 6e-15 of 'noise'), and the
    smoothing window then squared noise over a swing of zero."""
    x = np.full(1200, level)
    t = np.sort(np.random.default_rng(0).random(1200))  # unevenly sampled: the fit in time
    assert noise_level(x) == 0.0 and noise_level(x, t) == 0.0
    smooth, left = smoothed(x, 1e-3)
    assert np.array_equal(smooth, x) and left == 1e-3
    assert torque_legs(x)[1] == [0, x.size]


@pytest.mark.parametrize("level", [0.0, 31.2])
def test_a_stiffness_record_with_a_constant_torque_is_not_one(level):
    t = np.linspace(0.0, 12.0, 1200)
    angle = 1e-4 * np.sin(t) + np.random.default_rng(1).normal(0.0, 1e-6, t.size)
    meas = make_measurement("stiffness", t, np.full(t.size, level), angle)
    checks, _, wrong = examine(meas, DRIVE)
    assert f"the torque is {level:g} N·m on every row" in wrong
    assert [c.check for c in checks if c.status == "fail"] == ["torque_varies"]
