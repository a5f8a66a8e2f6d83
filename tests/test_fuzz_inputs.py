"""Fuzzing every parser of user input: a result or `InputError`, never a traceback.

Property-based tests (hypothesis, derandomized so CI sees the same inputs every run)
feed generated malformed, and some valid, inputs to hdsim's input parsers. Each must
return a result or raise `hdsim.errors.InputError` with a non-empty message, which the
CLI prints as one line with exit status 2; any other exception is a bug (a traceback,
exit 1) and fails the test, and so does a RuntimeWarning (more lines on stderr).

| target | examples |
|---|---|
| measurement CSV (`load_measurement`): ``#`` keys, header, rows, column maps | 120 |
| measurement files of raw bytes or text (binary junk, BOM, empty) | 100 |
| measurement HDF5 files with random datasets and attributes | 60 |
| ``hdsim fit DATA --json`` on generated CSV (exit 0 or 2, one line on stderr) | 15 |
| scenario TOML (`load_scenario`, `solver_options`) from random tables of both set-ups and junk | 120 |
| scenario files of raw junk text | 70 |
| driven scenarios through `Scenario` and `bench_from_scenario` | 85 |
| the ``[input_friction]`` table of a driven scenario (`for_unit`) | 75 |
| fitted-model TOML (`load_fitted`) | 100 |
| file names (NUL byte, too long) for every file reader | 50 |
| unit names (`load_unit`) | 75 |
| ``--set`` (`parse_sets` + `apply_sets`) | 120 |
| ``--columns`` (`parse_column_map`, then the map read on a file) | 100 |
| sobol ``--params/--range/--bounds/--dist`` (`parse_range`, `parse_assignments`, `from_unit`) | 100 |
| `HarmonicDrive.with_updates` with random dicts | 100 |

1305 inputs in all (about a third of the first depth; the deep targets, 100 examples and
more, at two thirds of the second: every kind of input is still drawn), about 6 s on two
cores. ``HDSIM_FUZZ_SCALE=20`` runs 20 times as many, new ones each run (a deeper search
by hand). Below the properties, one regression test per bug the fuzzer found, minimal input.
"""

from __future__ import annotations

import json
import math
import os

import h5py
import numpy as np
import pytest
import tomli_w
from hypothesis import HealthCheck, event, given, settings, strategies as st

from hdsim.cli import main
from hdsim.cli._common import apply_sets, parse_sets
from hdsim.errors import InputError
from hdsim.identification.fit import load_fitted
from hdsim.io.measurement import load_measurement, parse_column_map
from hdsim.model import effects as fx
from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import unit_names
from hdsim.model.input_friction import for_unit
from hdsim.scenarios.driven import bench_from_scenario
from hdsim.scenarios.profile_csv import read_profile_csv
from hdsim.scenarios.run import solver_options
from hdsim.scenarios.scenario import Scenario, builtin_scenario_path, load_scenario, schema_for
from hdsim.sensitivity.models import from_unit
from hdsim.sensitivity.problem import parse_assignments, parse_range
from hdsim.units import ANGLE_UNITS


#: examples x this, new ones each run when not 1 (see the module doc)
_SCALE = float(os.environ.get("HDSIM_FUZZ_SCALE", "1"))


def _settings(n: int):
    return settings(max_examples=max(1, int(n * _SCALE)), deadline=None, derandomize=_SCALE == 1, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                           HealthCheck.data_too_large, HealthCheck.filter_too_much])


def _ok_or_input_error(fn, *args, **kwargs):
    """``fn(*args)``, or None on an `InputError` with a message (the CLI prints it as one line).
    Any other exception propagates and fails the test: it would be a traceback, exit 1."""
    try:
        return fn(*args, **kwargs)
    except InputError as exc:
        assert " ".join(str(exc).split()), f"{fn.__name__} raised an InputError without a message"
        return None


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory):
    """The generated files' folder, with a driven scenario's input profile and another bench's stiffness test."""
    folder = tmp_path_factory.mktemp("fuzz")
    (folder / "profile.csv").write_text("time_s,wg_angle_deg,torque_Nm\n" + "".join(
        f"{0.01 * i},{3.6 * i},{0.1 * i}\n" for i in range(20)))
    (folder / "other.csv").write_text("# test: stiffness\nt,T_out,pos,iq_A\n" + "".join(
        f"{0.1 * i},{i - 5.0},{1e-3 * (i - 5.0)},{0.2 * i}\n" for i in range(12)))
    return folder


# a warning is printed on stderr beside the one line of an error: none may be raised
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

