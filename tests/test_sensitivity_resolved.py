"""Time-resolved indices against a closed form."""

import numpy as np
import pytest

from hdsim.sensitivity.problem import uniform
from hdsim.sensitivity.resolved import resolved_indices

T = np.linspace(0, np.pi, 9)


def rotating(X):
    # y(t) = x1 sin t + x2 cos t with equal variances: S1 = [sin² t, cos² t] = ST
    return X[:, :1] * np.sin(T) + X[:, 1:2] * np.cos(T)


def test_resolved_indices_follow_the_analytic_curves():
    res = resolved_indices(rotating, uniform(["x1", "x2"], [(-1, 1), (-1, 1)]), 2048, seed=1)
    assert res["S1"][:, 0] == pytest.approx(np.sin(T) ** 2, abs=0.03)
    assert res["S1"][:, 1] == pytest.approx(np.cos(T) ** 2, abs=0.03)
    assert res["ST"] == pytest.approx(res["S1"], abs=0.03)
    assert res["variance"] == pytest.approx(np.full(T.size, 1 / 3), rel=0.05)
