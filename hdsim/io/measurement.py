"""Measurement files: read, check and write bench data (CSV or HDF5).

The format is fixed by the project contract (``contracts.md`` section 1)::

    # test: stiffness            <- stiffness | kinematic_error (required)
    # ratio: 100                 <- transmission ratio; required for kinematic_error
    # rated_torque_Nm: 67        <- optional
    time_s,torque_Nm,angle_rad
    0.0,0.0,0.0
    ...

=================== ================================================================
test                columns (any order)
=================== ================================================================
``stiffness``       ``time_s``, ``torque_Nm``, ``angle_rad``
``kinematic_error`` ``time_s``, ``wg_angle_rad``, ``output_angle_rad``, ``torque_Nm``
=================== ================================================================

Angle columns may end in ``_deg``, ``_arcmin`` or ``_arcsec`` instead of ``_rad``;
they are converted to radians on reading. Files from another bench are read with a
column map (canonical name -> name in the file). The same data may come as HDF5: one
1-D dataset per column at the file's root, the ``#`` keys as file attributes.

Every problem is refused with one `hdsim.errors.InputError` line that names
the file, the line (CSV, 1-based, counting ``#`` lines and the header) or the row and
column (HDF5), and what was expected. Reading never writes anything.

Sign convention of the kinematic-error test (not fixed by the contract, chosen here):
``torque_Nm`` is the torque the load applies to the output, positive in the same sense
as in the stiffness test, so a positive torque twists the output positively relative to
``wg_angle_rad / ratio``.
"""

from __future__ import annotations

import csv
import difflib
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hdsim.io.atomic import atomic_path
from hdsim.errors import InputError

__all__ = [
    "Measurement",
    "TESTS",
    "ANGLE_UNITS",
    "load_measurement",
    "save_measurement",
    "parse_column_map",
    "make_measurement",
]

#: Columns each test needs, by canonical SI name.
TESTS: dict[str, tuple[str, ...]] = {
    "stiffness": ("time_s", "torque_Nm", "angle_rad"),
    "kinematic_error": ("time_s", "wg_angle_rad", "output_angle_rad", "torque_Nm"),
}

#: Angle unit suffixes and their size in radians.
ANGLE_UNITS: dict[str, float] = {
    "rad": 1.0,
    "deg": math.pi / 180.0,
    "arcmin": math.pi / (180.0 * 60.0),
    "arcsec": math.pi / (180.0 * 3600.0),
}

#: Fewest data rows a file may hold; below this nothing can be fitted.
MIN_ROWS = 10

_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
_HDF5_SUFFIXES = (".h5", ".hdf5", ".hdf")
_ANGLE_BASES = ("angle", "wg_angle", "output_angle")
# '#' keys this module interprets; all others are kept in ``meta`` untouched.
_RATED_KEYS = ("rated_torque_Nm", "rated_torque")