UNIT = load_unit()
LOST_MOTION = load_scenario(builtin_scenario_path("lost_motion"))

_TEXT = st.text(st.characters(codec="utf-8"), max_size=12)
_SPECIAL = ["nan", "inf", "-inf", "NaN", "", " ", "1e999", "-0", "0x10", "1_000", "１２", "²", "--1",
            "+", ".", "e5", "1,5", "none", "None", "true", "0", "-1", "1e300", "5e-324"]
_NUMBER_TEXT = st.one_of(st.floats().map(repr), st.integers(-10**6, 10**6).map(str), st.sampled_from(_SPECIAL))
_NUMBER = st.one_of(st.floats(), st.integers(-10**20, 10**20), st.sampled_from([0, 0.0, -1.0, 1e300, -1e300]))
def _mostly(sane, junk, rare: int = 4):
    """``sane`` but one time in ``rare + 1`` ``junk``."""
    return st.integers(0, rare).flatmap(lambda i: junk if i == rare else sane)


_ANGLES = ("rad", "deg", "arcmin", "arcsec")
_COLUMNS = ["time_s", "torque_Nm", "temperature_C", "wg_angle_rev"] + [
    f"{base}_{u}" for base in ("angle", "wg_angle", "output_angle") for u in _ANGLES]


# --------------------------------------------------------------------------- 1. measurements


@st.composite
def measurement_csv(draw, mutate: bool = True) -> tuple[bytes, dict | None]:
    """A CSV measurement, valid but for mutations (``mutate``), and sometimes a column map."""
    rare = st.integers(0, 3).map(lambda i: i == 3) if mutate else st.just(False)  # one time in four
    test = draw(st.sampled_from(["stiffness", "kinematic_error", "running_torque"]) if not draw(rare) else
                st.sampled_from(["stiffness ", "Stiffness", "junk", "", None]))
    meta = [] if test is None else [f"# test: {test}"]
    if draw(st.booleans()) or (test in ("kinematic_error", "running_torque") and not draw(rare)):
        meta.append(f"# ratio: {draw(_NUMBER_TEXT) if draw(rare) else '100'}")
    if test == "running_torque" and draw(st.booleans()):
        meta.append(f"# torque_side: {draw(_TEXT) if draw(rare) else draw(st.sampled_from(['input', 'output']))}")
    if draw(st.booleans()):
        meta.append(f"# rated_torque_Nm: {draw(_NUMBER_TEXT) if draw(rare) else '67'}")
    bad = st.sampled_from(["#", "", "# no colon", "# : x", "# test: x", "#ratio:1", "# test:"])
    meta += draw(st.lists(st.one_of(st.builds("# {}: {}".format, _TEXT, _TEXT), bad), max_size=draw(rare) * 2))
    meta = draw(st.permutations(meta))
    unit = draw(st.sampled_from(_ANGLES))
    if test == "running_torque":  # one angle or both, and sometimes the temperature
        angles = draw(st.sampled_from([["wg_angle"], ["output_angle"], ["wg_angle", "output_angle"]]))
        header = ["time_s", "torque_Nm"] + [f"{a}_{unit}" for a in angles]
        header += ["temperature_C"] if draw(st.booleans()) else []
    else:
        header = ["time_s", "torque_Nm"] + ([f"angle_{unit}"] if test != "kinematic_error"
                                            else [f"wg_angle_{unit}", f"output_angle_{unit}"])
    odd = st.sampled_from(["a\rb", '"t,s"', '"open', " ", "time_s ", "ANGLE_RAD", "x" * 140_000])
    header += draw(st.lists(st.one_of(odd, st.sampled_from(_COLUMNS), _TEXT), max_size=draw(rare) * 2))
    if draw(rare):
        header.pop(draw(st.integers(0, len(header) - 1)))
    header = draw(st.permutations(header))
    n = draw(st.sampled_from([12, 24, 10, 12, 9, 1, 0]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32)))  # numbers in bulk: fast to draw
    time, values = np.cumsum(rng.uniform(1e-3, 10.0, n)), rng.normal(0.0, 100.0, (n, len(header)))
    if not mutate or draw(st.booleans()):  # a record that looks like its test: a torque cycle and its twist
        torque, wg = 60.0 * np.sin(np.linspace(0.0, 2.0 * np.pi, n)), np.linspace(0.0, 20.0, n)
        rad = {"torque_Nm": torque, "angle": torque / 3e4 + 1e-3, "wg_angle": wg, "output_angle": wg / 100.0,
               "temperature_C": np.full(n, 25.0)}
        for c, name in enumerate(header):
            base, _, unit = name.rpartition("_")
            if name in rad or base in rad:
                values[:, c] = rad[name] if name in rad else rad[base] / ANGLE_UNITS.get(unit, 1.0)
    rows = [[repr(float(time[r] if name == "time_s" else values[r, c])) for c, name in enumerate(header)]
            for r in range(n)]
    for _ in range(draw(st.integers(0, 4)) if rows and draw(rare) else 0):
        r = draw(st.integers(0, len(rows) - 1))
        kind = draw(st.integers(0, 4))
        if kind == 0 and rows[r]:
            rows[r][draw(st.integers(0, len(rows[r]) - 1))] = draw(st.one_of(_NUMBER_TEXT, _TEXT))
        elif kind == 1:
            rows[r].append(draw(_NUMBER_TEXT))
        elif kind == 2 and rows[r]:
            rows[r].pop()
        elif kind == 3 and r and "time_s" in header and len(rows[r - 1]) == len(rows[r]) == len(header):
            rows[r][header.index("time_s")] = rows[r - 1][header.index("time_s")]  # time stands still
        elif kind == 4:
            rows.insert(r, [draw(st.sampled_from(["# late key: 1", "", "   "]))])
    sep = draw(st.sampled_from([";", "\t", ", "])) if draw(rare) else ","
    end = draw(st.sampled_from(["\n", "\r\n", "\r"])) if draw(rare) else "\n"
    text = end.join(meta + [sep.join(header)] + [",".join(row) for row in rows]) + end
    raw = text.encode("utf-8")
    if draw(st.booleans()):
        raw = b"\xef\xbb\xbf" + raw
    columns = None
    if mutate and draw(st.integers(0, 4)) == 0:
        columns = draw(st.dictionaries(st.sampled_from(_COLUMNS + ["junk"]),
                                       st.one_of(st.sampled_from(header + ["nope"]), _TEXT), max_size=3))
    return raw, columns


