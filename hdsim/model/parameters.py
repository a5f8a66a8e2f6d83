"""Parameter holders: numeric fields with a unit, physical bounds and a one-line meaning.

Every numeric parameter of the model (effects, wave generator, drive data,
calibration) is a dataclass field made by `param`. The metadata drives bound
checks on construction, the dotted parameter listing of `HarmonicDrive.params`,
the fit's parameter transforms and the messages a user sees.
"""

from __future__ import annotations

import functools
import math
import reprlib
from dataclasses import MISSING, field, fields
from typing import ClassVar

import numpy as np

from hdsim.errors import InputError
from hdsim.typing import is_number


def param(doc: str, unit: str, lower: float = 0.0, upper: float = np.inf, positive: bool = False,
          default=MISSING, count: str = ""):
    """A numeric parameter field with its unit and physical bounds.

    Parameters
    ----------
    doc : str
        One-line meaning, shown in messages and the API pages.
    unit : str
        Unit symbol, e.g. ``"N·m"``.
    lower, upper : float
        Closed physical bounds.
    positive : bool
        Zero is excluded as well (``lower`` is then only the display bound).
    default : float, optional
        Makes the parameter optional in scenario and fitted-model files.
    count : str, optional
        What the parameter counts (``"balls"``): it then takes whole numbers only
        (`not_whole`) and is no input of a Sobol study.
    """
    metadata = {"doc": doc, "unit": unit, "bounds": (lower, upper), "positive": positive}
    if count:  # only on counts: the other parameters' metadata stays as the docs print it
        metadata["count"] = count
    return field(default=default, metadata=metadata)


def not_whole(value) -> np.ndarray:
    """Where a count is not a whole number: a boolean array of ``value``'s shape.

    A relative slack of 1e-9 lets through a count computed in floats (the teeth of a
    drive, 2 × ratio) and nothing a person types (200.5, 22.000001).
    """
    value = np.asarray(value, dtype=float)
    return np.abs(value - np.round(value)) > 1e-9 * np.abs(value)


def whole_count_message(name: str, value: float, what: str) -> str:
    """The refusal of a count that is not whole, the same at every edge it enters by."""
    # to twelve digits: a count 22.000001 shown as "22" would contradict its own refusal
    return f"{name} = {value:.12g} must be a whole number of {what}"


@functools.lru_cache(maxsize=None)
def count_fields(cls) -> tuple[tuple[str, str], ...]:
    """(name, what it counts) of the numeric fields of ``cls`` that are counts (``param(..., count=...)``)."""
    return tuple((f.name, f.metadata["count"]) for f in fields(cls) if f.metadata.get("count"))


def _described(value) -> str:
    """What was given instead of numbers, for a refusal: the type and value, of a sequence
    the first element that is no number."""
    if isinstance(value, (list, tuple, np.ndarray)):
        for element in (value.ravel() if isinstance(value, np.ndarray) else value):
            if not is_number(element):
                element = element.item() if isinstance(element, np.generic) else element
                return f"{type(value).__name__} holding {type(element).__name__} {reprlib.repr(element)}"
    return f"{type(value).__name__} {reprlib.repr(value)}"


def as_numbers(name: str, value) -> np.ndarray:
    """``value`` as a float array of at most one dimension (a batch), or an `InputError`
    naming the parameter ``name`` and the type of what was given.

    Numbers only: numpy would read the string ``"0.6e-3"`` as 0.0006 in a list and fail
    on it alone, and take ``True`` as 1. A Python caller who passes either has mixed
    something up; the CLI parses its own text before it gets here.
    """
    try:
        array = np.asarray(value)
    except ValueError:  # ragged nesting, refused below with what it holds
        array = np.asarray(None)
    if array.dtype.kind not in "iuf":
        raise InputError(f"{name} must be a number or a 1-D array of numbers, got {_described(value)}")
    if array.ndim > 1:
        raise InputError(f"{name} must be a number or a 1-D array of numbers, got shape {array.shape}")
    return array.astype(float, copy=False)


def _as_float_array(owner: str, name: str, value) -> np.ndarray:
    return as_numbers(f"{owner}.{name}", value)


def float_if_scalar(value):
    """A Python float for a 0-d value (a numpy scalar or 0-d array), else ``value`` as it is.

    A single model's right-hand side runs on floats: numpy's scalars take the same `math`
    branches (they pass ``isinstance(x, float)``) but cost about three times a float per
    operation.
    """
    return float(value) if np.ndim(value) == 0 else value


@functools.lru_cache(maxsize=None)
def numeric_fields(cls) -> tuple[str, ...]:
    """The names of the numeric parameter fields (those made by `param`) of dataclass ``cls``."""
    return tuple(f.name for f in fields(cls) if f.metadata)


@functools.lru_cache(maxsize=None)
def checked_fields(cls) -> tuple:
    """(name, lower, upper, positive, unit) of every numeric field of ``cls``: the same for
    every instance, and a fit builds thousands of instances."""
    return tuple((f.name, *f.metadata["bounds"], f.metadata["positive"], f.metadata["unit"])
                 for f in fields(cls) if f.metadata)


class Parameters:
    """Base of every parameter holder: bound checks on construction, field listing.

    Subclasses are frozen dataclasses; a field may hold a float or a 1-D array (a batch
    of parameter sets evaluated at once).
    """

    #: dotted-name prefix used in messages (``drive``, ``wave_generator`` …)
    prefix: ClassVar[str] = ""

    def __post_init__(self):
        for name, lower, upper, positive, unit in checked_fields(type(self)):
            raw = getattr(self, name)
            if type(raw) is float and lower <= raw <= upper and (raw > 0.0 or not positive) and math.isfinite(raw):
                continue  # a single model's float within its bounds (the common case, without numpy)
            value = _as_float_array(self.prefix, name, raw)
            bad = ~np.isfinite(value) | (value < lower) | (value > upper)
            bound = f"[{lower:g}, {upper:g}]"
            if positive:
                bad |= value <= 0.0
                bound = f"({lower:g}, {upper:g}]" if lower <= 0.0 else bound
            if np.any(bad):
                first = np.atleast_1d(value)[np.argmax(np.atleast_1d(bad))]
                raise InputError(f"{self.prefix}.{name} = {first:g} is outside {bound}"
                                 + (f" {unit}" if unit not in ("", "-") else ""))
            if not isinstance(raw, int):  # a given int stays as written
                object.__setattr__(self, name, float_if_scalar(raw))
        for name, what in count_fields(type(self)):
            value = getattr(self, name)
            if type(value) is int or (type(value) is float and value.is_integer()):
                continue  # the usual case, without numpy: a fit builds thousands of instances
            bad = np.atleast_1d(not_whole(value))
            if bad.any():
                first = float(np.atleast_1d(value)[np.argmax(bad)])
                raise InputError(whole_count_message(f"{self.prefix}.{name}", first, what))

    def params(self) -> dict:
        """Every numeric field by name."""
        return {name: getattr(self, name) for name in numeric_fields(type(self))}

    @classmethod
    def param_meta(cls) -> dict:
        """Metadata (``doc``, ``unit``, ``bounds``, ``positive``) of every numeric field."""
        return {f.name: dict(f.metadata) for f in fields(cls) if f.metadata}

    @classmethod
    def unchecked(cls, **values):
        """An instance without bound checks, for neutral parameter values that lie on or
        beyond a physical bound (a zero stiffness that switches a law off)."""
        obj = object.__new__(cls)
        for name, value in values.items():
            object.__setattr__(obj, name, value)
        return obj
