"""Scenarios: TOML data describing a bench test, and the pure profile they imply.

A locked-wave-generator scenario (stiffness and lost-motion tests) is::

    name = "lost_motion"
    description = "..."
    setup = "locked_wave_generator"
    metrics = ["lost_motion"]

    [load]            # torque on the output, in fractions of the rated torque T_N
    amplitude = 0.04  # peak |T| / T_N
    cycles = 2        # levels: 0, +A, -A, (+A, -A) x (cycles-1), 0
    rate = 0.04       # mean loading rate [T_N per second]

    [output]
    samples_per_segment = 100

Any value can be overridden with ``--set scenario.load.rate=0.1``. The tables each
bench adds, and the keys it requires, come from its `hdsim.scenarios.setups.Setup`
(`hdsim.scenarios.registry`). A scenario is named by a file path or by the name of a
built-in scenario file (``lost_motion``, ``stiffness``, …, `builtin_scenario_names`).
"""

from __future__ import annotations

import copy
import os
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.scenarios.registry import SETUPS, get_setup
from hdsim.simulation.profiles import cosine_ramps, segment_times

_COMMON = {
    "name": str, "description": str, "setup": str, "metrics": list,
    "output": {"samples_per_segment": int},
    "solver": {"method": str, "rtol": float, "atol_scale": float, "max_step": float},
}



def schema_for(setup: str) -> dict:
    """The full schema of a scenario of set-up ``setup``: the common tables and the bench's own."""
    return {**_COMMON, **(SETUPS[setup].schema if setup in SETUPS else {})}


@dataclass(frozen=True)
class Scenario:
    """A validated scenario; ``data`` is the TOML table (kept for provenance)."""

    data: dict
    source: str = "<dict>"

    def __post_init__(self):
        # validation coerces values in place: work on our own copy, never the caller's dict
        object.__setattr__(self, "data", copy.deepcopy(self.data))
        if "setup" not in self.data and {"ratio", "rated_torque_Nm", "format"} & set(self.data):
            # a drive or fit file given where a scenario goes: "unknown key 'ratio'; did you mean
            # description?" had pointed the wrong way
            raise InputError(f"{self.source}: a drive or fit file, not a scenario: give it as the unit "
                             "(--unit FILE on the command line, the drive in Python)")
        if not isinstance(self.data.get("name"), str):
            raise InputError(f"{self.source}: missing 'name'")
        _check_name(self.data["name"], self.source)
        if not isinstance(self.setup, str):  # checked before the look-up, which needs a name
            raise InputError(f"{self.source}: setup must be str, got {self.setup!r}")
        setup = get_setup(self.setup, f"setup in {self.source}")
        _validate(self.data, schema_for(self.setup), self.source, "")
        if not all(isinstance(name, str) for name in self.metrics):  # names, looked up by the runners
            raise InputError(f"{self.source}: metrics must be a list of names, got {self.data['metrics']!r}")
        for table, keys in setup.required.items():
            for key in keys:
                if key not in self.data.get(table, {}):
                    raise InputError(f"{self.source}: missing {table}.{key}")
        if setup.check is not None:
            setup.check(self.data, self.source)

    @property
    def name(self) -> str:
        """The scenario's name (the stem of its result files)."""
        return self.data["name"]

    @property
    def setup(self) -> str:
        """The bench set-up (default ``locked_wave_generator``)."""
        return self.data.get("setup", "locked_wave_generator")

    @property
    def metrics(self) -> list[str]:
        """The metric groups asked for."""
        return list(self.data.get("metrics", []))

    @property
    def samples_per_segment(self) -> int:
        """Output samples per ramp of a locked-WG cycle (default 100)."""
        return int(self.data.get("output", {}).get("samples_per_segment", 100))

    def levels(self) -> np.ndarray:
        """Torque waypoints as fractions of T_N: 0, +A, −A, …, 0."""
        load = self.data["load"]
        amplitude = load["amplitude"]
        return np.array([0.0] + [amplitude, -amplitude] * load["cycles"] + [0.0])

    def times(self) -> np.ndarray:
        """Waypoint times [s] of the torque cycle (`levels` at the mean ``load.rate``)."""
        return segment_times(self.levels(), self.data["load"]["rate"])

    def torque_profile(self, rated_torque):
        """Applied output torque [N·m] as a function of time; per sample if T_N is an array."""
        shape = cosine_ramps(self.times(), self.levels())
        scale = np.asarray(rated_torque, dtype=float)
        return lambda t: shape(t) * scale

    def sample_times(self, samples_per_segment: int | None = None) -> np.ndarray:
        """Output times: ``samples_per_segment`` per ramp, waypoints included exactly."""
        n = samples_per_segment or self.samples_per_segment
        times = self.times()
        parts = [np.linspace(a, b, n, endpoint=False) for a, b in zip(times[:-1], times[1:])]
        return np.concatenate(parts + [times[-1:]])

    def with_updates(self, updates: dict) -> "Scenario":
        """A new scenario with ``{"load.rate": 0.1, ...}`` applied (dotted keys)."""
        data = copy.deepcopy(self.data)
        full = schema_for(self.setup)
        for key, value in updates.items():
            *path, leaf = key.split(".")
            table = data
            schema = full
            for part in path:
                if part not in schema or not isinstance(schema[part], dict):
                    raise unknown_name("scenario key", key, _flat_keys(full))
                schema = schema[part]
                table = table.setdefault(part, {})
            if leaf not in schema or isinstance(schema[leaf], dict):
                raise unknown_name("scenario key", key, _flat_keys(full))
            table[leaf] = _coerce(value, schema[leaf], key, self.source)
        return Scenario(data, self.source)


