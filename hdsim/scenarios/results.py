"""The run file (HDF5): time series, metrics, the full parameter set and provenance.

Layout of a run file (one run, or a batch of ``M`` runs)::

    /                attrs: hdsim_version, unit, scenario, setup, created
    /t               [s]
    /states/NAME     (M, nt)
    /signals/NAME    (M, nt)      torque_Nm, twist_rad, ...
    /metrics/NAME    (M,)         in the units their names carry
    /params/NAME     (M,) or ()   dotted parameter names, SI
    /effects         attrs: family -> effect id
    /input_friction  attrs: ripple_orders, ripple_amplitudes, ripple_phases (the law's lists;
                     its scalar fields are in /params as input_friction.NAME)
    /scenario        attrs: toml (the scenario table as TOML text)
    /solver          attrs: method, rtol, nfev, ...
    /bench           attrs: json (a driven run's metric windows, input mode and profile)
    /drive_file      attrs: toml, path (only for a unit read from a drive file)

Written atomically (a temporary file, then a rename). `hdsim.scenarios.run.Run.save`
writes one and `hdsim.scenarios.run.read_run` reads it back into a `Run`; the model is
rebuilt from the built-in unit of that name, or from the drive file's table stored in
``/drive_file`` (`hdsim.model.drive_file`), with every stored parameter and effect
applied (docs/tutorial-first-simulation.md).
"""

from __future__ import annotations

import datetime as _dt
import json
import tomllib
from pathlib import Path

import h5py
import numpy as np
import tomli_w

from hdsim._version import __version__
from hdsim.atomic import hdf5_atomic
from hdsim.errors import InputError
from hdsim.model.catalog import load_unit
from hdsim.model.drive import HarmonicDrive
from hdsim.model.drive_file import drive_from_table, drive_table
from hdsim.model.effects import make_effect
from hdsim.scenarios.scenario import Scenario
from hdsim.simulation.solver import SimulationResult


