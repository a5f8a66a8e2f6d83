"""Rules of the measurement-file format: column names, column maps, ``#`` keys, values.

Shared by the CSV and HDF5 readers (`hdsim.io.measurement_readers`) and by
`hdsim.io.measurement.make_measurement`, so that a file and a set of arrays are refused
for the same problems with the same words. The format itself is described in
docs/measurements.md.

Every check raises `hdsim.errors.InputError` with one line that names the file, the
place (CSV line, HDF5 row, column or attribute) and what was expected.
"""

from __future__ import annotations

import difflib
import math

import numpy as np

from hdsim.errors import InputError
from hdsim.io.import_options import glitch_rows, split_factor
from hdsim.units import ANGLE_UNITS

__all__ = [
    "TESTS",
    "ANGLE_UNITS",
    "MIN_ROWS",
    "RATED_KEYS",
    "Where",
    "parse_column_map",
    "check_map_keys",
    "canonical_names",
    "split_unit",
    "quote_cell",
    "interpret_meta",
    "resolve_columns",
    "check_values",
    "complete_angles",
    "OPTIONAL_COLUMNS",
    "TORQUE_SIDES",
]

#: Columns each test needs, by canonical SI name.
TESTS: dict[str, tuple[str, ...]] = {
    "stiffness": ("time_s", "torque_Nm", "angle_rad"),
    "kinematic_error": ("time_s", "wg_angle_rad", "output_angle_rad", "torque_Nm"),
    "running_torque": ("time_s", "wg_angle_rad", "output_angle_rad", "torque_Nm", "temperature_C"),
    "breakaway": ("time_s", "wg_angle_rad", "output_angle_rad", "torque_Nm", "temperature_C"),
}

#: Columns a test may lack: a running-torque test needs one angle (the ratio gives the
#: other) and may log the temperature.
OPTIONAL_COLUMNS: dict[str, tuple[str, ...]] = {
    "running_torque": ("wg_angle_rad", "output_angle_rad", "temperature_C"),
    "breakaway": ("wg_angle_rad", "output_angle_rad", "temperature_C"),
}

#: Of these, a test needs at least one: the tests of a drive turning with one shaft free
#: (friction sweep, breakaway ramp), whose torque is referred to the shaft ``# torque_side:`` names.
ONE_OF: dict[str, tuple[str, ...]] = {"running_torque": ("wg_angle_rad", "output_angle_rad"),
                                      "breakaway": ("wg_angle_rad", "output_angle_rad")}

#: the tests built in (a registered test kind adds its own; `register_test_columns`)
_BUILTIN_TESTS = tuple(TESTS)


def register_test_columns(test: str, columns, optional=()) -> None:
    """Let the file reader take records of a test the identification layer registered
    (`hdsim.identification.test_kinds.register_test_kind`): its columns by canonical SI
    name, and those of them it may lack. A built-in test's columns cannot be replaced."""
    if test in _BUILTIN_TESTS:
        raise InputError(f"the {test} test is built in; its columns cannot be replaced")
    TESTS[test] = tuple(columns)
    OPTIONAL_COLUMNS[test] = tuple(optional)


def unregister_test_columns(test: str) -> None:
    """Forget a test added with `register_test_columns`."""
    if test not in _BUILTIN_TESTS:
        TESTS.pop(test, None)
        OPTIONAL_COLUMNS.pop(test, None)


#: Values of ``# torque_side:`` (running-torque test): the shaft the torque is referred to.
TORQUE_SIDES = ("input", "output")

#: Fewest data rows a file may hold; below this nothing can be fitted.
MIN_ROWS = 10

#: ``#`` keys that give the rated torque, in order of preference. The keys ``test``,
#: ``ratio`` and these are interpreted; all others are kept in ``meta`` untouched.
RATED_KEYS = ("rated_torque_Nm", "rated_torque")

