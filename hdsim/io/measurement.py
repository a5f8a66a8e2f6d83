"""Measurement files: read, check and write bench data (CSV or HDF5).

The file format (docs/measurements.md)::

    # test: stiffness            <- stiffness | kinematic_error | running_torque | breakaway (required)
    # ratio: 100                 <- transmission ratio; required for kinematic_error
    # rated_torque_Nm: 67        <- optional
    time_s,torque_Nm,angle_rad
    0.0,0.0,0.0
    ...

| test | columns (any order) |
|---|---|
| ``stiffness`` | ``time_s``, ``torque_Nm``, ``angle_rad`` |
| ``kinematic_error`` | ``time_s``, ``wg_angle_rad``, ``output_angle_rad``, ``torque_Nm`` |
| ``running_torque`` | ``time_s``, ``wg_angle_rad`` and/or ``output_angle_rad``, ``torque_Nm``; optional ``temperature_C`` |
| ``breakaway`` | as ``running_torque`` |

A running-torque file (a friction sweep) or a breakaway file (the torque raised from rest
until the drive turns) names the shaft its torque is referred to with
``# torque_side: input`` (default) or ``output``; with ``# ratio:`` one angle gives the other.

Angle columns may end in ``_deg``, ``_arcmin``, ``_arcsec`` or ``_rev`` instead of
``_rad``; they are converted to radians on reading. Logs written by other bench
software are read with import options (`hdsim.io.import_options`). Files from another bench are read with a
column map (canonical name -> name in the file). The same data may come as HDF5: one
1-D dataset per column at the file's root, the ``#`` keys as file attributes.

Every problem is refused with one `hdsim.errors.InputError` line that names
the file, the line (CSV, 1-based, counting ``#`` lines and the header) or the row and
column (HDF5), and what was expected. Reading never writes anything.

Sign convention of the kinematic-error test: ``torque_Nm`` is the torque the load
applies to the output, positive in the same sense as in the stiffness test, so a
positive torque twists the output positively relative to ``wg_angle_rad / ratio``.

This module holds the data class and the public functions; the readers are in
`hdsim.io.measurement_readers` and the checks they share in
`hdsim.io.measurement_checks`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hdsim.errors import InputError
from hdsim.atomic import atomic_path, hdf5_atomic
from hdsim.io.import_options import RowReport, checked_options
from hdsim.io.measurement_checks import (
    RATED_KEYS,
    ONE_OF,
    OPTIONAL_COLUMNS,
    TESTS,
    complete_angles,
    Where,
    check_values,
    interpret_meta,
    parse_column_map,
    quote_cell,
)
from hdsim.io.measurement_readers import HDF5_SUFFIXES, read_measurement_file
from hdsim.units import ANGLE_UNITS

__all__ = [
    "Measurement",
    "measurement_from_run",
    "TESTS",
    "ANGLE_UNITS",
    "load_measurement",
    "save_measurement",
    "parse_column_map",
    "make_measurement",
]


@dataclass(frozen=True, eq=False)
class Measurement:
    """One bench measurement in SI units.

    Attributes
    ----------
    test : str
        ``'stiffness'``, ``'kinematic_error'`` or ``'running_torque'``.
    time : numpy.ndarray
        Sample times, strictly increasing [s].
    torque : numpy.ndarray
        Stiffness test: torque applied to the output [N·m]. Kinematic-error test: load
        torque measured at the output [N·m]. Running-torque test: the torque needed to
        turn the drive, on the shaft `torque_side` names [N·m].
    angle : numpy.ndarray
        Stiffness test: output twist; kinematic-error and running-torque tests: output
        angle [rad]. Any constant zero offset of the encoder is kept as measured.
    wg_angle : numpy.ndarray or None
        Wave-generator angle [rad] (kinematic-error and running-torque tests).
    ratio : float or None
        Transmission ratio [-]; negative when the output turns the other way.
    rated_torque : float or None
        Rated torque T_N [N·m], if the file gives it.
    meta : dict of str to str
        Every ``#`` key of the file (HDF5: every attribute) as text.
    source : str
        Path the data were read from (or ``'<arrays>'``).
    rows : RowReport
        What the import options did to the rows (dropped, windowed, joined runs).
    temperature : numpy.ndarray or None
        Temperature [°C], if a running-torque file logs it.
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
    rows: RowReport = RowReport()
    temperature: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.time.size)

    def __repr__(self) -> str:
        extra = f", ratio={self.ratio!r}" if self.ratio is not None else ""
        return f"Measurement(test={self.test!r}, rows={len(self)}{extra}, source={self.source!r})"

    @property
    def wg_driven(self) -> bool:
        """True when the wave generator turned and its angle was logged (a kinematic-error or
        running-torque record); False for a locked record."""
        return self.wg_angle is not None

    @property
    def output_angle(self) -> np.ndarray | None:
        """Output angle [rad] of a kinematic-error or running-torque test; None for a stiffness test."""
        return None if self.test == "stiffness" else self.angle

    @property
    def torque_side(self) -> str:
        """``'input'`` or ``'output'``: the shaft a running-torque record's torque is referred to."""
        return self.meta.get("torque_side", "input").strip()

    @property
    def kinematic_error(self) -> np.ndarray | None:
        """``output_angle - wg_angle / ratio`` [rad]; None for a stiffness test."""
        if self.test != "kinematic_error":
            return None
        return self.angle - self.wg_angle / self.ratio

    def columns(self) -> dict[str, np.ndarray]:
        """The data as canonical SI columns in the order of `TESTS`, e.g. ``{'time_s': ...}``."""
        by_name = {
            "time_s": self.time,
            "torque_Nm": self.torque,
            "angle_rad": self.angle,
            "output_angle_rad": self.angle,
            "wg_angle_rad": self.wg_angle,
            "temperature_C": self.temperature,
        }
        return {name: by_name[name] for name in TESTS[self.test] if by_name[name] is not None}