@_settings(120)
@given(case=measurement_csv())
def test_measurement_csv_is_read_or_refused(fuzz_dir, case):
    raw, columns = case
    path = fuzz_dir / "data.csv"
    path.write_bytes(raw)
    meas = _ok_or_input_error(load_measurement, path, columns)
    event("read" if meas is not None else "refused")
    if meas is not None:  # what is accepted is what the format promises
        assert len(meas) >= 10 and np.all(np.diff(meas.time) > 0)
        assert all(np.all(np.isfinite(v)) for v in meas.columns().values())


_RAW = st.one_of(st.binary(max_size=200), st.text(max_size=200).map(lambda s: s.encode("utf-8")),
                 st.builds(lambda a, b: a + b.encode("utf-8", "surrogatepass"),
                           st.sampled_from([b"", b"\xef\xbb\xbf", b"# test: stiffness\n", b"\x89HDF\r\n\x1a\n",
                                            b"# test: stiffness\ntime_s,torque_Nm,angle_rad\n"]),
                           st.text(max_size=200)))


@_settings(100)
@given(raw=_RAW, suffix=st.sampled_from([".csv", ".txt", ".h5"]))
def test_measurement_of_raw_bytes_is_refused(fuzz_dir, raw, suffix):
    path = fuzz_dir / f"raw{suffix}"
    path.write_bytes(raw)
    _ok_or_input_error(load_measurement, path)


_H5_VALUE = st.one_of(
    st.lists(st.floats(), min_size=0, max_size=14).map(lambda v: np.array(v, dtype=float)),
    st.lists(st.integers(-5, 5), max_size=14).map(lambda v: np.array(v, dtype=np.int64)),
    st.just(np.arange(30.0).reshape(10, 3)), st.just(np.float64(1.0)), st.just(np.array([b"a", b"b"])),
    st.just(np.linspace(0.0, 1.0, 12)), st.just(np.ones(12, dtype=bool)), st.just(np.ones(12, dtype=complex)))


@_settings(60)
@given(attrs=st.dictionaries(st.sampled_from(["test", "ratio", "rated_torque_Nm", "rated_torque", "x"]), st.one_of(
           st.sampled_from(["stiffness", "kinematic_error"]), _TEXT.map(lambda s: s.replace("\x00", "")),  # h5py
           st.floats(), st.integers(-10, 10), st.just(b"stiffness"), st.just(np.array([1.0, 2.0]))), max_size=4),
       datasets=st.dictionaries(st.sampled_from(_COLUMNS[:8] + ["junk"]), _H5_VALUE, max_size=5),
       group=st.booleans())
