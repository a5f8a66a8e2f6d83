"""HDF5 results: time series, metrics, the full parameter set and provenance.

Layout of a result file (one run, or a batch of ``M`` runs)::

    /                attrs: hdsim_version, unit, scenario, setup, created
    /t               [s]
    /states/NAME     (M, nt)
    /signals/NAME    (M, nt)      torque_Nm, twist_rad, ...
    /metrics/NAME    (M,)         in the units their names carry
    /params/NAME     (M,) or ()   dotted parameter names, SI
    /effects         attrs: family -> effect id
    /scenario        attrs: toml (the scenario table as TOML text)
    /solver          attrs: method, rtol, nfev, ...

Written atomically (temporary file, then rename).
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import tomli_w

from hdsim import __version__
from hdsim.io.atomic import atomic_path
from hdsim.errors import InputError
from hdsim.simulation.solver import SimulationResult


@dataclass
class StoredRun:
    """What `read_result` returns: the result plus its metrics and provenance."""

    result: SimulationResult
    metrics: dict[str, np.ndarray]
    params: dict[str, np.ndarray]
    effects: dict[str, str]
    scenario_toml: str
    attrs: dict


def write_result(path, run) -> Path:
    """Write a `hdsim.scenarios.run.Run` to ``path`` atomically; returns the path."""
    path = Path(path)
    result = run.result
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
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
            f.create_group("scenario").attrs["toml"] = tomli_w.dumps(run.scenario.data)
            f.create_group("solver").attrs.update({k: v for k, v in result.solver.items()})
    return path


def read_result(path) -> StoredRun:
    """Read a file written by `write_result`."""
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
            result = SimulationResult(t=f["t"][()], states=states, signals=signals, setup=str(attrs["setup"]),
                                      solver=dict(f["solver"].attrs),
                                      metadata={k: attrs[k] for k in ("unit", "scenario", "hdsim_version")})
            return StoredRun(result, metrics, params, dict(f["effects"].attrs),
                             str(f["scenario"].attrs["toml"]), attrs)
        except KeyError as exc:
            raise InputError(f"{path}: not an hdsim result file (missing {exc})") from None
