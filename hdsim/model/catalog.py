"""Built-in units and drive files, by name or path: `load_unit`.

A name gives a built-in unit, built from its catalog figures and cached; a path gives
the drive its drive file describes (`hdsim.model.drive_file`). Both are assembled by the
one recipe, `hdsim.model.datasheet.assemble_unit`, which also holds the catalog table
(`unit_names`, `catalog_entry`, `default_unit`) and the calibration. This module sits
above both, so the dependency runs one way: catalog → drive_file → datasheet.
"""

from __future__ import annotations

import functools
import os

from hdsim.errors import InputError
from hdsim.model.datasheet import _data, assemble_unit, catalog_entry, default_unit, unit_names
from hdsim.model.drive import HarmonicDrive
from hdsim.model.drive_file import load_drive_file

__all__ = ["load_unit", "is_drive_file", "as_drive"]


@functools.cache
def _build(name: str) -> HarmonicDrive:
    data = _data()
    entry = catalog_entry(name)
    fxd = data["effects"]
    return assemble_unit(
        name, entry["size"], entry, accuracy_arcmin=data["kinematic_error"]["accuracy_arcmin"][name],
        backlash_arcmin=fxd["backlash_arcmin"], slip_arcmin=fxd["slip_arcmin"],
        provenance={"catalog": entry, "geometry": "assumed proportions, hdsim/data/units.toml"})


def is_drive_file(name_or_path) -> bool:
    """Whether `load_unit` reads ``name_or_path`` as a drive file rather than a unit name.

    Parameters
    ----------
    name_or_path : str, os.PathLike or None
        What was given as the unit.

    Returns
    -------
    bool
        True for a path object (`os.PathLike`), and for a string that is not a built-in unit name
        and ends in ``.toml`` or holds a path separator.
    """
    if isinstance(name_or_path, os.PathLike):
        return True
    if not isinstance(name_or_path, str) or name_or_path in unit_names():
        return False
    return name_or_path.lower().endswith(".toml") or any(sep in name_or_path for sep in "/\\")


def load_unit(name_or_path: str | os.PathLike | None = None) -> HarmonicDrive:
    """A built-in unit, or any drive from its drive file, with its default effects.

    Parameters
    ----------
    name_or_path : str or os.PathLike, optional
        A built-in unit name (`unit_names`; default `default_unit`, CSG-25-100), or the
        path of a drive file: a TOML file with the figures of a datasheet
        (`hdsim.model.drive_file`; a path object, or a string ending in ``.toml`` or
        holding a path separator).

    Returns
    -------
    HarmonicDrive
        The calibrated model. A built-in unit is cached (the same object for the same
        name); so is a drive file until it changes (its modification time or size), so
        the several calls of one command read and calibrate it once.

    Raises
    ------
    InputError
        On an unknown name (with the closest known ones), or a drive file that is
        missing or refused (one line naming the file and the key).
    """
    if is_drive_file(name_or_path):
        try:
            stat = os.stat(name_or_path)
        except (OSError, ValueError):  # missing or unreadable: the reader says so in one line
            return load_drive_file(os.fspath(name_or_path))
        return _cached_drive_file(os.fspath(name_or_path), os.path.realpath(name_or_path),
                                  stat.st_mtime_ns, stat.st_size)
    if name_or_path is not None and not isinstance(name_or_path, str):
        raise InputError(f"a unit is a built-in name or a drive file path, got {type(name_or_path).__name__}")
    return _build(name_or_path or default_unit())


@functools.lru_cache(maxsize=32)
def _cached_drive_file(path: str, real_path: str, mtime_ns: int, size: int) -> HarmonicDrive:
    """`load_drive_file`, once per file version (the key holds its real path, time and size)."""
    return load_drive_file(path)


def as_drive(drive) -> HarmonicDrive:
    """The drive a caller means: a `HarmonicDrive` as it is, a built-in unit name or a drive
    file's path through `load_unit`.

    Parameters
    ----------
    drive : HarmonicDrive, str or os.PathLike
        A model object (built-in, changed with ``with_updates``, fitted), the name of a
        built-in unit or the path of a drive file.

    Returns
    -------
    HarmonicDrive

    Raises
    ------
    InputError
        On an unknown unit name, a refused drive file, or an object that is none of these.
    """
    if isinstance(drive, HarmonicDrive):
        return drive
    if isinstance(drive, (str, os.PathLike)):
        return load_unit(drive)
    raise InputError(f"a drive is a HarmonicDrive, a built-in unit name or a drive file's path, "
                     f"got {type(drive).__name__}")