def _build(data: dict[str, np.ndarray], test: str, ratio, rated, meta, source,
           rows: RowReport = RowReport()) -> Measurement:
    def frozen(values):
        values = np.array(values, dtype=np.float64)  # a private copy, then read-only
        values.flags.writeable = False
        return values

    driven = "angle_rad" not in TESTS[test]  # a driven test has the output and WG angles instead
    return Measurement(
        test=test,
        time=frozen(data["time_s"]),
        torque=frozen(data["torque_Nm"]),
        angle=frozen(data["output_angle_rad" if driven else "angle_rad"]),
        wg_angle=frozen(data["wg_angle_rad"]) if driven else None,
        temperature=frozen(data["temperature_C"]) if "temperature_C" in data else None,
        ratio=ratio,
        rated_torque=rated,
        meta=dict(meta),
        source=source,
        rows=rows,
    )


def load_measurement(path: str | os.PathLike, columns: dict[str, str] | None = None,
                     **import_options) -> Measurement:
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
        needs); without one, every column must be a canonical column. A name may be
        ``FACTOR*name`` (``"torque_Nm": "5.11*iq_A"``: torque from motor current).
    **import_options
        What the log does not say itself (`hdsim.io.import_options.ImportOptions`):
        ``test``, ``ratio``, ``rated_torque``, ``meta`` (other ``#`` keys), ``drop_nan``,
        ``window`` (T0, T1) [s] (``None`` for an open side), ``sample_rate`` [Hz] (no time
        column), ``concatenated``. An unknown name or a bad value is an `InputError`
        naming the keyword.

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
    options = checked_options(import_options)
    parsed = read_measurement_file(path, columns, options)
    return _build(parsed.data, parsed.test, parsed.ratio, parsed.rated_torque, parsed.meta,
                  str(path), parsed.rows)


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
    temperature=None,
) -> Measurement:
    """Build a checked `Measurement` from arrays in SI units.

    Parameters
    ----------
    test : str
        ``'stiffness'``, ``'kinematic_error'`` or ``'running_torque'``.
    time : array_like
        Sample times, strictly increasing [s].
    torque : array_like
        Torque [N·m].
    angle : array_like or None
        Stiffness test: twist; kinematic-error and running-torque tests: output angle
        [rad] (a running-torque test may give only ``wg_angle`` and the ratio).
    wg_angle : array_like, optional
        Wave-generator angle [rad]; required for ``'kinematic_error'``.
    ratio : float, optional
        Transmission ratio [-]; required for ``'kinematic_error'``, and for a
        running-torque test with one angle.
    rated_torque : float, optional
        Rated torque [N·m].
    meta : dict, optional
        Extra ``#`` keys (values kept as text).
    source : str
        A label for messages.
    temperature : array_like, optional
        Temperature [°C] (running-torque test).

    Returns
    -------
    Measurement
        The data as read-only float64 copies.

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
    where = Where(source)
    test, ratio, rated = interpret_meta(text_meta, where)
    given = {"time_s": time, "torque_Nm": torque, "angle_rad": angle,
             "output_angle_rad": angle, "wg_angle_rad": wg_angle, "temperature_C": temperature}
    optional = OPTIONAL_COLUMNS.get(test, ())
    if test in ONE_OF and angle is None and wg_angle is None:
        raise where.fail(f"a {test} measurement needs wg_angle or angle (the output angle)")
    data = {}
    for name in TESTS[test]:
        if given[name] is None and name in optional:
            continue
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
    check_values(data, where, {si: f"column '{si}'" for si in data}, from_file=False)
    data = complete_angles(data, test, ratio, where)
    return _build(data, test, ratio, rated, text_meta, source)


def _meta_for_writing(meas: Measurement) -> dict[str, str]:
    """The ``#`` keys to write: the fields first (authoritative), then the rest of meta."""
    meta = {"test": meas.test}
    if meas.ratio is not None:
        meta["ratio"] = repr(float(meas.ratio))
    if meas.rated_torque is not None:
        meta["rated_torque_Nm"] = repr(float(meas.rated_torque))
    for key, value in meas.meta.items():
        if key in meta or key in RATED_KEYS:
            continue
        meta[str(key)] = str(value)
    for key, value in meta.items():
        bad = not key.strip() or ":" in key or any(c in key + value for c in "\r\n")
        if bad:
            raise InputError(f"cannot write '#' key {quote_cell(key)}: keys need no ':' and "
                             "neither key nor value may hold a line break")
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

    Raises
    ------
    InputError
        On a ``#`` key that is empty or holds ``:``, or a key or value with a line break.
    """
    path = Path(path)
    meta = _meta_for_writing(meas)
    cols = meas.columns()
    if path.suffix.lower() in HDF5_SUFFIXES:
        with hdf5_atomic(path) as handle:
            for key, value in meta.items():
                handle.attrs[key] = value
            for name, values in cols.items():
                handle.create_dataset(name, data=np.asarray(values, dtype=np.float64))
        return path
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="\n") as out:
        for key, value in meta.items():
            out.write(f"# {key}: {value}\n")
        out.write(",".join(cols) + "\n")
        # Python's float repr is the shortest exact round-trip text.
        table = np.column_stack(list(cols.values())).tolist()
        out.write("".join(",".join(map(repr, row)) + "\n" for row in table))
    return path


def measurement_from_run(run, sample: int = 0, noise_rad: float = 0.0, seed: int = 0) -> Measurement:
    """The run as a bench record, for closing the loop simulate → fit: a stiffness test of
    a locked bench (torque and twist), a kinematic-error test of a driven one (load torque,
    output and wave-generator angles).

    Parameters
    ----------
    run : hdsim.scenarios.run.Run
        A finished run (`hdsim.run_scenario`, `hdsim.read_run`).
    sample : int
        Which model of a batch.
    noise_rad : float
        Rms of white noise added to the measured angle [rad]: an encoder's. A record
        without noise is the evaluator's own error, which the diagnosis says it cannot
        judge below (docs/measurements.md).
    seed : int
        Seed of the noise.

    Returns
    -------
    hdsim.io.measurement.Measurement

    Raises
    ------
    InputError
        A bench that gives no such record.
    """

    def signal(name):
        return np.asarray(run.result.signals[name], dtype=float).reshape(-1, np.size(run.result.t))[sample]

    t = np.asarray(run.result.t, dtype=float)
    noise = noise_rad * np.random.default_rng(seed).standard_normal(t.size) if noise_rad else 0.0
    params = run.model.params()

    def parameter(name):  # the sample's value of a batch's parameter (one value serves every sample)
        return float(np.ravel(params[name])[sample % np.size(params[name])])

    rated = parameter("drive.rated_torque")
    if run.scenario.setup == "locked_wave_generator":
        return make_measurement("stiffness", t, signal("torque_Nm"), signal("twist_rad") + noise,
                                rated_torque=rated)
    if run.scenario.setup == "driven_wave_generator":
        ratio = parameter("drive.ratio")
        return make_measurement("kinematic_error", t, signal("load_torque_Nm"), signal("output_angle_rad") + noise,
                                wg_angle=signal("wg_angle_rad"), ratio=ratio, rated_torque=rated)
    raise InputError(f"a {run.scenario.setup} run gives no bench record")