@dataclass(frozen=True, eq=False)
class Measurement:
    """One bench measurement in SI units.

    Attributes
    ----------
    test : str
        ``'stiffness'`` or ``'kinematic_error'``.
    time : numpy.ndarray
        Sample times, strictly increasing [s].
    torque : numpy.ndarray
        Stiffness test: torque applied to the output [N·m]. Kinematic-error test: load
        torque measured at the output [N·m].
    angle : numpy.ndarray
        Stiffness test: output twist; kinematic-error test: output angle [rad]. Any
        constant zero offset of the encoder is kept as measured.
    wg_angle : numpy.ndarray or None
        Wave-generator angle [rad] (kinematic-error test only).
    ratio : float or None
        Transmission ratio [-]; negative when the output turns the other way.
    rated_torque : float or None
        Rated torque T_N [N·m], if the file gives it.
    meta : dict of str to str
        Every ``#`` key of the file (HDF5: every attribute) as text.
    source : str
        Path the data were read from (or ``'<arrays>'``).
    """

    test: str
    time: np.ndarray
    torque: np.ndarray
    angle: np.ndarray
    wg_angle: np.ndarray | None = None
    ratio: float | None = None
    rated_torque: float | None = None
    meta: dict = field(default_factory=dict)
    source: str = "<arrays>"

    def __len__(self) -> int:
        return int(self.time.size)

    def __repr__(self) -> str:
        extra = f", ratio={self.ratio!r}" if self.ratio is not None else ""
        return f"Measurement(test={self.test!r}, rows={len(self)}{extra}, source={self.source!r})"

    @property
    def output_angle(self) -> np.ndarray | None:
        """Output angle [rad] of a kinematic-error test; None for a stiffness test."""
        return self.angle if self.test == "kinematic_error" else None

    @property
    def kinematic_error(self) -> np.ndarray | None:
        """``output_angle - wg_angle / ratio`` [rad]; None for a stiffness test."""
        if self.test != "kinematic_error":
            return None
        return self.angle - self.wg_angle / self.ratio

    def columns(self) -> dict[str, np.ndarray]:
        """The data as canonical SI columns in contract order, e.g. ``{'time_s': ...}``."""
        by_name = {
            "time_s": self.time,
            "torque_Nm": self.torque,
            "angle_rad": self.angle,
            "output_angle_rad": self.angle,
            "wg_angle_rad": self.wg_angle,
        }
        return {name: by_name[name] for name in TESTS[self.test]}


# --------------------------------------------------------------------------- names


def _split_unit(name: str) -> tuple[str, str] | None:
    """``'wg_angle_deg'`` -> ``('wg_angle', 'deg')``; None if not an angle name."""
    for base in _ANGLE_BASES:
        for unit in ANGLE_UNITS:
            if name == f"{base}_{unit}":
                return base, unit
    return None


def _canonical_names(test: str | None = None) -> list[str]:
    """Every accepted column name (all unit spellings) for ``test`` (or for any test)."""
    tests = [test] if test else list(TESTS)
    names: list[str] = []
    for t in tests:
        for col in TESTS[t]:
            split = _split_unit(col)
            spellings = [f"{split[0]}_{u}" for u in ANGLE_UNITS] if split else [col]
            names += [s for s in spellings if s not in names]
    return names


def parse_column_map(text: str) -> dict[str, str]:
    """Parse a CLI column map ``'time_s=t,torque_Nm=T_out,angle_deg=pos'``.

    Parameters
    ----------
    text : str
        Comma-separated ``canonical=name_in_file`` pairs. The canonical side is a
        contract column name; angle names may carry ``_rad``, ``_deg``, ``_arcmin`` or
        ``_arcsec`` to give the unit of the file's column.

    Returns
    -------
    dict of str to str
        Canonical name -> column name in the file.

    Raises
    ------
    InputError
        On a pair without ``=``, an empty side, an unknown canonical name or a
        canonical name given twice.
    """
    mapping: dict[str, str] = {}
    for pair in (p.strip() for p in str(text).split(",")):
        if not pair:
            continue
        key, sep, value = pair.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key or not value:
            raise InputError(
                f"--columns: malformed pair '{pair}'; expected canonical=name_in_file, "
                "e.g. time_s=t,torque_Nm=T_out,angle_deg=pos"
            )
        if key in mapping:
            raise InputError(f"--columns: '{key}' given twice")
        mapping[key] = value
    if not mapping:
        raise InputError("--columns: empty column map; expected e.g. time_s=t,torque_Nm=T_out")
    _check_map_keys(mapping, "--columns")
    return mapping


def _check_map_keys(mapping: dict[str, str], where: str) -> None:
    known = _canonical_names()
    for key, value in mapping.items():
        if key not in known:
            close = difflib.get_close_matches(key, known, n=3, cutoff=0.5)
            hint = f"did you mean {', '.join(close)}?" if close else f"known: {', '.join(known)}"
            raise InputError(f"{where}: unknown canonical column '{key}' in the column map; {hint}")
        if not isinstance(value, str) or not value:
            raise InputError(f"{where}: column map entry '{key}' needs a column name in the file")
    targets = list(mapping.values())
    for value in targets:
        if targets.count(value) > 1:
            raise InputError(f"{where}: column map reads file column '{value}' twice")