def test_measurement_hdf5_is_read_or_refused(fuzz_dir, attrs, datasets, group):
    path = fuzz_dir / "data.h5"
    with h5py.File(path, "w") as handle:
        for key, value in attrs.items():
            handle.attrs[key] = value
        for name, value in datasets.items():
            handle.create_dataset(name, data=value)
        if group:
            handle.create_group("provenance")
    _ok_or_input_error(load_measurement, path)


@_settings(15)
@given(case=st.one_of(measurement_csv(), measurement_csv(mutate=False)))
def test_fit_cli_exits_0_or_2_with_one_line(fuzz_dir, capsys, case):
    raw, columns = case
    path = fuzz_dir / "fit.csv"
    path.write_bytes(raw)
    argv = ["fit", str(path), "--json", "--out", str(fuzz_dir / "fit.fit.toml")]
    if columns:
        argv.append("--columns=" + ",".join(f"{k}={v}" for k, v in columns.items()))
    capsys.readouterr()
    code = main(argv)
    event(f"exit {code}")
    err = capsys.readouterr().err.strip().splitlines()
    assert code in (0, 2), err
    # refused: exactly one line; fitted: the data checks that are not ok, one line each
    if code == 2:
        assert len(err) == 1 and err[0].startswith("hdsim fit: error: "), err
    else:
        assert all(line.startswith("hdsim fit: warn: ") for line in err), err


@_settings(15)
@given(case=measurement_csv(mutate=False).filter(lambda c: b"# test: running_torque" in c[0]))
def test_diagnose_cli_on_a_sweep_exits_0_or_2_with_one_line(fuzz_dir, capsys, case):
    raw, _ = case
    path = fuzz_dir / "sweep.csv"
    path.write_bytes(raw)
    capsys.readouterr()
    code = main(["diagnose", str(path), "--json"])
    event(f"exit {code}")
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert code in (0, 2), err
    if code == 2:
        assert len(err) == 1 and err[0].startswith("hdsim diagnose: error: "), err
    else:
        assert json.loads(captured.out)["test"] == "running_torque"


# --------------------------------------------------------------------------- 2. scenarios

_WORDS = {"mode": ["prescribed", "pi"], "return": ["yes", "no"], "feedforward": ["yes", "no"],
          "position_loop": ["yes", "no"], "model": ["catalog", "none"], "method": ["Radau", "BDF", "RK45"],
          "profile": "hold constant reversal trapezoid sine csv none opposing step sweep".split(),
          "setup": ["locked_wave_generator", "driven_wave_generator"], "csv": ["profile.csv", "no.csv", ".", "a\x00b"]}
_METRICS = ("lost_motion hysteresis_loss stiffness windup transmission_accuracy tracking frequency_response "
            "order_spectrum lost_motion_centre_line junk").split() + [0.0]
_LISTS = {"metrics": st.lists(st.sampled_from(_METRICS), max_size=3)}
# a value of the wrong type, or an edge value of the right one
_JUNK = st.one_of(_NUMBER, _TEXT, st.booleans(), st.lists(st.one_of(_NUMBER, _TEXT), max_size=2),
                  st.dictionaries(st.sampled_from(["a", "rate"]), _NUMBER, max_size=1))
_SANE = {float: st.one_of(st.sampled_from([0.04, 0.2, 1.0, 2.0, 30.0, math.inf, math.nan]), st.floats(0.01, 100.0)),
         int: st.sampled_from([1, 2, 3, 10, 64, 100]),
         list: st.lists(st.one_of(st.floats(-0.3, 0.3), st.just(math.nan)), max_size=3)}


def _value_for(key: str, kind, rare):
    """Mostly a sane value for a schema entry; one time in ``rare`` junk or an edge value."""
    if isinstance(kind, dict):
        return _table(kind, rare)
    sane = ((_LISTS[key] if key in _LISTS else _SANE[list]) if kind is list else
            st.sampled_from(_WORDS.get(key, ["fuzz"])) if kind is str else _SANE[kind])
    return _mostly(sane, _JUNK, rare)


@st.composite
def _table(draw, schema: dict, rare: int = 8):
    """A dict of a few keys of ``schema`` (and sometimes a junk key) with values from `_value_for`."""
    keys = draw(st.lists(st.sampled_from(sorted(schema)), max_size=4, unique=True))
    table = {key: draw(_value_for(key, schema[key], rare)) for key in keys}
    if draw(st.integers(0, rare)) == rare:
        table[draw(_TEXT)] = draw(_JUNK)
    return table


