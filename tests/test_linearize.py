"""Linearisation (python-control) against a simulated free ring-down."""

import numpy as np
import pytest

from hdsim.model.catalog import load_unit
from hdsim.simulation.path import locked_wave_generator
from hdsim.simulation.linearize import linearize, natural_frequencies
from hdsim.simulation.solver import SolverOptions, integrate


def _ringdown_frequency(model, theta0, torque, equilibrium=0.0, periods=12):
    """Damped frequency [rad/s] from the zero crossings of a simulated free vibration."""
    system = locked_wave_generator(model, lambda t: torque)
    system.y0[0] = theta0
    wn = np.sqrt(model.base_stiffness / model.drive.J_out)
    t_end = periods * 2 * np.pi / wn
    t = np.linspace(0, t_end, 40000)
    result = integrate(system, (0, t_end), t, SolverOptions(rtol=1e-10, atol_scale=1e-10))
    x = result.signal("theta_out") - equilibrium
    sign = np.signbit(x)
    idx = np.flatnonzero(sign[1:] != sign[:-1])
    crossings = t[idx] - x[idx] * (t[idx + 1] - t[idx]) / (x[idx + 1] - x[idx])
    return np.pi / np.mean(np.diff(crossings[1:]))


def test_linear_natural_frequency_matches_ringdown():
    model = load_unit().without("hardening", "backlash", "friction")
    sys = linearize(lambda u: locked_wave_generator(model, lambda t: u), np.zeros(2), 0.0)
    wn, zeta = natural_frequencies(sys)
    assert wn[0] == pytest.approx(np.sqrt(model.base_stiffness / model.drive.J_out), rel=1e-6)
    damped = wn[0] * np.sqrt(1 - zeta[0] ** 2)
    measured = _ringdown_frequency(model, 1e-5, 0.0)
    assert measured == pytest.approx(damped, rel=0.01)


def test_tangent_stiffness_under_preload_sets_the_frequency():
    # preloaded into the second segment of the three-segment law: frequency from K2
    model = load_unit().without("backlash", "friction")
    T0 = 30.0
    from scipy.optimize import brentq

    path_spring = lambda th: model.hardening.torque(th, *model.split()) - T0  # noqa: E731
    theta0 = brentq(path_spring, 0, 1e-2)
    sys = linearize(lambda u: locked_wave_generator(model, lambda t: u), np.array([theta0, 0.0]), T0)
    wn, zeta = natural_frequencies(sys)
    K2 = model.hardening.stiffnesses(*model.split())[1]
    assert wn[0] == pytest.approx(np.sqrt(K2 / model.drive.J_out), rel=0.01)
    measured = _ringdown_frequency(model, theta0 + 2e-6, T0, equilibrium=theta0)
    assert measured == pytest.approx(wn[0] * np.sqrt(1 - zeta[0] ** 2), rel=0.01)