_ANGLE_BASES = ("angle", "wg_angle", "output_angle")


# --------------------------------------------------------------------------- names


def split_unit(name: str) -> tuple[str, str] | None:
    """Split an angle column name into its base and unit.

    Parameters
    ----------
    name : str
        A column name, e.g. ``'wg_angle_deg'``.

    Returns
    -------
    tuple of (str, str) or None
        ``('wg_angle', 'deg')``; None if ``name`` is not an angle column name.
    """
    for base in _ANGLE_BASES:
        for unit in ANGLE_UNITS:
            if name == f"{base}_{unit}":
                return base, unit
    return None


def canonical_names(test: str | None = None) -> list[str]:
    """Every accepted column name (all unit spellings) of one test or of any test.

    Parameters
    ----------
    test : str, optional
        A test name (`TESTS`); None for the names of every test.

    Returns
    -------
    list of str
        The names in the order of `TESTS`, each angle in every unit of
        `hdsim.units.ANGLE_UNITS`.
    """
    tests = [test] if test else list(TESTS)
    names: list[str] = []
    for t in tests:
        for col in TESTS[t]:
            split = split_unit(col)
            spellings = [f"{split[0]}_{u}" for u in ANGLE_UNITS] if split else [col]
            names += [s for s in spellings if s not in names]
    return names


