"""The command line under input it must refuse: one line on stderr, exit 2, nothing written.

Each test here reproduces a defect a tester found (a half JSON object, a result file of
infinities, a measurement overwritten by its own fit, a scenario name that wrote outside
--out, an "internal error" on input the user must fix, argparse's usage block, numpy's
warnings before the one-line refusal) and checks the refusal the project's rules ask for.
All run in-process and fast: no simulation is run (a run that gave infinities is faked).
"""

from __future__ import annotations

import json
import math
import shutil
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from hdsim.errors import InputError

DATA = Path(__file__).parent / "data" / "stiffness_example.csv"


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


def _files(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.fixture
def record(tmp_path) -> Path:
    """A valid stiffness record in the test's folder."""
    return Path(shutil.copy(DATA, tmp_path / "good.csv"))


# ---------------------------------------------------------------- 1. emit_json


def test_emit_json_prints_nothing_when_a_value_cannot_be_json(capsys):
    from hdsim.cli import emit_json

    with pytest.raises(ValueError):
        emit_json({"scenario": "stiffness", "metrics": {"K1_Nm_per_rad": math.inf}})
    assert capsys.readouterr().out == ""


# ---------------------------------------------------------------- 2. non-finite results


class _InfiniteRun:
    """What `run_scenario` returned for ``--set scenario.load.rate=1e300``: a metric of inf."""

    def __init__(self, model, scenario):
        self.model, self.scenario = model, scenario
        self.metrics = {"K1_Nm_per_rad": np.array([math.inf]), "torsion_at_rated_arcmin": np.array([6.3])}
        self.result = SimpleNamespace(setup=scenario.setup, metadata={"evaluator": {"chosen": "dynamic"}})

    def save(self, path):  # as the real run file is written
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text("written")
        return Path(path)


def _marking_writer(run, out_dir, figures=True):
    """Stands for `_common.write_outputs`: leaves a file, as the real one leaves the run's."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / f"{run.scenario.name}.h5").write_text("written")
    return {"result": str(out_dir / f"{run.scenario.name}.h5")}


@pytest.mark.parametrize("json_flag", [["--json"], []])
def test_simulate_refuses_a_non_finite_metric_before_writing(json_flag, cli, tmp_path, monkeypatch):
    from hdsim.cli import simulate

    monkeypatch.setattr(simulate, "run_scenario", lambda model, scenario, evaluator=None: _InfiniteRun(model, scenario))
    code, out, err = cli("simulate", "stiffness", "--out", tmp_path / "o5", "--no-figures", *json_flag)
    line = _one_line(err)
    assert code == 2 and out == "", err
    assert line.startswith("hdsim simulate: error:") and "K1_Nm_per_rad" in line and "no finite value" in line
    assert "torsion_at_rated_arcmin" not in line  # only the metrics that are not finite are named
    assert not (tmp_path / "o5").exists()


def test_demo_refuses_a_non_finite_metric_before_writing_either_run(cli, tmp_path, monkeypatch):
    from hdsim.cli import _common, demo

    def run(model, scenario):  # the lost-motion run is fine, the stiffness run overflowed
        bad = _InfiniteRun(model, scenario)
        if scenario.name == "lost_motion":
            bad.metrics = {"lost_motion_arcmin": np.array([0.85])}
        return bad

    monkeypatch.setattr(demo, "run_scenario", run)
    monkeypatch.setattr(_common, "write_outputs", _marking_writer)
    code, out, err = cli("demo", "--out", tmp_path / "demo", "--json")
    assert code == 2 and out == "" and "K1_Nm_per_rad" in err.splitlines()[-1], err
    assert not (tmp_path / "demo").exists()


def test_fit_refuses_a_non_finite_fit_before_writing(cli, record, monkeypatch):
    from hdsim.identification.fit import FitResult

    summary = FitResult.summary
    monkeypatch.setattr(FitResult, "summary", lambda self: {**summary(self), "rmse_rad": math.inf, "bic": math.inf})
    code, out, err = cli("fit", record, "--json", cwd=record.parent)
    line = _one_line(err)  # the data checks' warnings are said after the work: there is none
    assert code == 2 and out == "", err
    assert "rmse_rad" in line and "bic" in line and "no finite value" in line
    assert _files(record.parent) == ["good.csv"]


def test_fit_refuses_the_record_with_an_absurd_torque_cell(cli, record):
    """The tester's record (the 6th data row's torque -1e200): refused in one line, nothing written."""
    lines = record.read_text().splitlines(keepends=True)
    cells = lines[3 + 5].split(",")
    cells[1] = "-1e200"
    lines[3 + 5] = ",".join(cells)
    bad = record.with_name("bad.csv")
    bad.write_text("".join(lines))
    code, out, err = cli("fit", bad, "--json", cwd=record.parent)
    assert code == 2 and out == "" and _one_line(err).startswith("hdsim fit: error:"), err
    assert _files(record.parent) == ["bad.csv", "good.csv"]


# ---------------------------------------------------------------- 3. the data file as output


@pytest.mark.parametrize("spelling", ["good.csv", "./sub/../good.csv", "{abs}"])
def test_fit_out_cannot_overwrite_the_data_file(spelling, cli, record):
    (record.parent / "sub").mkdir()
    before = record.read_bytes()
    code, out, err = cli("fit", record.name, "--out", spelling.format(abs=record), cwd=record.parent)
    line = _one_line(err)
    assert code == 2 and "--out" in line and "data file" in line, err
    assert record.read_bytes() == before


def test_fit_out_through_a_link_cannot_overwrite_the_data_file(cli, record):
    link = record.with_name("link.csv")
    link.symlink_to(record)
    code, _, err = cli("fit", record.name, "--out", link.name, cwd=record.parent)
    assert code == 2 and "data file" in _one_line(err)
    assert record.read_bytes() == DATA.read_bytes()


@pytest.mark.parametrize("verb", ["fit", "diagnose"])
def test_a_report_page_cannot_overwrite_the_data_file(verb, cli, tmp_path):
    data = Path(shutil.copy(DATA, tmp_path / "index.md"))  # a record named like the report's page
    code, _, err = cli(verb, data.name, "--report", ".", "--out" if verb == "fit" else "--json",
                       *(["fit.toml"] if verb == "fit" else []), cwd=tmp_path)
    line = _one_line(err)
    assert code == 2 and "--report" in line and "data file" in line, err
    assert data.read_bytes() == DATA.read_bytes() and _files(tmp_path) == ["index.md"]


# ---------------------------------------------------------------- 4. the scenario name


@pytest.mark.parametrize("name", ["../../etc/x", "", "  ", "a/b", "a\\b", ".hidden", "..", "a\0b"])
def test_a_scenario_name_that_is_no_file_stem_is_refused(name):
    from hdsim.scenarios.scenario import Scenario, load_scenario

    scenario = load_scenario("lost_motion")
    with pytest.raises(InputError, match="name"):
        scenario.with_updates({"name": name})
    with pytest.raises(InputError, match="name"):
        Scenario({**scenario.data, "name": name}, "my.toml")


def test_every_builtin_scenario_still_loads():
    from hdsim.scenarios.scenario import builtin_scenario_names, load_scenario

    for name in builtin_scenario_names():
        assert load_scenario(name).name == name


@pytest.mark.parametrize("name", ["../../etc/x", ""])
def test_simulate_with_a_bad_scenario_name_writes_nothing(name, cli, tmp_path):
    out = tmp_path / "a" / "b" / "out"
    code, _, err = cli("simulate", "lost_motion", "--set", f"scenario.name={name}", "--out", out)
    if name == "":  # '--set scenario.name=' is refused by --set itself; the file's name = "" is not
        assert code == 2 and "NAME=VALUE" in _one_line(err)
        scenario = tmp_path / "empty.toml"
        text = Path(__file__).parents[1].joinpath("scenarios", "lost_motion.toml").read_text()
        scenario.write_text(text.replace('name = "lost_motion"', 'name = ""'))
        code, _, err = cli("simulate", scenario, "--out", out)
    assert code == 2 and "name" in _one_line(err), err
    assert _files(tmp_path) == ([] if name else ["empty.toml"])


# ---------------------------------------------------------------- 5. exit 2, not "internal error"


@pytest.mark.parametrize("verb, option", [("fit", "--out"), ("fit", "--report"), ("diagnose", "--report"),
                                          ("simulate", "--out"), ("sobol", "--out"), ("sobol", "--report"),
                                          ("demo", "--out")])
def test_an_empty_path_is_refused_not_taken_for_the_default(verb, option, cli, record, capsys):
    """``--out ''`` had written to the default place, as if the option had not been given."""
    data = {"fit": [record.name], "diagnose": [record.name], "simulate": ["lost_motion"], "sobol": [], "demo": []}
    with pytest.raises(SystemExit) as stopped:  # the option parser's refusal, as for any malformed option
        cli(verb, *data[verb], option, "", cwd=record.parent)
    assert stopped.value.code == 2 and f"argument {option}: an empty path" in _one_line(capsys.readouterr().err)
    assert _files(record.parent) == ["good.csv"]


def test_fit_out_that_is_a_folder_is_refused(cli, record):
    (record.parent / "dir").mkdir()
    code, _, err = cli("fit", record.name, "--out", "dir", cwd=record.parent)
    line = _one_line(err)
    assert code == 2 and "--out" in line and "folder" in line and "internal" not in line
    assert _files(record.parent) == ["dir", "good.csv"]


def test_diagnose_report_with_a_folder_for_its_page_is_refused_before_the_work(cli, record):
    (record.parent / "rep" / "index.html").mkdir(parents=True)
    code, _, err = cli("diagnose", record.name, "--report", "rep", cwd=record.parent)
    line = _one_line(err)
    assert code == 2 and "index.html" in line and "internal" not in line, err
    assert _files(record.parent / "rep") == ["index.html"]  # no index.md, no figures


@pytest.mark.parametrize("verb", ["fit", "diagnose"])
def test_report_that_is_a_file_is_refused(verb, cli, record):
    (record.parent / "afile").write_text("")
    code, _, err = cli(verb, record.name, "--report", "afile", cwd=record.parent)
    assert code == 2 and "not a folder" in _one_line(err), err


def test_sobol_report_that_is_a_file_is_refused(cli, tmp_path):
    (tmp_path / "afile").write_text("")
    code, out, err = cli("sobol", "--function", "ishigami", "--n", "64", "--workers", "1", "--report", "afile",
                         cwd=tmp_path)
    line = _one_line(err)
    assert code == 2 and out == "" and "--report" in line and "not a folder" in line, err
    assert _files(tmp_path) == ["afile"]


def test_sobol_report_with_a_folder_for_its_summary_is_refused(cli, tmp_path):
    (tmp_path / "rep" / "sobol.json").mkdir(parents=True)
    code, _, err = cli("sobol", "--function", "ishigami", "--n", "16", "--workers", "1", "--report", "rep",
                       cwd=tmp_path)
    assert code == 2 and "sobol.json" in _one_line(err), err
    assert _files(tmp_path / "rep") == ["sobol.json"]


@pytest.mark.parametrize("option, value", [("--seed", "-1"), ("--chunksize", "-5")])
def test_sobol_refuses_a_negative_seed_or_chunk(option, value, cli, tmp_path):
    code, out, err = cli("sobol", "--function", "ishigami", "--n", "16", "--workers", "1", option, value,
                         cwd=tmp_path)
    line = _one_line(err)
    assert code == 2 and out == "" and option in line and "internal" not in line, err


@pytest.mark.parametrize("verb", ["simulate", "demo"])
def test_a_folder_where_a_result_file_goes_is_refused_before_the_run(verb, cli, tmp_path, monkeypatch):
    from hdsim.cli import demo, simulate

    def never(*args, **kwargs):
        raise AssertionError("the run must not start")

    monkeypatch.setattr(simulate, "run_scenario", never)
    monkeypatch.setattr(demo, "run_scenario", never)
    (tmp_path / "out" / "lost_motion.h5").mkdir(parents=True)
    code, _, err = cli(verb, *(["lost_motion"] if verb == "simulate" else []), "--out", tmp_path / "out")
    assert code == 2 and "lost_motion.h5" in _one_line(err), err


# ---------------------------------------------------------------- 6. argument errors


@pytest.mark.parametrize("args, prog", [
    (["simulate", "lost_motion", "--bogus"], "hdsim simulate"),
    (["fit"], "hdsim fit"),
    (["sobol", "--n"], "hdsim sobol"),
    (["units", "--json", "extra"], "hdsim units"),
    (["bogus"], "hdsim"),
    (["--bogus"], "hdsim"),
])
def test_an_argument_error_is_one_line_naming_the_verb(args, prog, capsys):
    from hdsim.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(args)
    err = capsys.readouterr().err
    line = _one_line(err)
    assert exit_.value.code == 2 and "usage" not in err
    assert line.startswith(f"{prog}: error: ") and line.endswith(f"({prog} --help lists the options)"), line


def test_a_negative_range_says_how_to_write_it(capsys):
    from hdsim.cli import main

    with pytest.raises(SystemExit):
        main(["sobol", "--function", "ishigami", "--range", "-10%"])
    assert "--range=VALUE" in _one_line(capsys.readouterr().err)
    # written so, it reaches the option's own check: a range is a half-width, never negative
    assert main(["sobol", "--unit", "CSG-25-100", "--params", "h_pz", "--range=-10%",
                 "--output", "lost_motion_arcmin"]) == 2
    assert "--range must be between 0%" in _one_line(capsys.readouterr().err)


# ---------------------------------------------------------------- 7. library warnings


def _noisy_verb(args):
    """A verb that trips numpy and scipy warnings, warns itself, says a check, then refuses."""
    from scipy.integrate import solve_ivp

    np.array([1e308]) * 10.0  # numpy's overflow: a RuntimeWarning attributed to this line
    np.polyfit([1.0, 1.0, 1.0], [1.0, 2.0, 3.0], 1)  # numpy's RankWarning
    solve_ivp(lambda t, y: -y, (0.0, 1e-3), [1.0], rtol=1e-14)  # scipy's 'rtol is too small'
    warnings.warn("a warning of the program's own", UserWarning)  # not a library's: still shown
    print("hdsim units: warn: a check the user must read", file=sys.stderr)
    raise InputError("the one line")


def test_library_warnings_are_hidden_unless_debug(cli, monkeypatch):
    monkeypatch.setattr("hdsim.cli.units.main", _noisy_verb)
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        code, out, err = cli("units")
    assert code == 2 and out == ""
    assert err.splitlines() == ["hdsim units: warn: a check the user must read", "hdsim units: error: the one line"]
    assert [str(w.message) for w in shown] == ["a warning of the program's own"]
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        with pytest.raises(InputError):
            cli("units", "--debug")
    messages = " | ".join(str(w.message) for w in shown)
    assert "overflow" in messages and "rtol" in messages and "poorly conditioned" in messages.lower(), messages


# ---------------------------------------------------------------- 8. units --template --json


def test_units_template_json_is_one_json_object_holding_the_template(cli):
    from hdsim.model.drive_file import template

    code, out, err = cli("units", "--template", "--json")
    assert code == 0 and err == ""
    assert json.loads(out) == {"format": "toml", "template": template()}


def test_a_scenario_or_drive_file_saved_with_a_byte_order_mark_is_read(tmp_path):
    """Windows editors start a UTF-8 file with a BOM; TOML took it for a statement
    ('Invalid statement (line 1, column 1)'). CSV files already accepted it."""
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

    scenario = tmp_path / "bom.toml"
    scenario.write_bytes(b"\xef\xbb\xbf" + builtin_scenario_path("lost_motion").read_bytes())
    assert load_scenario(scenario).data == load_scenario("lost_motion").data
    drive = tmp_path / "drive.toml"
    drive.write_bytes(b"\xef\xbb\xbf" + b'name = "X"\nratio = 100\nrated_torque_Nm = 87\n')
    assert load_unit(drive).name == "X"
