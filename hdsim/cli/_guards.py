"""Checks a verb makes before it writes anything: where the results go, and that they are numbers.

Every check raises `hdsim.errors.InputError` (or `SolverError` for a run that gave no
finite value) with one line naming the path or option and what to do, so that bad input is
refused with exit status 2 *before* the work, and nothing is left half written.
"""

from __future__ import annotations

import argparse

import math
import os
from pathlib import Path

from hdsim.atomic import check_writable_folder, is_special_file
from hdsim.errors import InputError, SolverError
from hdsim.io.report_files import REPORT_PAGES


def same_file(a, b) -> bool:
    """Whether paths ``a`` and ``b`` name one file (a link or ``./x`` included); a path that
    does not exist yet is compared by its resolved name."""
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet): the names decide
        return Path(a).resolve() == Path(b).resolve()


def refuse_overwriting_data(path, data, option: str) -> None:
    """InputError if writing ``path`` (given as ``option``) would replace the measurement file ``data``."""
    if data is not None and same_file(path, data):
        raise InputError(f"{option} would write {path} over the data file {data}, replacing the "
                         f"measurement; give another path")


def refuse_special_file(path: Path, option: str) -> None:
    """InputError when ``path`` is a device, a pipe or a socket (`hdsim.atomic.is_special_file`)."""
    if is_special_file(path):
        raise InputError(f"{option}: {path} is not a regular file (a device, pipe or socket), and a result "
                         "replaces its file when written; give a file name (to keep nothing, leave the option out)")


def path_argument(text: str) -> str:
    """An option's path as given, refused when empty: ``--out ''`` had written to the
    default place as if the option had not been given (argparse's ``type=``)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty path; give a file or folder name")
    return text


def check_output_file(path, option: str, data=None) -> Path:
    """Make sure a result file can be written at ``path`` before any work is done.

    ``path`` must not be a folder nor the data file ``data``, and its folder must be writable.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{option}: {path} is a folder; give a file name with {option} FILE")
    refuse_special_file(path, option)
    refuse_overwriting_data(path, data, option)
    check_writable_folder(path.parent)
    return path


def check_output_folder(folder, option: str, names=REPORT_PAGES, data=None) -> Path:
    """Make sure results can be written into ``folder`` before any work is done.

    ``folder`` must be (or become) a writable folder, and none of the files ``names`` written
    into it may be a folder or the data file ``data``: a later failure would leave half the
    results behind (a report's figures without its page, a run's file without its figures).
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{option} {folder} is a file, not a folder; give a folder (it is created if missing)")
    check_writable_folder(folder)
    for name in names:
        path = folder / name
        if path.is_dir():
            raise InputError(f"{option} {folder}: {path} is a folder, so the results cannot be written "
                             f"there; remove it or give another folder")
        refuse_special_file(path, f"{option} {folder}")
        refuse_overwriting_data(path, data, f"{option} {folder}")
    return folder


def nonfinite_names(values, prefix: str = "") -> list[str]:
    """The dotted names of every float in ``values`` (nested dicts and lists) that is NaN or
    infinite; None and non-numbers are not values and pass."""
    if hasattr(values, "tolist"):  # a numpy array or scalar: as Python lists and floats
        values = values.tolist()
    if isinstance(values, dict):
        return [name for key, value in values.items()
                for name in nonfinite_names(value, f"{prefix}{key}.")]
    if isinstance(values, (list, tuple)):
        return [name for i, value in enumerate(values) for name in nonfinite_names(value, f"{prefix}{i}.")]
    try:
        number = float(values)
    except (TypeError, ValueError):
        return []
    if isinstance(values, (str, bytes, bool)) or math.isfinite(number):
        return []
    return [prefix.rstrip(".")]


def require_finite(values, what: str, hint: str) -> None:
    """SolverError naming every value of ``values`` that is not finite, before anything is written.

    Strict JSON cannot carry NaN or infinity, and a result file holding them would mislead:
    a run (or fit) that produces them has failed, and the user's values are what to change.
    """
    bad = nonfinite_names(values)
    if bad:
        shown = ", ".join(bad[:5]) + (f" and {len(bad) - 5} more" if len(bad) > 5 else "")
        raise SolverError(f"{what} gave no finite value for {shown}; {hint}; nothing was written")