@st.composite
def scenario_dict(draw, setup: str | None = None):
    """A scenario table of ``setup`` or of either set-up (or a junk one)."""
    setup = setup or draw(st.sampled_from(["locked_wave_generator", "driven_wave_generator"] * 3 + ["junk"]))
    data = draw(_table(schema_for(setup)))
    if draw(st.integers(0, 8)) < 8:  # mostly the keys a scenario needs
        data.setdefault("name", "fuzz")
        data.setdefault("setup", draw(_mostly(st.just(setup), _JUNK, rare=8)))
        for table, keys in {"locked_wave_generator": {"load": ("amplitude", "cycles", "rate")},
                            "driven_wave_generator": {"input": ("mode", "profile")}}.get(setup, {}).items():
            if isinstance(data.setdefault(table, {}), dict):
                for key in keys:
                    data[table].setdefault(key, draw(_value_for(key, schema_for(setup)[table][key], 8)))
        if "csv" in (data.get("input", {}).get("profile"), data.get("load", {}).get("profile")):
            data["input"].setdefault("csv", draw(st.sampled_from(_WORDS["csv"])))
    return data


@_settings(120)
@given(data=scenario_dict())
def test_scenario_file_is_loaded_or_refused(fuzz_dir, data):
    path = fuzz_dir / "scenario.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    scenario = _ok_or_input_error(load_scenario, path)
    event("loaded" if scenario is not None else "refused")
    if scenario is not None:  # the [solver] table is checked when a run starts; nothing runs here
        _ok_or_input_error(solver_options, scenario)


_TOML_JUNK = st.one_of(
    st.text(max_size=200), st.binary(max_size=100).map(lambda b: b.decode("latin-1")),
    st.builds("{}\n{}".format, st.sampled_from(['name = "x"', "[load]", 'setup = "driven_wave_generator"',
                                                "name = ", "[[input]]", "a = 1\na = 2", "x = nan"]),
              st.text(max_size=60)))


@_settings(70)
@given(text=_TOML_JUNK)
def test_scenario_of_junk_text_is_refused(fuzz_dir, text):
    path = fuzz_dir / "junk.toml"
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    _ok_or_input_error(load_scenario, path)


@_settings(85)
@given(data=scenario_dict("driven_wave_generator"))
def test_driven_bench_is_built_or_refused(fuzz_dir, data):
    scenario = _ok_or_input_error(Scenario, data, str(fuzz_dir / "driven.toml"))
    bench = scenario and _ok_or_input_error(bench_from_scenario, UNIT, scenario)
    event("bench" if bench else "refused")
    if bench:
        _assert_finite(bench.input_friction)


def _assert_finite(f):
    """Nothing infinite or NaN reaches the integrator."""
    assert np.all(np.isfinite([f.starting_torque, f.coulomb_torque, f.viscous, f.stribeck_speed,
                               *f.ripple_orders, *f.ripple_amplitudes, *f.ripple_phases])), f


@_settings(75)
@given(table=_table(schema_for("driven_wave_generator")["input_friction"]))
def test_input_friction_table_is_read_or_refused(table):
    """The [input_friction] table of a driven scenario, its types checked by `Scenario` first."""
    data = {"name": "f", "setup": "driven_wave_generator", "input": {"mode": "pi", "profile": "hold"},
            "input_friction": table}
    scenario = _ok_or_input_error(Scenario, data)
    friction = scenario and _ok_or_input_error(for_unit, UNIT, scenario.data["input_friction"])
    if friction:
        _assert_finite(friction)


# --------------------------------------------------------------------------- 3. drive and model files

_PARAMS = sorted(UNIT.params())
_EFFECT_PARAMS = sorted({f"{family}.{name}" for family, classes in fx.FAMILIES.items()
                         for cls in classes.values() for name in cls.param_meta()})
_NAME_JUNK = st.one_of(_TEXT, st.sampled_from(["", "friction", "flexspline.junk", "drive.", ".h_c", "h_pz"]))


@st.composite
def fit_doc(draw):
    """A fitted-model file as written by `FitResult.save`, with junk in some places."""
    rare = st.integers(0, 6).map(lambda i: i == 6)
    doc = {"format": draw(_JUNK) if draw(rare) else "hdsim-fit-1",
           "unit": draw(st.one_of(_JUNK, st.just(""))) if draw(rare) else draw(st.sampled_from(unit_names()))}
    families = draw(st.lists(st.sampled_from(list(fx.FAMILIES)), max_size=3, unique=True))
    doc["effects"] = {f: draw(st.sampled_from(sorted(fx.FAMILIES[f])) if not draw(rare) else
                              st.one_of(st.sampled_from(["tanh", "dahl", "fourier", "junk"]), _JUNK))
                      for f in families}
    if draw(rare):
        doc["effects"][draw(_NAME_JUNK)] = draw(st.one_of(st.sampled_from(["none", "dahl"]), _JUNK))
    names = draw(st.lists(st.sampled_from(_PARAMS + _EFFECT_PARAMS), max_size=4, unique=True))
    doc["parameters"] = {n: draw(st.one_of(st.sampled_from([v, 2 * v, 0.5 * v]), _NUMBER, _JUNK))
                         for n in names for v in [UNIT.params().get(n, 1e-3)]}
    if draw(rare):
        doc["parameters"][draw(_NAME_JUNK)] = draw(_JUNK)
    for table in draw(st.lists(st.sampled_from(["effects", "parameters", "offset", "fit"]), max_size=1)):
        doc[table] = draw(_JUNK)  # a table that is not one
    return doc