def _show(cell: str, limit: int = 30) -> str:
    """A cell quoted for a one-line message, shortened and free of line breaks."""
    text = repr(cell)
    return text if len(text) <= limit else text[: limit - 4] + "...'"


# --------------------------------------------------------------------------- checks


class _Where:
    """Turns a 0-based data row into the words a message uses (CSV line or HDF5 row)."""

    def __init__(self, path: str, lines: list[int] | None = None):
        self.path = path
        self.lines = lines  # CSV: the file line of each data row (1-based)

    def row(self, i: int) -> str:
        if self.lines is not None:
            return f"line {self.lines[i]}"
        return f"row {i + 1}"

    def fail(self, text: str) -> InputError:
        return InputError(f"{self.path}: {text}")


def _parse_number(where: "_Where", key: str, value: str, origin: str, *,
                  positive=False, nonzero=False) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not math.isfinite(number) or (positive and number <= 0) or (nonzero and number == 0):
        need = "a positive number" if positive else "a non-zero number" if nonzero else "a number"
        raise where.fail(f"{origin}'# {key}:' is {_show(str(value))}; expected {need}")
    return number


def _interpret_meta(
    meta: dict[str, str], where: _Where, origin: dict[str, str] | None = None
) -> tuple[str, float | None, float | None]:
    """``test``, ``ratio`` and ``rated_torque`` from the ``#`` keys, checked.

    ``origin`` maps a key to where it was read (``'line 2: '``), for messages.
    """
    origin = origin or {}
    tests = " or ".join(TESTS)
    if "test" not in meta:
        raise where.fail("no '# test:' key; expected '# test: stiffness' or "
                         "'# test: kinematic_error' (HDF5: a 'test' attribute)")
    test = meta["test"].strip()
    if test not in TESTS:
        close = difflib.get_close_matches(test, list(TESTS), n=1, cutoff=0.5)
        hint = f" (did you mean {close[0]}?)" if close else ""
        raise where.fail(f"{origin.get('test', '')}unknown test {_show(test)}{hint}; "
                         f"expected {tests}")
    ratio = None
    if "ratio" in meta:
        ratio = _parse_number(where, "ratio", meta["ratio"], origin.get("ratio", ""),
                              nonzero=True)
    elif test == "kinematic_error":
        raise where.fail("no '# ratio:' key; a kinematic_error file needs the transmission "
                         "ratio, e.g. '# ratio: 100'")
    rated = None
    for key in _RATED_KEYS:
        if key in meta:
            rated = _parse_number(where, key, meta[key], origin.get(key, ""), positive=True)
            break
    return test, ratio, rated


