"""Measured input profiles of driven scenarios (``input.profile = "csv"``): the CSV reader.

The arrays it returns become a WG motion (`hdsim.simulation.motion.csv_motion`) and a
load (`hdsim.simulation.loads.csv_load`); docs/tutorial-kinematic-error.md shows a file.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from hdsim.errors import InputError
from hdsim.units import ANGLE_UNITS, rpm_to_rad_per_s

#: columns whose cells must be numbers (others are ignored, NaN if not numeric)
_WANTED = {"time_s", "torque_Nm", "wg_speed_rpm", "wg_speed_rad_per_s"} | {f"wg_angle_{u}" for u in ANGLE_UNITS}


def read_profile_csv(path) -> dict[str, np.ndarray]:
    """Read a measured input profile (CSV) into SI arrays.

    Columns: ``time_s`` plus ``wg_angle_<rad|deg|arcmin|arcsec>`` or ``wg_speed_rpm`` /
    ``wg_speed_rad_per_s``; optional ``torque_Nm`` (the load applied to the output, as in
    the kinematic-error measurement files of docs/measurements.md, which are accepted as
    they are). ``#`` lines are skipped; other columns are ignored.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    dict
        ``time`` [s], ``angle`` [rad] or ``speed`` [rad/s], and ``torque`` [N·m] if present.

    Raises
    ------
    InputError
        On a missing file or column, a cell that is not a number, fewer than 4 rows, a
        non-finite value or a time that does not increase; the message names the file
        and the line.
    """
    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except FileNotFoundError:
        raise InputError(f"{path}: profile file not found") from None
    except (UnicodeDecodeError, IsADirectoryError):
        raise InputError(f"{path}: not a text CSV file") from None
    except (OSError, ValueError) as exc:  # no permission; a name the system refuses (too long, a NUL byte)
        raise InputError(f"{str(path)!r}: cannot read the profile file "
                         f"({getattr(exc, 'strerror', None) or exc})") from None
    rows = [(n + 1, line) for n, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise InputError(f"{path}: no header row")
    header = [h.strip() for h in next(csv.reader([rows[0][1]]))]
    body = rows[1:]
    if len(body) < 4:
        raise InputError(f"{path}: a profile needs at least 4 rows, found {len(body)}")
    columns = {}
    for name in header:
        columns[name] = np.empty(len(body))
    for r, (lineno, line) in enumerate(body):
        cells = next(csv.reader([line]))
        if len(cells) != len(header):
            raise InputError(f"{path}: line {lineno}: expected {len(header)} cells, found {len(cells)}")
        for name, cell in zip(header, cells):
            try:
                columns[name][r] = float(cell)
            except ValueError:
                if name in _WANTED:
                    raise InputError(f"{path}: line {lineno}, column {name}: '{cell.strip()[:30]}' is not a "
                                     "number") from None
                columns[name][r] = np.nan
    if "time_s" not in columns:
        raise InputError(f"{path}: missing column time_s (columns: {', '.join(header)})")
    out = {"time": columns["time_s"]}
    for unit, factor in ANGLE_UNITS.items():
        if f"wg_angle_{unit}" in columns:
            out["angle"] = columns[f"wg_angle_{unit}"] * factor
            break
    else:
        if "wg_speed_rpm" in columns:
            out["speed"] = rpm_to_rad_per_s(columns["wg_speed_rpm"])
        elif "wg_speed_rad_per_s" in columns:
            out["speed"] = columns["wg_speed_rad_per_s"]
        else:
            raise InputError(f"{path}: missing the input column: wg_angle_rad (or _deg, _arcmin, _arcsec), "
                             "wg_speed_rpm or wg_speed_rad_per_s")
    if "torque_Nm" in columns:
        out["torque"] = columns["torque_Nm"]
    for name, values in out.items():
        if not np.all(np.isfinite(values)):
            raise InputError(f"{path}: column for {name} has a non-finite value at data row "
                             f"{int(np.flatnonzero(~np.isfinite(values))[0]) + 1}")
    if np.any(np.diff(out["time"]) <= 0.0):
        k = int(np.flatnonzero(np.diff(out["time"]) <= 0.0)[0])
        raise InputError(f"{path}: time_s is not strictly increasing at data row {k + 2}")
    return out
