"""Readers of measurement files: CSV and HDF5, by suffix or by content.

Each reader turns one file into checked SI columns and the interpreted ``#`` keys
(`Parsed`); `hdsim.io.measurement.load_measurement` builds the `Measurement` from
them. The format is described in docs/measurements.md; the checks they share with
arrays given in memory are in `hdsim.io.measurement_checks`. Reading never writes
anything.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path
from typing import NamedTuple

import numpy as np

from hdsim.errors import InputError
from hdsim.io.import_options import AS_WRITTEN, ImportOptions, RowReport, apply_rows
from hdsim.io.measurement_checks import (
    MIN_ROWS,
    TESTS,
    Where,
    check_values,
    complete_angles,
    interpret_meta,
    quote_cell,
    resolve_columns,
)

__all__ = ["Parsed", "HDF5_SUFFIXES", "read_measurement_file", "read_csv", "read_hdf5"]

#: File suffixes read and written as HDF5 (any other file is read as CSV unless it
#: starts with the HDF5 signature).
HDF5_SUFFIXES = (".h5", ".hdf5", ".hdf")

_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


class Parsed(NamedTuple):
    """What a reader found in one file, checked.

    Attributes
    ----------
    data : dict of str to numpy.ndarray
        Canonical SI name (``'time_s'``, ``'angle_rad'``, ...) -> values in SI units
        ([s], [N·m], [rad]).
    test : str
        ``'stiffness'`` or ``'kinematic_error'``.
    ratio : float or None
        Transmission ratio [-].
    rated_torque : float or None
        Rated torque [N·m].
    meta : dict of str to str
        Every ``#`` key (HDF5: attribute) as text, the import options' keys applied.
    rows : RowReport
        What the import options did to the rows.
    """

    data: dict
    test: str
    ratio: float | None
    rated_torque: float | None
    meta: dict
    rows: RowReport = RowReport()


def read_measurement_file(path: str | os.PathLike, columns: dict[str, str] | None,
                          options: ImportOptions = AS_WRITTEN) -> Parsed:
    """Open a measurement file and read it as HDF5 or as CSV.

    Parameters
    ----------
    path : str or os.PathLike
        The file. ``.h5``/``.hdf5``/``.hdf`` files, and any file starting with the HDF5
        signature, are read as HDF5; everything else as CSV.
    columns : dict of str to str or None
        Column map, canonical name -> name in the file (a name may be ``FACTOR*name``).
    options : ImportOptions
        What the user says of the log (keys, rows, time axis).

    Returns
    -------
    Parsed
        The checked columns and keys.

    Raises
    ------
    InputError
        On a missing or unreadable file, a column map that is not a dict, and every
        refusal of `read_csv` and `read_hdf5`.
    """
    shown = str(path)
    try:
        with open(path, "rb") as handle:
            head = handle.read(len(_HDF5_SIGNATURE))
            is_hdf5 = head == _HDF5_SIGNATURE or Path(shown).suffix.lower() in HDF5_SUFFIXES
            raw = head if is_hdf5 else head + handle.read()
    except FileNotFoundError:
        raise InputError(f"{shown}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{shown}: is a directory; expected a measurement file") from None
    except OSError as exc:
        raise InputError(f"{shown}: cannot read ({exc.strerror or exc})") from None
    except ValueError as exc:  # a name the system refuses: a NUL byte
        raise InputError(f"{shown!r}: cannot read ({exc})") from None
    if columns is not None and not isinstance(columns, dict):
        raise InputError(f"{shown}: the column map must be a dict canonical -> name in file")
    if is_hdf5:
        if not raw:
            raise InputError(f"{shown}: the file is empty; expected an HDF5 file")
        return read_hdf5(shown, columns, options)
    return read_csv(shown, raw, columns, options)


# --------------------------------------------------------------------------- CSV


def read_csv(path: str, raw: bytes, columns: dict[str, str] | None,
             options: ImportOptions = AS_WRITTEN) -> Parsed:
    """Read the bytes of a CSV measurement file.

    Parameters
    ----------
    path : str
        The file, for messages.
    raw : bytes
        The whole file (UTF-8, a byte-order mark and Windows line ends allowed).
    columns : dict of str to str or None
        Column map, canonical name -> name in the file.
    options : ImportOptions
        What the user says of the log.

    Returns
    -------
    Parsed
        The checked columns and keys.

    Raises
    ------
    InputError
        Naming the line (1-based, counting ``#`` lines and the header) for: text that is
        not UTF-8, an empty file, a malformed or repeated ``#`` line, a missing header,
        a ``#`` line after the header, a row with the wrong number of cells, a cell
        that is not a number, and every refusal of `hdsim.io.measurement_checks`.
    """
    where = Where(path)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise where.fail(f"not a text CSV file (byte {exc.start + 1} is not UTF-8); expected "
                         "'# key: value' lines, a header row and numbers") from None
    if not text.strip():
        raise where.fail("the file is empty; expected '# test: ...', a header row and at "
                         f"least {MIN_ROWS} rows of numbers")
    meta: dict[str, str] = {}
    origin: dict[str, str] = {}  # key -> 'line N: ' for messages
    header_at = header_line = None
    body_at = len(text)  # where the data rows start (a character offset)
    for number, (line, body_at) in enumerate(_head_lines(text), start=1):
        line = line.rstrip("\r")
        stripped = line.strip()
        if not stripped:
            continue
        if not stripped.startswith("#"):
            header_at, header_line = number, line
            break
        body = stripped[1:].strip()
        if not body:
            continue  # a bare '#' spacer line
        key, sep, value = body.partition(":")
        key = key.strip()
        if not sep or not key or " " in key:
            # a free-text note ("# bench 3, after the oil change"): a log written by bench
            # software keeps it, and nothing in a log needs editing to be read
            continue
        if key in meta:
            raise where.fail(f"line {number}: '# {key}:' given twice")
        meta[key] = value.strip()
        origin[key] = f"line {number}: "
    if header_at is None:
        raise where.fail("no header row; expected a header such as "
                         "'time_s,torque_Nm,angle_rad' after the '#' lines")
    keys, origin = _with_options(meta, origin, options)
    test, ratio, rated = interpret_meta(keys, where, origin)
    header = _header_cells(header_line, header_at, where)
    index = resolve_columns(header, test, columns, where, "column", _optional(options))

    offset = len(text[:body_at].encode("utf-8")) + (3 if raw.startswith(b"\xef\xbb\xbf") else 0)
    if len(raw) - offset >= FAST_BODY:
        del text  # a long log's decoded copy is as large as the file: not kept while numpy parses
        fast = _numeric_body(raw, offset, len(header))
        if fast is not None:  # a clean numeric table: parsed without a Python string per cell
            numbers = np.arange(header_at + 1, header_at + 1 + len(fast))
            data = {si: fast[:, i] * factor for si, (i, factor) in index.items()}
            del fast
            return _finish(path, data, numbers, options, test, ratio, rated, meta, header, index)
        text = raw.decode("utf-8-sig")
    lines = text[body_at:].split("\n")
    rows: list[list[str]] = []
    numbers: list[int] = []
    for number, line in enumerate(lines, start=header_at + 1):
        line = line.rstrip("\r")
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
    where = Where(path, lines=numbers)
    if not rows:
        raise where.fail(f"no data rows after the header; expected at least {MIN_ROWS}")
    data = {si: _column_values(rows, i, header[i], where, options.drop_nan) * factor
            for si, (i, factor) in index.items()}
    return _finish(path, data, np.asarray(numbers), options, test, ratio, rated, meta, header, index)


def _finish(path, data, numbers, options, test, ratio, rated, meta, header, index) -> Parsed:
    """The import options and the value checks on the parsed columns (``numbers``: the file
    line of each row, for the messages)."""
    data, report, kept = apply_rows(data, options, Where(path, lines=numbers))
    where = Where(path, lines=numbers[kept])
    check_values(data, where, _shown(header, index))
    data = complete_angles(data, test, ratio, where)
    return Parsed(data, test, ratio, rated, {**meta, **options.overrides()}, report)


#: a body shorter than this [bytes] is parsed cell by cell (about 20,000 rows): the
#: numeric parser's start-up is not worth it, and the messages of the cell parser are exact
FAST_BODY = 1_000_000


def _head_lines(text: str):
    """``(line, offset of the next line)`` from the start of ``text``, without splitting the
    whole file (the '#' lines and the header are all that is read this way)."""
    start = 0
    while start < len(text):
        end = text.find("\n", start)
        end = len(text) if end < 0 else end
        yield text[start:end], end + 1
        start = end + 1


def _numeric_body(raw: bytes, offset: int, width: int) -> np.ndarray | None:
    """The data rows as a (rows, width) float array when the body (from byte ``offset`` of
    ``raw``) is a clean numeric table: no blank, '#' or short line and no empty cell. Else
    None, and the cell-by-cell parser reads it and names the line of anything wrong. A
    ten-million-row log then costs its array, not a Python string per cell (about 300
    bytes a row): numpy's parser reads the file's bytes where they are."""
    stream = io.BytesIO(raw)
    stream.seek(offset)
    try:
        values = np.loadtxt(stream, delimiter=",", dtype=np.float64, ndmin=2, comments=None, encoding="utf-8")
    except ValueError:
        return None
    rows = raw.count(b"\n", offset) + (0 if raw.endswith(b"\n") else 1)
    if values.shape != (rows, width):  # a blank line was skipped: the line numbers would drift
        return None
    return values


def _with_options(meta: dict, origin: dict, options: ImportOptions) -> tuple[dict, dict]:
    """The file's keys with the import options' keys over them, and where each came from."""
    keys = options.overrides()
    return {**meta, **keys}, {**origin, **{k: "option: " for k in keys}}


def _optional(options: ImportOptions) -> tuple[str, ...]:
    """Columns a file may lack under these options: the time when it comes from the row index."""
    return ("time_s",) if options.sample_rate is not None else ()


def _shown(header, index) -> dict[str, str]:
    shown = {si: f"column '{header[i]}'" for si, (i, _) in index.items()}
    return {"time_s": "time_s (from the row index)", **shown}


def _header_cells(line: str, number: int, where: Where) -> list[str]:
    try:
        return [h.strip() for h in next(csv.reader([line]))]
    except csv.Error as exc:  # a lone carriage return inside the line, a name over csv's size limit
        why = "a carriage return inside the line" if "\r" in line else str(exc)
        raise where.fail(f"line {number}: cannot read the header row ({why}); expected column "
                         "names separated by commas, lines ending in \\n or \\r\\n") from None


def _column_values(rows: list[list[str]], i: int, name: str, where: Where, blank_is_nan: bool) -> np.ndarray:
    cells = [row[i] for row in rows]
    if blank_is_nan:  # --drop-nan: an empty cell is a failed read, like a written NaN
        cells = [cell if cell.strip() else "nan" for cell in cells]
    try:
        return np.array(cells, dtype=np.float64)
    except ValueError:
        pass
    for r, cell in enumerate(cells):  # slow path only to name the first bad cell
        try:
            float(cell)
        except ValueError:
            raise where.fail(f"{where.row(r)}, column '{name}': {quote_cell(cell.strip())} is "
                             "not a number; expected a number") from None
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


def read_hdf5(path: str, columns: dict[str, str] | None, options: ImportOptions = AS_WRITTEN) -> Parsed:
    """Read an HDF5 measurement file: one 1-D dataset per column, keys as attributes.

    Parameters
    ----------
    path : str
        The file.
    columns : dict of str to str or None
        Column map, canonical name -> dataset name in the file.
    options : ImportOptions
        What the user says of the log.

    Returns
    -------
    Parsed
        The checked columns and keys (every root attribute as text).

    Raises
    ------
    InputError
        Naming the dataset or row for: a file h5py cannot open, no dataset at the root,
        a dataset that is not a 1-D column of numbers, datasets of unequal length, and
        every refusal of `hdsim.io.measurement_checks`.
    """
    import h5py

    where = Where(path)
    try:
        handle = h5py.File(path, "r")
    except OSError as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise where.fail(f"cannot read as HDF5 ({reason}); expected an HDF5 file with one "
                         "dataset per column") from None
    with handle:
        meta = {str(k): _attr_text(v) for k, v in handle.attrs.items()}
        if "test" not in meta and {"hdsim_version", "scenario"} <= set(meta):
            raise where.fail(f"this is an hdsim result file (the {meta['scenario']} scenario run by hdsim "
                             "simulate), not a bench record; hdsim.read_run reads it, and docs/measurements.md "
                             "shows how to turn a run into a record")
        keys, origin = _with_options(meta, {k: f"attribute '{k}': " for k in meta}, options)
        test, ratio, rated = interpret_meta(keys, where, origin)
        # Groups (e.g. provenance) are not columns; only root datasets are.
        header = [name for name, item in handle.items() if isinstance(item, h5py.Dataset)]
        if not header:
            raise where.fail(f"no datasets at the file's root; a {test} file needs "
                             f"{', '.join(TESTS[test])}")
        index = resolve_columns(header, test, columns, where, "dataset", _optional(options))
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
    data, report, _ = apply_rows(data, options, where)
    check_values(data, where, {"time_s": "time_s (from the row index)",
                               **{si: f"dataset '{header[i]}'" for si, (i, _) in index.items()}})
    data = complete_angles(data, test, ratio, where)
    return Parsed(data, test, ratio, rated, {**meta, **options.overrides()}, report)
