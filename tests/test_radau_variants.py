"""The single-model Radau of `hdsim.simulation.block_radau` takes scipy's steps bit for bit:
the same LAPACK routines, without the argument checks around them."""

from __future__ import annotations

import numpy as np
from scipy.integrate import Radau, solve_ivp

from hdsim.model.catalog import load_unit
from hdsim.simulation.block_radau import DenseRadau
from hdsim.simulation.path import locked_wave_generator


def _van_der_pol(t, y, mu=200.0):
    """A stiff oscillator with a closed Jacobian-free form: Radau's usual test."""
    return [y[1], mu * (1.0 - y[0] ** 2) * y[1] - y[0]]


def test_the_single_model_radau_takes_scipys_steps_bit_for_bit():
    stock, ours = (solve_ivp(_van_der_pol, (0.0, 400.0), [2.0, 0.0], method=m, rtol=1e-6, atol=1e-6)
                   for m in (Radau, DenseRadau))
    assert stock.success and ours.success and stock.nlu > 10
    assert (stock.nfev, stock.njev, stock.nlu) == (ours.nfev, ours.njev, ours.nlu)
    np.testing.assert_array_equal(ours.t, stock.t)
    np.testing.assert_array_equal(ours.y, stock.y)


def test_the_locked_bench_of_the_default_unit_runs_the_same_steps():
    system = locked_wave_generator(load_unit("CSG-25-100"), lambda t: 87.0 * np.sin(2.0 * np.pi * t))
    atol = 1e-6 * system.state_scales
    runs = [solve_ivp(system.rhs, (0.0, 0.5), system.y0, method=m, rtol=1e-6, atol=atol) for m in (Radau, DenseRadau)]
    assert all(r.success for r in runs) and runs[0].y.shape[1] > 50
    np.testing.assert_array_equal(runs[1].y, runs[0].y)
