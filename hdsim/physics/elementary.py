"""Elementary functions of a float or an array: `math` for a float, numpy for an array.

A single model's right-hand side calls the laws on Python floats, where a numpy
function costs about a microsecond a call, ten times the `math` function's. The laws
call these instead of numpy's so that one formula serves both.
"""

from __future__ import annotations

import math

import numpy as np


def tanh(x):
    """tanh of a float (`math`) or an array (numpy)."""
    return math.tanh(x) if isinstance(x, float) else np.tanh(x)


def exp(x):
    """exp of a float (`math`) or an array (numpy)."""
    return math.exp(x) if isinstance(x, float) else np.exp(x)


def sin(x):
    """sin of a float (`math`) or an array (numpy)."""
    return math.sin(x) if isinstance(x, float) else np.sin(x)


def cos(x):
    """cos of a float (`math`) or an array (numpy)."""
    return math.cos(x) if isinstance(x, float) else np.cos(x)