def _resolve_columns(
    header: list[str], test: str, columns: dict[str, str] | None, where: _Where, what: str
) -> dict[str, tuple[int, float]]:
    """Map each canonical SI column of ``test`` to (index in ``header``, unit factor).

    ``what`` is ``'column'`` (CSV) or ``'dataset'`` (HDF5), for messages.
    """
    for i, name in enumerate(header):
        if not name:
            raise where.fail(f"{what} {i + 1} of the header has no name")
        if header.count(name) > 1:
            raise where.fail(f"{what} '{name}' appears twice in the header")
    # Rename the file's columns to canonical names by the map (canonical -> file).
    canonical_of: dict[str, str] = {}
    if columns:
        _check_map_keys(columns, where.path)
        for key, file_name in columns.items():
            if file_name not in header:
                raise where.fail(f"column map reads '{key}' from {what} '{file_name}', which is "
                                 f"not in the file (it has {', '.join(header)})")
            canonical_of[file_name] = key
    allowed = _canonical_names(test)
    needed = TESTS[test]
    found: dict[str, tuple[int, str]] = {}  # canonical SI name -> (index, canonical spelling)
    for i, name in enumerate(header):
        spelled = canonical_of.get(name, name)
        if spelled not in allowed:
            if columns and name not in canonical_of and spelled not in _canonical_names():
                continue  # a column map names the columns to read; the rest are ignored
            raise where.fail(_unknown_column_text(name, spelled, test, what, bool(columns)))
        split = _split_unit(spelled)
        si = f"{split[0]}_rad" if split else spelled
        if si in found:
            first, first_spelled = header[found[si][0]], found[si][1]

            def shown(n, sp):
                return f"'{n}'" if n == sp else f"'{n}' (mapped to {sp})"

            raise where.fail(f"{what}s {shown(first, first_spelled)} and {shown(name, spelled)} "
                             f"both give {si}; expected one of them")
        found[si] = (i, spelled)
    for si in needed:
        if si not in found:
            split = _split_unit(si)
            alt = f" (or {split[0]}_deg/_arcmin/_arcsec)" if split else ""
            raise where.fail(f"missing {what} '{si}'{alt}; a {test} file needs "
                             f"{', '.join(needed)}")
    return {si: (i, ANGLE_UNITS[_split_unit(sp)[1]] if _split_unit(sp) else 1.0)
            for si, (i, sp) in found.items()}


def _unknown_column_text(name: str, spelled: str, test: str, what: str, mapped: bool) -> str:
    allowed = _canonical_names(test)
    shown = f"'{name}'" if name == spelled else f"'{name}' (mapped to {spelled})"
    close = difflib.get_close_matches(spelled, allowed, n=2, cutoff=0.6)
    hint = f" (did you mean {' or '.join(close)}?)" if close else ""
    if spelled in _canonical_names():
        hint = " (a column of the other test; is '# test:' right?)"
    if "," not in name and (";" in name or "\t" in name):
        hint = " (the separator must be a comma)"
    extra = "" if mapped else "; use a column map for another bench's names"
    return (f"unknown {what} {shown}{hint}; a {test} file has {', '.join(TESTS[test])} "
            f"(angles may end in _deg, _arcmin, _arcsec){extra}")


def _check_values(data: dict[str, np.ndarray], where: _Where, names: dict[str, str]) -> None:
    """Finite numbers, enough rows, strictly increasing time.

    ``names`` maps each canonical SI column to the column's name in the file, so that a
    message names what the user sees.
    """
    n = data["time_s"].size
    for si, values in data.items():
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            i = int(bad[0])
            raise where.fail(f"{where.row(i)}, {names[si]}: {float(values[i])!r} is not "
                             "finite; expected a finite number")
    if n < MIN_ROWS:
        raise where.fail(f"{n} data rows; expected at least {MIN_ROWS}")
    t = data["time_s"]
    bad = np.flatnonzero(~(np.diff(t) > 0))
    if bad.size:
        i = int(bad[0]) + 1
        raise where.fail(f"{where.row(i)}, {names['time_s']}: {float(t[i])!r} after "
                         f"{float(t[i - 1])!r}; expected time to increase strictly")


def _build(data: dict[str, np.ndarray], test: str, ratio, rated, meta, source) -> Measurement:
    def frozen(values):
        values = np.array(values, dtype=np.float64)  # a private copy, then read-only
        values.flags.writeable = False
        return values

    ke = test == "kinematic_error"
    return Measurement(
        test=test,
        time=frozen(data["time_s"]),
        torque=frozen(data["torque_Nm"]),
        angle=frozen(data["output_angle_rad" if ke else "angle_rad"]),
        wg_angle=frozen(data["wg_angle_rad"]) if ke else None,
        ratio=ratio,
        rated_torque=rated,
        meta=dict(meta),
        source=source,
    )


# --------------------------------------------------------------------------- CSV