@_settings(100)
@given(doc=fit_doc())
def test_fitted_model_file_is_loaded_or_refused(fuzz_dir, doc):
    path = fuzz_dir / "model.fit.toml"
    path.write_text(tomli_w.dumps(doc), encoding="utf-8")
    model = _ok_or_input_error(load_fitted, path)
    event("loaded" if model is not None else "refused")


@_settings(50)
@given(name=st.one_of(_TEXT.filter(lambda s: ".." not in s), st.integers(250, 5000).map("a".__mul__)))
def test_file_names_are_read_or_refused(fuzz_dir, name):
    """Any name (NUL bytes, too long for the system, a folder) under the fuzz folder."""
    path = f"{fuzz_dir}/{name}"
    for read in (load_measurement, load_scenario, load_fitted, read_profile_csv):
        _ok_or_input_error(read, path)


@_settings(75)
@given(name=st.one_of(st.sampled_from(unit_names() + ["", "csg-25-100", "CSG-25-100 ", "CSG-25"]), _TEXT,
                      st.none(), st.integers(), st.lists(_TEXT, max_size=2)))
def test_unit_name_is_loaded_or_refused(name):
    _ok_or_input_error(load_unit, name)


# --------------------------------------------------------------------------- 4. option strings

_SCENARIO_KEYS = [f"scenario.{table}.{key}" if isinstance(keys, dict) else f"scenario.{table}"
                  for table, keys in schema_for("locked_wave_generator").items()
                  for key in (keys if isinstance(keys, dict) else [None])]
_VALUE_TEXT = st.one_of(st.sampled_from(_SPECIAL + ["dahl", "2", "0.1", "[1]"]), _NUMBER_TEXT, _TEXT)
_SET_ITEM = st.one_of(
    st.builds("{}={}".format, st.sampled_from(_PARAMS + ["h_pz", "friction.junk"]), _VALUE_TEXT),
    st.builds("{}={}".format, st.sampled_from(list(fx.FAMILIES)), st.sampled_from(["none", "dahl", "0"])),
    st.builds("{}={}".format, st.one_of(st.sampled_from(["scenario.load.cycles", "scenario.load.rate",
                                                         "scenario.output.samples_per_segment"]),
                                        st.sampled_from(_SCENARIO_KEYS + ["scenario.load", "scenario.junk.x",
                                                                         "scenario."])),
              st.one_of(st.sampled_from(["²", "--1", "1.5", "-1", "0", "nan", "inf", "1e999", "none"]),
                        _VALUE_TEXT)),
    st.builds("{}={}".format, _NAME_JUNK, _VALUE_TEXT), _TEXT)


@_settings(120)
@given(items=st.lists(_SET_ITEM, max_size=3))
def test_set_options_are_applied_or_refused(items):
    sets = _ok_or_input_error(parse_sets, items) or {}
    for one in [sets] + [{k: v} for k, v in sets.items()] if sets else ():  # together, then alone
        event("applied" if _ok_or_input_error(apply_sets, UNIT, LOST_MOTION, one) else "refused")


@st.composite
def column_map_text(draw):
    """The map that reads ``other.csv`` (`fuzz_dir`), with a pair dropped, changed or added now and then."""
    pairs = ["time_s=t", "torque_Nm=T_out", f"angle_{draw(st.sampled_from(_ANGLES))}=pos"]
    for _ in range(draw(_mostly(st.just(0), st.integers(1, 3)))):
        i = draw(st.integers(0, len(pairs)))
        pairs[i:i + draw(st.integers(0, 1))] = [draw(st.one_of(st.builds(
            "{}={}".format, st.sampled_from(_COLUMNS + ["junk", "", " time_s"]),
            st.sampled_from(["t", "T_out", "pos", "iq_A", "5.11*iq_A", "", "nope", "t=t"])), _TEXT))]
    return draw(st.sampled_from([",", ", ", ",,", ";"])).join(draw(st.permutations(pairs)))


