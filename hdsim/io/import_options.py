"""Import options: how a log written by other bench software is read without editing it.

Real logs carry no ``#`` keys, name and scale their columns their own way, write a NaN
where a read failed, restart their clock for every run of a sequence, or have no clock
at all (a step test logged point by point). `ImportOptions` says, once, what the file
does not: the test and the drive's numbers (as ``#`` keys would), which rows to keep,
and how to build the time axis. The readers (`hdsim.io.measurement_readers`) apply it
between reading the cells and checking them (docs/measurements.md, "Bringing your own
bench log").

The order of the row operations is fixed and documented, so a user can predict it:

1. time: from the row index at ``sample_rate`` [Hz] when the file has no time column;
2. concatenated runs: each run whose clock restarts continues after the previous one;
3. window: keep rows with ``T0 <= time_s <= T1`` (on the joined clock);
4. drop NaN: drop rows with a non-finite cell in a column the test uses, or a one-row
   glitch (`glitch_rows`), counted.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields

import numpy as np

from hdsim.errors import InputError
from hdsim.signals import glitches
from hdsim.typing import is_number

__all__ = ["ImportOptions", "checked_options", "RowReport", "parse_window", "parse_meta", "split_factor", "apply_rows", "glitch_rows"]

#: ``FACTOR*column`` in a column map: a number, a ``*``, then the file's column name
_FACTOR = re.compile(r"^\s*([-+]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf(?:inity)?|nan))\s*\*\s*(\S.*?)\s*$",
                     re.IGNORECASE)  # inf and nan are read, to be refused as factors


@dataclass(frozen=True)
class ImportOptions:
    """What the user says of a log that the log does not say itself.

    Attributes
    ----------
    test : str or None
        Sets (or overrides) the ``# test`` key.
    ratio : float or None
        Sets the ``# ratio`` key [-].
    rated_torque : float or None
        Sets the ``# rated_torque_Nm`` key [N·m].
    meta : dict of str to str
        Any other ``#`` key, e.g. ``{"torque_side": "output"}``; wins over the file's.
    drop_nan : bool
        Drop rows with a non-finite (or empty) cell in a used column, or a one-row glitch
        (`glitch_rows`), instead of refusing the file; the count is reported.
    window : tuple of float or None
        ``(T0, T1)`` [s]: keep rows with ``T0 <= time_s <= T1``; a side ``None`` is open
        (as ``--window 5:`` is), kept as an infinity.
    sample_rate : float or None
        For a file without a time column: ``time_s = row index / sample_rate`` [Hz].
    concatenated : bool
        The file holds several runs whose clock restarts; each continues after the
        previous one, one median sample interval later.
    """

    test: str | None = None
    ratio: float | None = None
    rated_torque: float | None = None
    meta: dict = field(default_factory=dict)
    drop_nan: bool = False
    window: tuple[float, float] | None = None
    sample_rate: float | None = None
    concatenated: bool = False

    def __post_init__(self):
        for name in ("ratio", "rated_torque", "sample_rate"):
            value = getattr(self, name)
            if value is not None and not (is_number(value) and math.isfinite(value) and value != 0):
                raise InputError(f"{name}: must be a finite non-zero number, got {value!r}")
        if self.rated_torque is not None and self.rated_torque < 0:
            raise InputError(f"rated_torque: must be positive, got {self.rated_torque!r}")
        if self.sample_rate is not None and self.sample_rate < 0:
            raise InputError(f"sample_rate: must be positive, got {self.sample_rate!r}")
        if self.test is not None and not isinstance(self.test, str):
            raise InputError(f"test: must be the name of a test (a str), e.g. 'stiffness', got {self.test!r}")
        if not isinstance(self.meta, Mapping):
            raise InputError(f"meta: must be a dict of '#' keys, e.g. {{'torque_side': 'output'}}, "
                             f"got {type(self.meta).__name__} {self.meta!r}")
        for name in ("drop_nan", "concatenated"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise InputError(f"{name}: must be True or False, got {getattr(self, name)!r}")
        if self.window is not None:
            object.__setattr__(self, "window", _window(self.window))

    def overrides(self) -> dict[str, str]:
        """The ``#`` keys these options set, as text (they win over the file's)."""
        keys = {str(k): str(v) for k, v in self.meta.items()}
        if self.test is not None:
            keys["test"] = str(self.test)
        if self.ratio is not None:
            keys["ratio"] = repr(float(self.ratio))
        if self.rated_torque is not None:
            keys["rated_torque_Nm"] = repr(float(self.rated_torque))
        return keys


