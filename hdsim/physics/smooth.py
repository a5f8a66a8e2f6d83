"""Smooth ramps shared by the laws: softplus (a rounded ``max(x, 0)``) and its slope.

Each takes the `math` branch for a float (a single model's right-hand side) and the
numpy branch for an array, with the same formula in both (`hdsim.physics.elementary`).
"""

from __future__ import annotations

import math

import numpy as np

from hdsim.physics.elementary import tanh


def softplus(x, width):
    """Smooth ``max(x, 0)`` over ``width``: ``w·log(1 + exp(x/w))``, overflow-safe.

    Parameters
    ----------
    x : float or array
        Argument [any unit].
    width : float or array
        Rounding width [the unit of ``x``], > 0.

    Returns
    -------
    float or array
        ``max(x, 0)`` rounded, within ``w·log 2`` of it at ``x = 0`` and within
        ``w·e^{-|x|/w}`` away from it [the unit of ``x``].
    """
    z = x / width
    if isinstance(z, float):
        return width * (max(z, 0.0) + math.log1p(math.exp(-abs(z))))
    return width * (np.maximum(z, 0.0) + np.log1p(np.exp(-np.abs(z))))


def softplus_slope(x, width):
    """d(`softplus`)/dx, the logistic step ``(1 + tanh(x/2w))/2`` from 0 to 1 [-]."""
    return 0.5 * (1.0 + tanh(0.5 * x / width))


def magnitude_and_sign(x):
    """``(|x|, sign x)`` as `numpy.abs` and `numpy.sign` give them (sign 0 at 0, NaN at NaN)."""
    if isinstance(x, float):
        return abs(x), (1.0 if x > 0.0 else -1.0 if x < 0.0 else 0.0 if x == 0.0 else x)
    return np.abs(x), np.sign(x)