@_settings(100)
@given(text=_mostly(column_map_text(), _TEXT, rare=6))
def test_column_map_option_is_parsed_or_refused(fuzz_dir, text):
    mapping = _ok_or_input_error(parse_column_map, text)
    event("read" if mapping and _ok_or_input_error(load_measurement, fuzz_dir / "other.csv", mapping) else "refused")


def _sobol_problem(names, range_text, bounds, dists):
    """What ``hdsim sobol --unit CSG-25-100 --params ... --range ... --bounds ... --dist ...`` checks."""
    frac = parse_range(range_text) if range_text is not None else None
    return from_unit("CSG-25-100", names, "lost_motion_arcmin", None, frac,
                     parse_assignments(bounds, "--bounds"), parse_assignments(dists, "--dist"))


_STUDY_NAMES = ["h_pz", "h_c", "R_v", "flexspline.h_p", "friction.slip_torque", "backlash.gap", "drive.ratio",
                "calibration.kappa_mesh", "hardening.T1"]
_BOUND = st.sampled_from(["1e-4", "2e-3", "0.5", "1", "-1", "0"])


@st.composite
def sobol_options(draw):
    """(names, --range, --bounds, --dist) that mostly make a study, with junk now and then."""
    names = draw(st.lists(_mostly(st.sampled_from(_STUDY_NAMES), st.one_of(_TEXT, st.just("junk"))),
                          min_size=1, max_size=3))
    range_text = draw(_mostly(st.sampled_from(["10%", " 5 % ", "0.5%", None]),
                              st.one_of(st.builds("{}%".format, _NUMBER_TEXT), _TEXT, st.just("10"))))
    bounds = [f"{n}={draw(_BOUND)}:{draw(_BOUND)}" for n in draw(st.lists(st.sampled_from(names), max_size=2))]
    dists = [f"{n}={draw(st.sampled_from(['unif', 'logunif', 'norm', 'norm:1e-3:1e-4', 'norm:0:0']))}"
             for n in draw(st.lists(st.sampled_from(names), max_size=1))]
    if draw(st.integers(0, 4)) == 4:
        junk = st.one_of(st.builds("{}={}:{}".format, st.sampled_from(_STUDY_NAMES), _NUMBER_TEXT, _NUMBER_TEXT),
                         st.builds("{}={}".format, st.sampled_from(_STUDY_NAMES),
                                   st.sampled_from(["unif:1", "norm:x", "norm:1:2:3", "logunif:", "beta"])),
                         _TEXT)
        draw(st.sampled_from([bounds, dists])).append(draw(junk))
    return names, range_text, bounds, dists


@_settings(100)
@given(options=sobol_options())
def test_sobol_options_build_a_problem_or_are_refused(options):
    event("built" if _ok_or_input_error(_sobol_problem, *options) else "refused")


_UPDATE_JUNK = st.one_of(_NUMBER, _TEXT, st.none(), st.lists(st.floats(-1.0, 1.0), max_size=3),
                         st.lists(st.lists(st.floats(0, 1), max_size=2), max_size=2),
                         st.sampled_from([np.array([]), {}, (1.0, "a")]))


@st.composite
def model_updates(draw):
    """``{dotted name: value}``: near-nominal numbers or batches of two, junk names and values now and then."""
    updates = {}
    for name in draw(st.lists(_mostly(st.sampled_from(_PARAMS), _NAME_JUNK, rare=8), max_size=3)):
        nominal = UNIT.params().get(name, 1.0)
        sane = st.one_of(st.floats(0.95, 1.05).map(lambda f: nominal * f),
                         st.just([nominal, 1.02 * nominal]), st.just(np.array([nominal, 0.98 * nominal])))
        updates[name] = draw(_mostly(sane, _UPDATE_JUNK))
    return updates


@_settings(100)
@given(updates=model_updates())
def test_model_updates_are_applied_or_refused(updates):
    event("updated" if _ok_or_input_error(UNIT.with_updates, updates) else "refused")


# --------------------------------------------------------------------------- bugs the fuzzer found
# Each raised something other than InputError (a traceback, exit 1) before its fix.


@pytest.mark.parametrize("header", [b"time_s,torque_Nm,angle_rad,\r0", b"a" * 140_000], ids=["cr", "long"])
def test_csv_header_that_csv_cannot_split_is_refused(tmp_path, header):
    """_csv.Error: a lone carriage return in the header line, a name over csv's field limit."""
    (tmp_path / "m.csv").write_bytes(b"# test: stiffness\n" + header + b"\n")
    with pytest.raises(InputError, match="line 2: cannot read the header row"):
        load_measurement(tmp_path / "m.csv")


