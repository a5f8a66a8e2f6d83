"""The verdict's noise floor is the white part of the residual, whatever a model's kinks do.

A residual is white noise plus what the model misses. Where that structure sits in a few
rows (the kinks of a friction's reversal or a gap's edge), the differences of the residual
count it as noise: ``std(Δr)/√2`` rose with it, and a residual at 1.4× the noise was
called explained. The floor is the local cubic's median (`hdsim.signals.noise_level`).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hdsim.identification.residuals import EXPLAINED_RATIO, noise_floor, whiteness

SIGMA = 1e-6  # [rad]
N = 20_000


def test_the_floor_of_white_noise_is_its_rms():
    r = SIGMA * np.random.default_rng(3).standard_normal(N)
    assert noise_floor(r) == pytest.approx(SIGMA, rel=0.03)
    assert whiteness(r)["explained"]


def _bumps(every: int, height: float) -> np.ndarray:
    """Three-row bumps of ``height`` every ``every`` rows: a structure held in a few rows."""
    s = np.zeros(N)
    for start in range(every // 2, N - 3, every):
        s[start:start + 3] = height
    return s


def test_a_structure_in_a_few_rows_is_not_read_as_noise():
    # bumps on 3 % of the rows, 5.5 σ high: rms² = σ²(1 + 0.9), and the differences' floor
    # σ²(1 + 0.3) would put the rms at 1.21× the floor, "explained"
    noise = SIGMA * np.random.default_rng(4).standard_normal(N)
    r = noise + _bumps(100, 5.5 * SIGMA)
    differences = float(np.std(np.diff(r)) / math.sqrt(2.0))
    rms = float(np.std(r))
    assert rms / differences < EXPLAINED_RATIO  # the case the old floor called explained
    assert noise_floor(r) == pytest.approx(SIGMA, rel=0.10)
    w = whiteness(r)
    assert not w["explained"] and w["rms_over_noise"] == pytest.approx(math.sqrt(1.9), rel=0.1)