def parse_column_map(text: str) -> dict[str, str]:
    """Parse a CLI column map ``'time_s=t,torque_Nm=T_out,angle_deg=pos'``.

    Parameters
    ----------
    text : str
        Comma-separated ``canonical=name_in_file`` pairs. The canonical side is a
        canonical column name (docs/measurements.md); angle names may carry ``_rad``,
        ``_deg``, ``_arcmin`` or ``_arcsec`` to give the unit of the file's column.

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
    check_map_keys(mapping, "--columns")
    return mapping


def check_map_keys(mapping: dict[str, str], where: str) -> None:
    """Refuse a column map with an unknown canonical name or a file column read twice.

    Parameters
    ----------
    mapping : dict of str to str
        Canonical name -> column name in the file.
    where : str
        What the message starts with (the file, or ``'--columns'``).

    Raises
    ------
    InputError
        On an unknown canonical name (with the closest known names), an empty file
        column name, or one file column mapped twice.
    """
    known = canonical_names()
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


def quote_cell(cell: str, limit: int = 30) -> str:
    """A cell quoted for a one-line message, shortened and free of line breaks.

    Parameters
    ----------
    cell : str
        The text as found in the file.
    limit : int
        Longest quoted text [characters].

    Returns
    -------
    str
        ``repr(cell)``, cut to ``limit`` characters with ``...`` when longer.
    """
    text = repr(cell)
    return text if len(text) <= limit else text[: limit - 4] + "...'"


# --------------------------------------------------------------------------- checks


class Where:
    """Turns a 0-based data row into the words a message uses (CSV line or HDF5 row).

    Parameters
    ----------
    path : str
        The file (or label) every message starts with.
    lines : list of int, optional
        CSV: the file line (1-based) of each data row; None names rows instead.
    """

    def __init__(self, path: str, lines: list[int] | None = None):
        self.path = path
        self.lines = lines

    def row(self, i: int) -> str:
        """``'line N'`` (CSV) or ``'row N'`` for data row ``i`` (0-based)."""
        if self.lines is not None:
            return f"line {self.lines[i]}"
        return f"row {i + 1}"

    def fail(self, text: str) -> InputError:
        """The error to raise: ``text`` after the file name."""
        return InputError(f"{self.path}: {text}")


def _parse_number(where: Where, key: str, value: str, origin: str, *,
                  positive=False, nonzero=False) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not math.isfinite(number) or (positive and number <= 0) or (nonzero and number == 0):
        need = "a positive number" if positive else "a non-zero number" if nonzero else "a number"
        raise where.fail(f"{origin}'# {key}:' is {quote_cell(str(value))}; expected {need}")
    return number


def interpret_meta(
    meta: dict[str, str], where: Where, origin: dict[str, str] | None = None
) -> tuple[str, float | None, float | None]:
    """``test``, ``ratio`` and ``rated_torque`` from the ``#`` keys, checked.

    Parameters
    ----------
    meta : dict of str to str
        Every ``#`` key (HDF5: attribute) as text.
    where : Where
        Names the file in messages.
    origin : dict of str to str, optional
        Key -> where it was read (``'line 2: '``), put in front of a message.

    Returns
    -------
    tuple of (str, float or None, float or None)
        The test, the transmission ratio [-] and the rated torque [N·m].

    Raises
    ------
    InputError
        On a missing or unknown test, a missing ratio (kinematic_error, breakaway, a torque
        on the output of a running-torque test), or a ratio or
        rated torque that is not a number (zero ratio, rated torque not positive).
    """
    origin = origin or {}
    tests = ", ".join(list(TESTS)[:-1]) + " or " + list(TESTS)[-1]
    if "test" not in meta:
        raise where.fail(f"no '# test:' key; expected '# test: T' with T {tests} (HDF5: a 'test' attribute; "
                         "a log without keys: test=TEST)")
    test = meta["test"].strip()
    if test not in TESTS:
        close = difflib.get_close_matches(test, list(TESTS), n=1, cutoff=0.5)
        hint = f" (did you mean {close[0]}?)" if close else ""
        raise where.fail(f"{origin.get('test', '')}unknown test {quote_cell(test)}{hint}; "
                         f"expected {tests}")
    side = meta.get("torque_side", "input").strip()
    if test in ONE_OF and side not in TORQUE_SIDES:
        raise where.fail(f"{origin.get('torque_side', '')}'# torque_side:' is {quote_cell(side)}; expected "
                         "input or output (the shaft the running torque is referred to)")
    ratio = None
    if "ratio" in meta:
        ratio = _parse_number(where, "ratio", meta["ratio"], origin.get("ratio", ""),
                              nonzero=True)
    elif (why := _why_ratio(test, side)):
        raise where.fail(f"no '# ratio:' key; a {test} file {why}, e.g. '# ratio: 100' (or ratio=100)")
    rated = None
    for key in RATED_KEYS:
        if key in meta:
            rated = _parse_number(where, key, meta[key], origin.get(key, ""), positive=True)
            break
    return test, ratio, rated


def _why_ratio(test: str, side: str) -> str:
    """Why a record of ``test`` with its torque on ``side`` needs the ratio ('' when it does not)."""
    if test == "kinematic_error":
        return "needs the transmission ratio"
    if test == "breakaway":
        # its starting torques are given on both shafts and compared with the catalog's output figure
        return "needs the transmission ratio to give its starting torques on both shafts"
    if test in ONE_OF and side == "output":
        # the law is fitted on the wave-generator shaft: without the ratio an output torque
        # would be taken for the input's, a hundred times too large
        return "with '# torque_side: output' needs the transmission ratio to refer the torque to the input"
    return ""


def resolve_columns(
    header: list[str], test: str, columns: dict[str, str] | None, where: Where, what: str,
    optional: tuple[str, ...] = (),
) -> dict[str, tuple[int, float]]:
    """Map each canonical SI column of ``test`` to (index in ``header``, unit factor).

    Parameters
    ----------
    header : list of str
        The file's column (CSV) or dataset (HDF5) names, in file order.
    test : str
        ``'stiffness'`` or ``'kinematic_error'``.
    columns : dict of str to str or None
        Column map, canonical name -> name in the file. With a map, file columns that
        are neither mapped nor canonical are ignored.
    where : Where
        Names the file in messages.
    what : str
        ``'column'`` (CSV) or ``'dataset'`` (HDF5), for messages.
    optional : tuple of str
        Canonical SI names that may be missing (``time_s`` when the time comes from the
        row index, `hdsim.io.import_options`).

    Returns
    -------
    dict of str to tuple of (int, float)
        Canonical SI name (``'angle_rad'``) -> (index in ``header``, the factor to SI: the
        size of the file's angle unit [rad], times a map's ``FACTOR*column`` factor).

    Raises
    ------
    InputError
        On a nameless or repeated header name, a map naming a column the file lacks, an
        unknown column, two columns giving the same quantity, or a missing column.
    """
    for i, name in enumerate(header):
        if not name:
            raise where.fail(f"{what} {i + 1} of the header has no name")
        if header.count(name) > 1:
            raise where.fail(f"{what} '{name}' appears twice in the header")
    # Rename the file's columns to canonical names by the map (canonical -> file).
    canonical_of: dict[str, str] = {}
    scale_of: dict[str, float] = {}  # canonical spelling -> factor of FACTOR*column
    if columns:
        check_map_keys(columns, where.path)
        for key, source in columns.items():
            file_name, scale_of[key] = split_factor(source) if source not in header else (source, 1.0)
            if file_name not in header:
                raise where.fail(f"column map reads '{key}' from {what} '{file_name}', which is "
                                 f"not in the file (it has {', '.join(header)})")
            canonical_of[file_name] = key
    allowed = canonical_names(test)
    needed = TESTS[test]
    optional = tuple(optional) + OPTIONAL_COLUMNS.get(test, ())
    found: dict[str, tuple[int, str]] = {}  # canonical SI name -> (index, canonical spelling)
    for i, name in enumerate(header):
        spelled = canonical_of.get(name, name)
        if spelled not in allowed:
            if columns and name not in canonical_of and spelled not in canonical_names():
                continue  # a column map names the columns to read; the rest are ignored
            raise where.fail(_unknown_column_text(name, spelled, test, what, bool(columns)))
        split = split_unit(spelled)
        si = f"{split[0]}_rad" if split else spelled
        if si in found:
            first, first_spelled = header[found[si][0]], found[si][1]

            def shown(n, sp):
                return f"'{n}'" if n == sp else f"'{n}' (mapped to {sp})"

            raise where.fail(f"{what}s {shown(first, first_spelled)} and {shown(name, spelled)} "
                             f"both give {si}; expected one of them")
        found[si] = (i, spelled)
    for si in needed:
        if si not in found and si not in optional:
            split = split_unit(si)
            alt = f" (or {split[0]}_deg/_arcmin/_arcsec/_rev)" if split else ""
            if si == "time_s":
                alt = " (a log without a clock: give its sample rate with sample_rate=HZ)"
            raise where.fail(f"missing {what} '{si}'{alt}; a {test} file needs "
                             f"{', '.join(needed)}")
    either = ONE_OF.get(test, ())
    if either and not any(si in found for si in either):
        raise where.fail(f"missing {what} {' or '.join(repr(si) for si in either)} (or _deg/_arcmin/_arcsec/_rev); "
                         f"a {test} file needs at least one of them")
    return {si: (i, (ANGLE_UNITS[split_unit(sp)[1]] if split_unit(sp) else 1.0) * scale_of.get(sp, 1.0))
            for si, (i, sp) in found.items()}


def complete_angles(data: dict[str, np.ndarray], test: str, ratio: float | None, where: Where) -> dict:
    """A running-torque record with both angles: the one the file lacks from the other and the ratio.

    Parameters
    ----------
    data : dict of str to numpy.ndarray
        Canonical SI columns as read.
    test : str
        The test; other tests are returned unchanged.
    ratio : float or None
        Transmission ratio N [-] (``output = wg / N``).
    where : Where
        Names the file in messages.

    Returns
    -------
    dict of str to numpy.ndarray
        ``data`` with ``wg_angle_rad`` and ``output_angle_rad`` both present.

    Raises
    ------
    InputError
        When one angle is missing and the ratio is not given.
    """
    if test not in ONE_OF:
        return data
    wg, out = data.get("wg_angle_rad"), data.get("output_angle_rad")
    if wg is not None and out is not None:
        return data
    if ratio is None:
        have = "wg_angle_rad" if wg is not None else "output_angle_rad"
        raise where.fail(f"only {have} is given and no '# ratio:' key; a {test} file with one angle needs "
                         "the transmission ratio to give the other (e.g. ratio=100)")
    data = dict(data)
    if wg is None:
        data["wg_angle_rad"] = out * ratio
    else:
        data["output_angle_rad"] = wg / ratio
    return data


def _unknown_column_text(name: str, spelled: str, test: str, what: str, mapped: bool) -> str:
    allowed = canonical_names(test)
    shown = f"'{name}'" if name == spelled else f"'{name}' (mapped to {spelled})"
    close = difflib.get_close_matches(spelled, allowed, n=2, cutoff=0.6)
    hint = f" (did you mean {' or '.join(close)}?)" if close else ""
    if spelled in canonical_names():
        hint = " (a column of the other test; is '# test:' right?)"
    if "," not in name and (";" in name or "\t" in name):
        hint = " (the separator must be a comma)"
    extra = "" if mapped else "; use a column map for another bench's names"
    return (f"unknown {what} {shown}{hint}; a {test} file has {', '.join(TESTS[test])} "
            f"(angles may end in _deg, _arcmin, _arcsec, _rev){extra}")


def check_values(data: dict[str, np.ndarray], where: Where, names: dict[str, str], from_file: bool = True) -> None:
    """Refuse anything but finite numbers, enough rows and strictly increasing time.

    Parameters
    ----------
    data : dict of str to numpy.ndarray
        Canonical SI name -> values in SI units; must hold ``time_s`` [s].
    where : Where
        Names the file and the row in messages.
    names : dict of str to str
        Canonical SI name -> how the message names the column (``"column 'pos'"``), so
        that a message names what the user sees.
    from_file : bool
        The columns were read from a file (`load_measurement`): the messages name its import
        options (``drop_nan=True``, ``concatenated=True``); else they are arrays
        (`make_measurement`), which the caller mends.

    Raises
    ------
    InputError
        On a NaN or infinite value, a one-row glitch (`glitch_rows`), fewer than
        `MIN_ROWS` rows, or a time that does not increase strictly.
    """
    n = data["time_s"].size
    drop, glitch, join = (("a log's failed reads are dropped with drop_nan=True",
                           "drop_nan=True drops them with the NaN rows", "concatenated=True joins them")
                          if from_file else ("drop those rows from the arrays", "drop them from the arrays",
                                             "join their clocks into one"))
    for si, values in data.items():
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            i = int(bad[0])
            raise where.fail(f"{where.row(i)}, {names[si]}: {float(values[i])!r} is not "
                             f"finite; expected a finite number ({bad.size} such rows; {drop})")
    if n < MIN_ROWS:
        raise where.fail(f"{n} data rows; expected at least {MIN_ROWS}")
    for si, rows in glitch_rows(data).items():
        i, values = int(rows[0]), data[si]
        raise where.fail(f"{where.row(i)}, {names[si]}: {float(values[i])!r} jumps away from both neighbours "
                         f"({float(values[i - 1]):.6g}, {float(values[i + 1]):.6g}) and back: a glitch, a failed "
                         f"read? ({rows.size} such rows; {glitch})")
    t = data["time_s"]
    bad = np.flatnonzero(~(np.diff(t) > 0))
    if bad.size:
        i = int(bad[0]) + 1
        raise where.fail(f"{where.row(i)}, {names['time_s']}: {float(t[i])!r} after "
                         f"{float(t[i - 1])!r}; expected time to increase strictly (several runs whose clock "
                         f"restarts? {join})")