@pytest.mark.parametrize("data, match", [
    ({"name": "x", "setup": []}, "setup must be str"),  # TypeError: unhashable type: 'list'
    ({"name": "x", "setup": 0.0}, "setup must be str"),  # TypeError: 'float' object is not iterable
    ({"name": "x", "setup": "driven_wave_generator", "metrics": [0.0],  # TypeError in unknown_name
      "input": {"mode": "prescribed", "profile": "hold"}}, "metrics must be a list of names"),
])
def test_scenario_with_a_setup_or_metric_that_is_no_name_is_refused(data, match):
    with pytest.raises(InputError, match=match):
        Scenario(data, "s.toml")


@pytest.mark.parametrize("text", ["²", "--1"], ids=["superscript", "double-minus"])
def test_set_of_an_integer_key_to_digits_int_cannot_read_is_refused(text):
    """ValueError: '²' and '--1' passed the isdigit() test but int() refuses them."""
    with pytest.raises(InputError, match="load.cycles must be int"):
        apply_sets(UNIT, LOST_MOTION, {"scenario.load.cycles": text})


@pytest.mark.parametrize("doc, match", [
    ({"effects": {"": "none"}}, "unknown effect family"),  # KeyError: ''
    ({"effects": {"friction": []}}, "effects.friction must be an effect id"),  # TypeError: unhashable
    ({"effects": 0.0}, r"\[effects\] must be a table"),  # AttributeError: no attribute 'items'
    ({"parameters": 0.0}, r"\[parameters\] must be a table"),  # TypeError: not iterable
    ({"unit": 5}, "unit must be a unit name"),  # TypeError in load_unit
])
def test_fitted_model_file_of_the_wrong_shape_is_refused(tmp_path, doc, match):
    whole = {"format": "hdsim-fit-1", "unit": "CSG-25-100", "effects": {}, "parameters": {}}  # each key a fit writes
    (tmp_path / "m.fit.toml").write_text(tomli_w.dumps({**whole, **doc}))
    with pytest.raises(InputError, match=match):
        load_fitted(tmp_path / "m.fit.toml")


def test_model_update_given_as_a_list_is_an_array_batch():
    """TypeError: '>=' not supported between 'list' and 'float' (the geometry checks)."""
    assert UNIT.with_updates({"flexspline.h_p": [3e-4, 3.5e-4]}).batch_size == 2


@pytest.mark.parametrize("value", [[], np.array([])], ids=["list", "array"])
def test_model_update_to_an_empty_array_is_refused(value):
    """TypeError: can't multiply sequence by 'float' (a list); an empty array made a batch of no models."""
    with pytest.raises(InputError, match="empty array"):
        UNIT.with_updates({"flexspline.h_c": value})


@pytest.mark.parametrize("name", ["a\x00b", "a" * 5000], ids=["nul", "long"])
def test_file_name_the_system_refuses_is_one_line(tmp_path, name):
    """ValueError (embedded null byte) or OSError (file name too long)."""
    for read in (load_measurement, load_scenario, load_fitted, read_profile_csv):
        with pytest.raises(InputError, match="cannot read|not found"):
            read(f"{tmp_path}/{name}")


def test_driven_scenario_naming_a_profile_file_the_system_refuses_is_refused(tmp_path):
    """A TOML string may hold a NUL byte: ValueError from reading input.csv."""
    path = tmp_path / "s.toml"
    path.write_text('name = "x"\nsetup = "driven_wave_generator"\n'
                    '[input]\nmode = "prescribed"\nprofile = "csv"\ncsv = "a\\u0000b"\n')
    with pytest.raises(InputError, match="cannot read the profile file"):
        bench_from_scenario(UNIT, load_scenario(path))


@pytest.mark.parametrize("table", [{"ripple_amplitudes": [math.nan, math.nan]}, {"viscous_Nms": math.inf},
                                   {"starting_torque_Nm": math.inf}], ids=["nan-ripple", "inf-viscous", "inf-start"])
def test_input_friction_that_is_not_finite_is_refused(table):
    """Was accepted: NaN fails every comparison of the range checks, inf passes '>= 0'."""
    with pytest.raises(InputError, match="finite"):
        for_unit(UNIT, table)


def test_huge_dimension_is_refused_in_one_line_without_a_warning(capsys):
    """RuntimeWarning (overflow writing the value in mm) printed on stderr beside the error line."""
    assert main(["simulate", "lost_motion", "--set", "flexspline.h_p=1e306", "--json"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
