"""Type aliases of the public interface, for annotations and type checkers.

A model parameter is a float, or a 1-D array of values that makes a *batch* model
integrated in one solver call (docs/api.md); the aliases below name that and the
other recurring argument kinds. They are plain aliases: any value of the aliased
types is accepted at run time.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import TypeAlias, Union

import numpy as np
import numpy.typing as npt

__all__ = ["FloatOrArray", "ArrayLike", "ParameterValues", "PathLike", "Bounds", "is_number"]

FloatOrArray: TypeAlias = Union[float, np.ndarray]
"""One value [SI unit of the quantity], or a 1-D array of values (a batch, one per sample)."""

ArrayLike: TypeAlias = npt.ArrayLike
"""Anything numpy turns into a float array: a float, a list, a tuple, an ndarray."""

ParameterValues: TypeAlias = Mapping[str, FloatOrArray]
"""Dotted parameter name (``"flexspline.h_c"``) to its value [SI], a float or a batch array."""

PathLike: TypeAlias = Union[str, os.PathLike]
"""A file-system path given as text or as a path object."""

Bounds: TypeAlias = Mapping[str, Union[tuple[float, float], str]]
"""Per-parameter interval of a study: ``(low, high)`` [SI unit of the parameter] or ``"LOW:HIGH"``."""


def is_number(value) -> bool:
    """Whether ``value`` is one real number (Python's or numpy's); a bool is not one."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
