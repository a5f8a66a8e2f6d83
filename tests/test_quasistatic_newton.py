"""The numpy evaluator's step solve (`hdsim.simulation.quasistatic._solve`) on balances
whose root is known: a row that crawls inside its bracket is bisected to the root, and a
row whose balance is not finite is lost without holding the rest of the batch.

The balance is ``g(e) = 2 (e − root)`` with a reported slope just over half the true one,
the situation of the Dahl micro-slip path near the slider's stop: each Newton step lands
on the other side of the root, 4 % nearer, inside the bracket.
"""

from __future__ import annotations

import numpy as np

from hdsim.simulation.quasistatic import _solve

ROOT = np.array([1.0e-4, -3.0e-4])
X_TOL = 1e-8


class _Balance:
    """Stands in for the evaluator's kernel: a linear balance, no friction states."""

    n_states = 0

    def __init__(self, slope_reported, lost_rows=()):
        self.slope_reported = slope_reported
        self.lost = np.zeros(ROOT.size, dtype=bool)
        self.lost[list(lost_rows)] = True
        self.dg_floor = np.full(ROOT.size, 1e-6)
        self.calls = 0

    def balance(self, e, e0, s0, torque, rate):
        self.calls += 1
        g = np.where(self.lost, np.nan, 2.0 * (e - ROOT))
        dg = np.full_like(g, self.slope_reported)
        return g, dg, g, dg


def _solve_from(kern, guess):
    return _solve(kern, guess, np.zeros(ROOT.size), np.zeros((0, ROOT.size)), 0.0, None, 1e-12, X_TOL, 60,
                  np.full(ROOT.size, 1e-4))


def test_a_step_that_crawls_inside_its_bracket_is_bisected_to_its_root():
    kern = _Balance(slope_reported=1.02)  # the true slope is 2: each step overshoots to 96 % of the error
    x, _, _, _, solved = _solve_from(kern, ROOT + 1e-4)
    assert solved.all()
    np.testing.assert_allclose(x, ROOT, rtol=0, atol=2 * X_TOL)
    assert kern.calls > 60  # Newton alone did not get there: 0.96**60 of the error is left


def test_a_lost_row_does_not_keep_the_batch_iterating():
    kern = _Balance(slope_reported=2.0, lost_rows=[1])  # exact slope: the finite row is solved in two steps
    x, _, _, _, solved = _solve_from(kern, ROOT + 1e-4)
    assert solved.tolist() == [True, False]
    assert x[0] == ROOT[0]
    assert kern.calls <= 3  # not the 60 iterations of the cap, at every step of the record