def _read_csv(path: str, raw: bytes, columns) -> Measurement:
    where = _Where(path)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise where.fail(f"not a text CSV file (byte {exc.start + 1} is not UTF-8); expected "
                         "'# key: value' lines, a header row and numbers") from None
    lines = text.split("\n")
    if not text.strip():
        raise where.fail("the file is empty; expected '# test: ...', a header row and at "
                         f"least {MIN_ROWS} rows of numbers")
    meta: dict[str, str] = {}
    origin: dict[str, str] = {}  # key -> 'line N: ' for messages
    header_at = None
    for number, line in enumerate(lines, start=1):
        line = line.rstrip("\r")
        stripped = line.strip()
        if not stripped:
            continue
        if not stripped.startswith("#"):
            header_at = number
            break
        body = stripped[1:].strip()
        if not body:
            continue  # a bare '#' spacer line
        key, sep, value = body.partition(":")
        key = key.strip()
        if not sep or not key:
            raise where.fail(f"line {number}: malformed '#' line {_show(stripped, 40)}; "
                             "expected '# key: value'")
        if key in meta:
            raise where.fail(f"line {number}: '# {key}:' given twice")
        meta[key] = value.strip()
        origin[key] = f"line {number}: "
    if header_at is None:
        raise where.fail("no header row; expected a header such as "
                         "'time_s,torque_Nm,angle_rad' after the '#' lines")
    test, ratio, rated = _interpret_meta(meta, where, origin)
    header = [h.strip() for h in next(csv.reader([lines[header_at - 1].rstrip("\r")]))]
    index = _resolve_columns(header, test, columns, where, "column")

    rows: list[list[str]] = []
    numbers: list[int] = []
    for number in range(header_at + 1, len(lines) + 1):
        line = lines[number - 1].rstrip("\r")
        if not line.strip():
            continue
        if line.lstrip().startswith("#"):
            raise where.fail(f"line {number}: '#' line after the header; expected '#' lines "
                             "only before the header")
        cells = line.split(",")
        if len(cells) != len(header):
            raise where.fail(f"line {number}: {len(cells)} cells; expected {len(header)} "
                             f"({', '.join(header)})")
        rows.append(cells)
        numbers.append(number)
    where = _Where(path, lines=numbers)
    if not rows:
        raise where.fail(f"no data rows after the header; expected at least {MIN_ROWS}")
    data = {si: _column_values(rows, i, header[i], where) * factor
            for si, (i, factor) in index.items()}
    _check_values(data, where, {si: f"column '{header[i]}'" for si, (i, _) in index.items()})
    return _build(data, test, ratio, rated, meta, path)


def _column_values(rows: list[list[str]], i: int, name: str, where: _Where) -> np.ndarray:
    cells = [row[i] for row in rows]
    try:
        return np.array(cells, dtype=np.float64)
    except ValueError:
        pass
    for r, cell in enumerate(cells):  # slow path only to name the first bad cell
        try:
            float(cell)
        except ValueError:
            raise where.fail(f"{where.row(r)}, column '{name}': {_show(cell.strip())} is not "
                             "a number; expected a number") from None
    raise where.fail(f"column '{name}': cannot read the numbers")  # pragma: no cover


# --------------------------------------------------------------------------- HDF5


def _attr_text(value) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(-1)[0]
    if isinstance(value, np.generic):
        value = value.item()
        if isinstance(value, bytes):
            return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray):
        return " ".join(_attr_text(v) for v in value.reshape(-1))
    return str(value)