#: characters a scenario name cannot hold: it is the stem of the result files, written in
#: the output folder, so a path separator would put them elsewhere (and NUL no system takes)
_NAME_FORBIDDEN = ("/", "\\", "\0")


def _check_name(name: str, source: str) -> None:
    """InputError unless ``name`` can be the stem of a file inside the output folder: not
    empty, no path separator, not starting with '.' (a hidden file, or '..' a way out)."""
    if not name.strip():
        raise InputError(f"{source}: name is empty; give the scenario a name (the stem of its result files)")
    if any(c in name for c in _NAME_FORBIDDEN) or name.startswith("."):
        raise InputError(f"{source}: name {name!r} cannot be a file name in the output folder: "
                         "use letters, digits, '-' and '_', with no '/' or '\\' and no leading '.'")


def _flat_keys(schema, prefix=""):
    for key, value in schema.items():
        if isinstance(value, dict):
            yield from _flat_keys(value, f"{prefix}{key}.")
        else:
            yield f"{prefix}{key}"


def _coerce(value, kind, key, source):
    if kind is float and isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    if kind is int and isinstance(value, int) and not isinstance(value, bool):
        return value
    if kind is float and isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            pass
    if kind is int and isinstance(value, str):
        try:  # int() itself decides: '--5' and '²' pass isdigit() tests but are no integers
            return int(value)
        except ValueError:
            pass
    if kind in (str, list) and isinstance(value, kind):
        return value
    if kind is list and isinstance(value, str):  # --set input.speeds_rpm=[500,2000]: a TOML array
        import tomllib

        try:
            parsed = tomllib.loads(f"v = {value}")["v"]
        except (tomllib.TOMLDecodeError, ValueError):
            parsed = None
        if isinstance(parsed, list):
            return parsed
    raise InputError(f"{source}: {key} must be {kind.__name__}, got {value!r}")


def _validate(table, schema, source, prefix):
    for key, value in table.items():
        name = prefix + key
        if key not in schema:
            raise unknown_name(f"key in {source}", name, [prefix + k for k in schema])
        if isinstance(schema[key], dict):
            if not isinstance(value, dict):
                raise InputError(f"{source}: [{name}] must be a table")
            _validate(value, schema[key], source, name + ".")
        else:
            table[key] = _coerce(value, schema[key], name, source)


def read_toml(path, kind: str = "TOML") -> dict:
    """Read a TOML file into a dict.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    kind : str
        What the file is, for the messages (``"scenario"``).

    Raises
    ------
    InputError
        One line naming the file on any problem (missing, a folder, not TOML).
    """
    path = Path(path)
    try:
        return tomllib.loads(path.read_text(encoding="utf-8-sig"))  # a Windows editor's BOM is no statement
    except FileNotFoundError:
        raise InputError(f"{path}: {kind} file not found") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, expected a {kind} .toml file") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: not valid TOML: {exc}") from None
    except (OSError, ValueError) as exc:  # no permission; a name the system refuses (too long, a NUL byte)
        raise InputError(f"{str(path)!r}: cannot read the {kind} file "
                         f"({getattr(exc, 'strerror', None) or exc})") from None


def load_scenario(scenario) -> Scenario:
    """A validated scenario from a file, a built-in name or a `Scenario`.

    Parameters
    ----------
    scenario : str, os.PathLike or Scenario
        A scenario TOML file; or, where no such file exists, the name of a built-in
        scenario (``"lost_motion"``, see `builtin_scenario_names`), found from any
        working directory; a `Scenario` is returned as it is.

    Returns
    -------
    Scenario
        Its ``source`` is the file read.

    Raises
    ------
    InputError
        One line on any problem: a file that is neither found nor a built-in name (the
        message lists the built-in scenarios), invalid TOML, an unknown key or set-up,
        a value of the wrong type or out of range.
    """
    if isinstance(scenario, Scenario):
        return scenario
    if not isinstance(scenario, (str, os.PathLike)):
        raise InputError(f"a scenario is a Scenario, a built-in scenario name or a scenario file's path, "
                         f"got {type(scenario).__name__}")
    path = Path(scenario)
    try:
        is_file, exists = path.is_file(), path.exists()
    except OSError:  # a name the system refuses (too long): read_toml says so in one line
        is_file = exists = True
    if not is_file:
        names = builtin_scenario_names()
        if str(scenario) in names:
            path = builtin_scenario_path(str(scenario))
        elif not exists:
            raise InputError(f"{path}: scenario file not found, nor a built-in scenario "
                             f"({', '.join(names)})")
    return Scenario(read_toml(path, "scenario"), str(path))


def builtin_scenario_path(name: str) -> Path:
    """The scenario file ``NAME.toml`` shipped inside the package (``hdsim/data/scenarios``).

    The checkout's ``scenarios/`` folder holds the same files for reading and copying.
    """
    folder = Path(str(resources.files("hdsim").joinpath("data", "scenarios")))
    candidate = folder / f"{name}.toml"
    if candidate.is_file():
        return candidate
    raise unknown_name("built-in scenario", name, builtin_scenario_names())


def builtin_scenario_names() -> list[str]:
    """Names of the scenario files shipped inside the package."""
    folder = Path(str(resources.files("hdsim").joinpath("data", "scenarios")))
    return sorted(p.stem for p in folder.glob("*.toml"))