def write_run_file(path, run) -> Path:
    """Write a run to an HDF5 run file atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target file (layout in the module description); replaced if it exists.
    run : hdsim.scenarios.run.Run
        A finished run (one model or a batch).

    Returns
    -------
    pathlib.Path
        The written file.
    """
    path = Path(path)
    result = run.result
    with hdf5_atomic(path) as f:
        f.attrs.update(hdsim_version=__version__, unit=run.model.name, scenario=run.scenario.name,
                       setup=result.setup,
                       created=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"))
        f.create_dataset("t", data=result.t).attrs["unit"] = "s"
        for group, table in (("states", result.states), ("signals", result.signals)):
            g = f.create_group(group)
            for name, values in table.items():
                g.create_dataset(name, data=np.asarray(values), compression="gzip", compression_opts=4)
        g = f.create_group("metrics")
        for name, values in run.metrics.items():
            g.create_dataset(name, data=np.asarray(values, dtype=float))
        g = f.create_group("params")
        for name, value in run.model.params().items():
            g.create_dataset(name, data=np.asarray(value, dtype=float))
        f.create_group("effects").attrs.update({s: e.id for s, e in run.model.effects().items()})
        f.create_group("input_friction").attrs.update(_ripple(run.model.input_friction))
        f.create_group("scenario").attrs["toml"] = tomli_w.dumps(run.scenario.data)
        f.create_group("solver").attrs.update({k: v for k, v in result.solver.items()})
        # what a bench says of its run (a driven run's metric windows, input mode, profile)
        bench = {k: result.metadata[k] for k in BENCH_METADATA if k in result.metadata}
        if bench:
            f.create_group("bench").attrs["json"] = json.dumps(bench)
        table = drive_table(run.model)
        if table:  # the unit is not a built-in one: keep what rebuilds it
            f.create_group("drive_file").attrs.update(toml=tomli_w.dumps(table),
                                                      path=str(run.model.provenance["drive_file"]["path"]))
    return path


#: the result metadata a bench adds to its run (`hdsim.scenarios.driven`), kept in the file
BENCH_METADATA = ("windows", "input_mode", "profile")


def read_run_file(path) -> tuple[HarmonicDrive, Scenario, SimulationResult, dict]:
    """Read a file written by `write_run_file`.

    Parameters
    ----------
    path : str or os.PathLike
        The run file.

    Returns
    -------
    tuple
        (model, scenario, result, metrics): the model rebuilt from the built-in unit
        (or the stored drive-file table) with the stored parameters and effects, the
        scenario (its ``source`` is the file), the result (times [s], states, signals,
        solver statistics; ``metadata`` holds the file's ``unit``, ``scenario``,
        ``hdsim_version``, ``created`` and ``evaluator``, the one that ran, and a driven
        run's ``windows``, ``input_mode`` and ``profile``) and the metrics ``{name: (M,)}``.

    Raises
    ------
    InputError
        If the file cannot be opened as HDF5, lacks a part of the layout, or names a
        unit or an effect that is not known.
    """
    path = Path(path)
    try:
        f = h5py.File(path, "r")
    except (OSError, FileNotFoundError) as exc:
        raise InputError(f"{path}: not a readable hdsim result ({exc})") from None
    with f:
        try:
            states = {k: v[()] for k, v in f["states"].items()}
            signals = {k: v[()] for k, v in f["signals"].items()}
            metrics = {k: v[()] for k, v in f["metrics"].items()}
            params = {k: v[()] for k, v in f["params"].items()}
            attrs = dict(f.attrs)
            solver = dict(f["solver"].attrs)
            metadata = {k: attrs[k] for k in ("unit", "scenario", "hdsim_version", "created") if k in attrs}
            # the solver's method names the evaluator that ran: not stored twice
            metadata["evaluator"] = "quasistatic" if solver.get("method") == "quasistatic" else "dynamic"
            if "bench" in f:
                metadata.update(json.loads(str(f["bench"].attrs["json"])))
            result = SimulationResult(t=f["t"][()], states=states, signals=signals, setup=str(attrs["setup"]),
                                      solver=solver, metadata=metadata)
            effects = {k: str(v) for k, v in f["effects"].attrs.items()}
            scenario_toml = str(f["scenario"].attrs["toml"])
            unit = str(attrs["unit"])
            ripple = dict(f["input_friction"].attrs) if "input_friction" in f else {}
            drive_file = None
            if "drive_file" in f:
                g = f["drive_file"]
                drive_file = (tomllib.loads(str(g.attrs["toml"])), str(g.attrs["path"]))
        except KeyError as exc:
            raise InputError(f"{path}: not an hdsim result file (missing {exc})") from None
    model = stored_model(unit, params, effects, drive_file)
    if ripple:  # files written before the drive carried its input friction have none
        model = model.with_input_friction(model.input_friction.with_updates(
            **{k: tuple(float(v) for v in np.atleast_1d(ripple[k])) for k in _RIPPLE_FIELDS if k in ripple}))
    scenario = Scenario(tomllib.loads(scenario_toml), str(path))
    return model, scenario, result, metrics


_RIPPLE_FIELDS = ("ripple_orders", "ripple_amplitudes", "ripple_phases", "position_orders", "position_amplitudes",
                  "position_phases")


def _ripple(law) -> dict:
    """The ripple lists of an input-friction law, as float arrays (HDF5 attributes)."""
    return {k: np.asarray(getattr(law, k), dtype=float) for k in _RIPPLE_FIELDS}


def stored_model(unit: str, params: dict, effects: dict, drive_file: tuple | None = None) -> HarmonicDrive:
    """A model from what a run file stores.

    Parameters
    ----------
    unit : str
        Name of a built-in unit (`hdsim.model.datasheet.unit_names`).
    params : dict
        Dotted parameter name → value (SI), scalars or arrays of shape (M,).
    effects : dict
        Slot → effect id.
    drive_file : tuple, optional
        ``(table, path)`` of the drive file the unit was read from: the unit is rebuilt
        from this table (`hdsim.model.drive_file.drive_from_table`), not from ``unit``.

    Returns
    -------
    HarmonicDrive
        The unit with each slot's effect built from its stored parameters
        (`hdsim.model.effects.make_effect`) and every other parameter applied.
    """
    values = {name: float(v) if np.ndim(v) == 0 else np.asarray(v, dtype=float) for name, v in params.items()}
    slots = {}
    for family, effect_id in effects.items():
        own = {name.partition(".")[2]: v for name, v in values.items() if name.partition(".")[0] == family}
        slots[family] = make_effect(family, effect_id, **own)
    rest = {name: v for name, v in values.items() if name.partition(".")[0] not in effects}
    base = load_unit(unit) if drive_file is None else drive_from_table(*drive_file)
    return base.with_effects(**slots).with_updates(rest)