def _read_hdf5(path: str, columns) -> Measurement:
    import h5py

    where = _Where(path)
    try:
        handle = h5py.File(path, "r")
    except OSError as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise where.fail(f"cannot read as HDF5 ({reason}); expected an HDF5 file with one "
                         "dataset per column") from None
    with handle:
        meta = {str(k): _attr_text(v) for k, v in handle.attrs.items()}
        test, ratio, rated = _interpret_meta(meta, where, {k: f"attribute '{k}': " for k in meta})
        # Groups (e.g. provenance) are not columns; only root datasets are.
        header = [name for name, item in handle.items() if isinstance(item, h5py.Dataset)]
        if not header:
            raise where.fail(f"no datasets at the file's root; a {test} file needs "
                             f"{', '.join(TESTS[test])}")
        index = _resolve_columns(header, test, columns, where, "dataset")
        data, length = {}, None
        for si, (i, factor) in index.items():
            name = header[i]
            dset = handle[name]
            if dset.ndim != 1:
                raise where.fail(f"dataset '{name}' has shape {dset.shape}; expected a 1-D column")
            if dset.dtype.kind not in "iuf":
                raise where.fail(f"dataset '{name}' holds {dset.dtype} values; expected numbers")
            if length is not None and dset.shape[0] != length[1]:
                raise where.fail(f"dataset '{name}' has {dset.shape[0]} rows but "
                                 f"'{length[0]}' has {length[1]}; expected equal lengths")
            length = length or (name, dset.shape[0])
            data[si] = np.asarray(dset[()], dtype=np.float64) * factor
    _check_values(data, where, {si: f"dataset '{header[i]}'" for si, (i, _) in index.items()})
    return _build(data, test, ratio, rated, meta, path)


# --------------------------------------------------------------------------- API


def load_measurement(path: str | os.PathLike, columns: dict[str, str] | None = None) -> Measurement:
    """Read and check a measurement file (CSV, or HDF5 by suffix or content).

    Parameters
    ----------
    path : str or os.PathLike
        The file. ``.h5``/``.hdf5``/``.hdf`` files, and any file starting with the HDF5
        signature, are read as HDF5; everything else as CSV.
    columns : dict of str to str, optional
        Column map, canonical name -> name in the file, e.g.
        ``{"time_s": "t", "torque_Nm": "T_out", "angle_deg": "pos"}``. An angle key's
        suffix gives the unit of the file's column. With a map, file columns that are
        neither mapped nor canonical are ignored (another bench logs more than this test
        needs); without one, every column must be a contract column.

    Returns
    -------
    Measurement
        SI data; angles in [rad] with the file's zero offset kept.

    Raises
    ------
    InputError
        One line naming the file, the line/row or column and what was expected, for: a
        missing file, an empty file, a malformed ``#`` line, a missing or unknown
        ``test``, a missing ratio (kinematic_error), a missing, unknown or duplicated
        column, a non-numeric, NaN or infinite cell, fewer than 10 rows, time not
        strictly increasing, an unreadable HDF5 file.
    """
    shown = str(path)
    try:
        with open(path, "rb") as handle:
            head = handle.read(len(_HDF5_SIGNATURE))
            is_hdf5 = head == _HDF5_SIGNATURE or Path(shown).suffix.lower() in _HDF5_SUFFIXES
            raw = head if is_hdf5 else head + handle.read()
    except FileNotFoundError:
        raise InputError(f"{shown}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{shown}: is a directory; expected a measurement file") from None
    except OSError as exc:
        raise InputError(f"{shown}: cannot read ({exc.strerror or exc})") from None
    if columns is not None and not isinstance(columns, dict):
        raise InputError(f"{shown}: the column map must be a dict canonical -> name in file")
    if is_hdf5:
        if not raw:
            raise InputError(f"{shown}: the file is empty; expected an HDF5 file")
        return _read_hdf5(shown, columns)
    return _read_csv(shown, raw, columns)


