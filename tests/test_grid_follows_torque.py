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

ENGINES = ["numpy", pytest.param("compiled", marks=pytest.mark.skipif(
    __import__("importlib").util.find_spec("numba") is None, reason="numba not installed"))]


def _linear():
    return load_unit("CSG-25-100").without("hardening", "friction", "backlash", "damping")


def _noisy_torque(n=12_000, amplitude=40.0):
    t = np.linspace(0.0, 10.0, n)
    return t, amplitude * np.sin(2 * np.pi * 0.5 * t) + np.random.default_rng(3).normal(0.0, 0.1, t.size)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_linear_spring_on_a_grid_twists_by_each_samples_own_torque(engine):
    drive = _linear()
    t, torque = _noisy_torque()
    stepped = locked_twist(drive, t, torque, grid=4000, engine=engine)[0]
    every = locked_twist(drive, t, torque, grid=None, engine=engine)[0]
    # the closed form: every sample's twist is its torque over the one stiffness
    stiffness = float(drive.base_stiffness)
    np.testing.assert_allclose(every * stiffness, torque, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(stepped, every, rtol=0, atol=1e-12 * np.max(np.abs(every)))


def test_the_engines_follow_the_torque_alike_through_hardening_and_the_dead_zone():
    """The secant of each interval, its bounds and the torque at the steps: the numpy and
    the compiled engine on the default unit without its friction (three-segment hardening,
    whose secant is below the base compliance, and backlash), under a torque with a ripple
    between the steps. Were the secant the base compliance, they would differ by 3e-6 rad."""
    pytest.importorskip("numba")
    t = np.linspace(0.0, 10.0, 6000)
    torque = 80.0 * np.sin(2 * np.pi * 0.5 * t) + 0.1 * np.sin(2 * np.pi * 137.0 * t)
    drive = load_unit("CSG-25-100").without("friction")
    twists = [locked_twist(drive, t, torque, grid=2000, engine=engine)[0] for engine in ("numpy", "compiled")]
    np.testing.assert_allclose(twists[1], twists[0], rtol=0, atol=1e-9)  # they agree to 2e-11 rad


def test_the_driven_bench_counts_the_torque_between_steps_once():
    """The driven quasi-static bench had added the departure from the stepped torque itself;
    with the evaluator now adding it too, a linear drive twisted by the departure twice."""
    from hdsim.simulation.driven_quasistatic import _twist

    drive = _linear()
    t, torque = _noisy_torque()
    twist, _ = _twist(drive, t, torque[:, None], np.sin(2 * np.pi * 0.5 * t)[:, None])
    np.testing.assert_allclose(twist[0] * float(drive.base_stiffness), torque, rtol=1e-9, atol=1e-9)