def checked_options(given: dict) -> ImportOptions:
    """`ImportOptions` of `load_measurement`'s keyword arguments, an unknown name refused by name."""
    known = [f.name for f in fields(ImportOptions)]
    unknown = [name for name in given if name not in known]
    if unknown:
        raise InputError(f"load_measurement: unknown import option {', '.join(map(repr, unknown))}; known: {', '.join(known)}")
    return ImportOptions(**given)


#: no import options: the file is read as it is
AS_WRITTEN = ImportOptions()


@dataclass(frozen=True)
class RowReport:
    """What the row operations did, for the data summary and the checks.

    Attributes
    ----------
    dropped_rows : int
        Rows dropped for a non-finite cell or a glitch.
    windowed_rows : int
        Rows outside the window.
    runs : int
        Runs found in a concatenated file (1 otherwise).
    time_from_rows : bool
        The time axis was built from the row index.
    """

    dropped_rows: int = 0
    windowed_rows: int = 0
    runs: int = 1
    time_from_rows: bool = False


def _window(value) -> tuple[float, float]:
    """The ``window`` keyword as ``(T0, T1)`` [s]: a pair of numbers, ``None`` for an open side."""
    usage = "window: expected (T0, T1) in seconds, None for an open side, e.g. (2.5, 40) or (5, None)"
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence) or len(value) != 2:
        raise InputError(f"{usage}; got {value!r}")
    if not all(side is None or is_number(side) for side in value):
        raise InputError(f"{usage}; got {value!r}")
    lo = -math.inf if value[0] is None else float(value[0])
    hi = math.inf if value[1] is None else float(value[1])
    if not lo <= hi:  # also refuses NaN
        raise InputError(f"window: ({lo:g}, {hi:g}) is empty; expected T0 <= T1")
    return lo, hi


def parse_window(text: str) -> tuple[float, float]:
    """``'T0:T1'`` as ``(T0, T1)`` [s]; an empty side is open (``'5:'``, ``':20'``)."""
    lo, sep, hi = str(text).partition(":")
    if not sep:
        raise InputError(f"--window: {text!r} is not T0:T1 (seconds), e.g. --window 2.5:40")
    try:
        bounds = (float(lo) if lo.strip() else -math.inf, float(hi) if hi.strip() else math.inf)
    except ValueError:
        raise InputError(f"--window: {text!r} is not T0:T1 (seconds), e.g. --window 2.5:40") from None
    if not bounds[0] <= bounds[1]:
        raise InputError(f"--window: {text!r} is empty or not a number; expected T0 <= T1")
    return bounds


def parse_meta(items) -> dict[str, str]:
    """``['KEY=VALUE', ...]`` (repeated ``--meta``) as a dict of ``#`` keys."""
    out: dict[str, str] = {}
    for item in items or ():
        key, sep, value = str(item).partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key or ":" in key or any(c in key + value for c in "\r\n"):
            raise InputError(f"--meta: {item!r} is not KEY=VALUE (a '#' key without ':'), "
                             "e.g. --meta torque_side=output")
        out[key] = value
    return out


