"""Between its steps the quasi-static evaluator follows each sample's own torque.

A long record is stepped on a grid (`hdsim.simulation.quasistatic.sample_grid`) and the
twist between steps was interpolated in time: a noisy torque channel's noise, which a
linear spring passes straight into the twist, was smoothed away between steps, and the
residual of the right model was coloured, above its noise floor (a kinematic-error run
under a sine load with 0.1 N·m of torque noise was called "misses an effect").
"""

from __future__ import annotations

import numpy as np
import pytest

from hdsim.model.catalog import load_unit
from hdsim.simulation.quasistatic import locked_twist

pytest.importorskip("numba")


def _linear():
    return load_unit("CSG-25-100").without("hardening", "friction", "backlash", "damping")


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_a_linear_spring_on_a_grid_twists_by_each_samples_own_torque(engine):
    drive = _linear()
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 10.0, 12_000)
    torque = 40.0 * np.sin(2 * np.pi * 0.5 * t) + rng.normal(0.0, 0.1, t.size)
    stepped = locked_twist(drive, t, torque, grid=4000, engine=engine)[0]
    every = locked_twist(drive, t, torque, grid=None, engine=engine)[0]
    # the closed form: every sample's twist is its torque over the one stiffness
    stiffness = np.median(torque / every)
    np.testing.assert_allclose(every * stiffness, torque, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(stepped, every, rtol=0, atol=1e-12 * np.max(np.abs(every)))