def make_measurement(
    test: str,
    time,
    torque,
    angle,
    wg_angle=None,
    ratio: float | None = None,
    rated_torque: float | None = None,
    meta: dict | None = None,
    source: str = "<arrays>",
) -> Measurement:
    """Build a checked `Measurement` from arrays in SI units.

    Parameters
    ----------
    test : str
        ``'stiffness'`` or ``'kinematic_error'``.
    time, torque, angle : array_like
        Time [s], torque [N·m], twist or output angle [rad].
    wg_angle : array_like, optional
        Wave-generator angle [rad]; required for ``'kinematic_error'``.
    ratio : float, optional
        Transmission ratio [-]; required for ``'kinematic_error'``.
    rated_torque : float, optional
        Rated torque [N·m].
    meta : dict, optional
        Extra ``#`` keys (values kept as text).
    source : str
        A label for messages.

    Raises
    ------
    InputError
        On the same problems `load_measurement` refuses.
    """
    text_meta = {str(k): str(v) for k, v in (meta or {}).items()}
    text_meta["test"] = str(test)
    if ratio is not None:
        text_meta["ratio"] = repr(float(ratio))
    if rated_torque is not None:
        text_meta["rated_torque_Nm"] = repr(float(rated_torque))
    where = _Where(source)
    test, ratio, rated = _interpret_meta(text_meta, where)
    given = {"time_s": time, "torque_Nm": torque, "angle_rad": angle,
             "output_angle_rad": angle, "wg_angle_rad": wg_angle}
    data = {}
    for name in TESTS[test]:
        if given[name] is None:
            raise where.fail(f"missing column '{name}'; a {test} measurement needs "
                             f"{', '.join(TESTS[test])}")
        try:
            values = np.asarray(given[name], dtype=np.float64)
        except (TypeError, ValueError):
            raise where.fail(f"column '{name}' is not numeric; expected numbers") from None
        if values.ndim != 1:
            raise where.fail(f"column '{name}' has shape {values.shape}; expected 1-D")
        data[name] = values
    sizes = {name: v.size for name, v in data.items()}
    if len(set(sizes.values())) > 1:
        raise where.fail(f"columns differ in length ({sizes}); expected equal lengths")
    _check_values(data, where, {si: f"column '{si}'" for si in data})
    return _build(data, test, ratio, rated, text_meta, source)


def _meta_for_writing(meas: Measurement) -> dict[str, str]:
    """The ``#`` keys to write: the fields first (authoritative), then the rest of meta."""
    meta = {"test": meas.test}
    if meas.ratio is not None:
        meta["ratio"] = repr(float(meas.ratio))
    if meas.rated_torque is not None:
        meta["rated_torque_Nm"] = repr(float(meas.rated_torque))
    for key, value in meas.meta.items():
        if key in meta or key in _RATED_KEYS:
            continue
        meta[str(key)] = str(value)
    for key, value in meta.items():
        bad = not key.strip() or ":" in key or any(c in key + value for c in "\r\n")
        if bad:
            raise InputError(f"cannot write '#' key {_show(key)}: keys need no ':' and neither "
                             "key nor value may hold a line break")
    return meta


def save_measurement(meas: Measurement, path: str | os.PathLike) -> Path:
    """Write a measurement atomically in canonical SI columns with its ``#`` keys.

    Parameters
    ----------
    meas : Measurement
        The data.
    path : str or os.PathLike
        Target file; ``.h5``/``.hdf5``/``.hdf`` writes HDF5 (one dataset per column,
        keys as attributes), anything else CSV. Numbers are written with the shortest
        text that reads back to the same float, so save -> load is exact.

    Returns
    -------
    pathlib.Path
        The written file.
    """
    path = Path(path)
    meta = _meta_for_writing(meas)
    cols = meas.columns()
    with atomic_path(path) as tmp:
        if path.suffix.lower() in _HDF5_SUFFIXES:
            import h5py

            with h5py.File(tmp, "w") as handle:
                for key, value in meta.items():
                    handle.attrs[key] = value
                for name, values in cols.items():
                    handle.create_dataset(name, data=np.asarray(values, dtype=np.float64))
        else:
            with open(tmp, "w", encoding="utf-8", newline="\n") as out:
                for key, value in meta.items():
                    out.write(f"# {key}: {value}\n")
                out.write(",".join(cols) + "\n")
                # Python's float repr is the shortest exact round-trip text.
                table = np.column_stack(list(cols.values())).tolist()
                out.write("".join(",".join(map(repr, row)) + "\n" for row in table))
    return path