def split_factor(source: str) -> tuple[str, float]:
    """A column map's source as (column name, factor): ``'5.11*iq_A'`` → ``('iq_A', 5.11)``.

    A source that is not ``NUMBER*name`` is a plain column name with factor 1.
    """
    match = _FACTOR.match(source)
    if not match:
        return source, 1.0
    factor = float(match.group(1))
    if not math.isfinite(factor) or factor == 0.0:
        raise InputError(f"column map source {source!r}: the factor must be a finite non-zero number")
    return match.group(2), factor


def apply_rows(data: dict, options: ImportOptions, where) -> tuple[dict, RowReport, np.ndarray]:
    """Apply the row operations of ``options`` to read columns, before they are checked.

    Parameters
    ----------
    data : dict of str to numpy.ndarray
        Canonical SI name -> values; ``time_s`` may be absent when ``options.sample_rate``
        is set.
    options : ImportOptions
        The options.
    where : hdsim.io.measurement_checks.Where
        Names the file in messages.

    Returns
    -------
    tuple
        (columns after the operations, `RowReport`, indices of the rows kept).

    Raises
    ------
    InputError
        A file without a time column and no sample rate, a time column and a sample
        rate both, a window that keeps no row.
    """
    n = len(next(iter(data.values()))) if data else 0
    time_from_rows = False
    if "time_s" not in data:
        if options.sample_rate is None:
            raise where.fail("no time column; give its name with columns={'time_s': NAME}, or the "
                             "sample rate of a log without one with sample_rate=HZ")
        data = {**data, "time_s": np.arange(n, dtype=float) / options.sample_rate}
        time_from_rows = True
    elif options.sample_rate is not None:
        raise where.fail("the file has a time column; sample_rate=HZ is for logs without one")
    runs = 1
    if options.concatenated:
        joined, runs = _joined_clock(data["time_s"])
        data = {**data, "time_s": joined}
    keep = np.ones(n, dtype=bool)
    windowed = 0
    if options.window is not None:
        t = data["time_s"]
        inside = (t >= options.window[0]) & (t <= options.window[1])
        windowed = int(np.count_nonzero(~inside & np.isfinite(t)))
        keep &= inside | ~np.isfinite(t)
        if not np.any(inside):
            raise where.fail(f"no row has time_s within the window {options.window[0]:g}:{options.window[1]:g} s "
                             f"(the file's time runs {np.nanmin(t):g} … {np.nanmax(t):g} s)")
    dropped = 0
    if options.drop_nan:
        finite = np.logical_and.reduce([np.isfinite(v) for v in data.values()])
        for rows in glitch_rows(data).values():
            finite[rows] = False
        dropped = int(np.count_nonzero(keep & ~finite))
        keep &= finite
    if not keep.all():
        data = {k: v[keep] for k, v in data.items()}
    return data, RowReport(dropped, windowed, runs, time_from_rows), np.flatnonzero(keep)


def glitch_rows(data: dict) -> dict[str, np.ndarray]:
    """The rows of each column that are isolated one-row glitches (`hdsim.signals.glitches`):
    a failed read that wrote a number, which would otherwise pass for the drive's answer.
    The time column is left to the clock's own check."""
    found = {name: glitches(values) for name, values in data.items() if name != "time_s"}
    return {name: rows for name, rows in found.items() if rows.size}


def _joined_clock(time: np.ndarray) -> tuple[np.ndarray, int]:
    """A clock that restarts (a drop) joined into one, and the number of runs: each run
    continues one median sample interval after the previous run's last sample."""
    t = np.asarray(time, dtype=float)
    step = np.diff(t)
    forward = step[np.isfinite(step) & (step > 0)]
    dt = float(np.median(forward)) if forward.size else 1.0
    restart = np.flatnonzero(np.isfinite(step) & (step <= 0))
    shift = np.zeros_like(t)
    for i in restart:  # rows after i belong to the next run
        shift[i + 1:] += t[i] + dt - t[i + 1]
    return t + shift, 1 + restart.size
