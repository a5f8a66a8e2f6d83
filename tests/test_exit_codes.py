"""Exit status means something: 2 for bad input only, 1 for a failure of the program.

The program's own failure is reported in one line that says so and how to get the
traceback (``--debug`` or ``HDSIM_DEBUG=1``); a model that raises a programming error
ends a study at once, as bad input, instead of filling it with failed rows.
"""

from __future__ import annotations

import errno
import os

import numpy as np
import pytest

from hdsim.cli import main
from hdsim.sensitivity import ModelError, evaluate


def test_bad_input_is_exit_2_with_one_line(capsys):
    assert main(["simulate", "no_such_scenario_anywhere", "--json"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hdsim simulate: error:")


def test_a_failure_of_the_program_is_exit_1_and_says_so(capsys, monkeypatch):
    import hdsim.cli.units as units_verb

    def broken(args):
        raise ZeroDivisionError("division by zero deep inside")

    monkeypatch.setattr(units_verb, "main", broken)
    monkeypatch.delenv("HDSIM_DEBUG", raising=False)
    parser_main = main
    assert parser_main(["units"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "internal error: ZeroDivisionError" in err[0] and "--debug" in err[0]


@pytest.mark.parametrize("how", ["flag", "env"])
def test_debug_shows_the_traceback(capsys, monkeypatch, how):
    import hdsim.cli.units as units_verb

    def broken(args):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(units_verb, "main", broken)
    argv = ["units"]
    if how == "flag":
        argv.append("--debug")
    else:
        monkeypatch.setenv("HDSIM_DEBUG", "1")
    with pytest.raises(ZeroDivisionError):
        main(argv)


class _BuggyModel:
    """A user's model with a bug: every row raises TypeError."""

    calls = 0

    def __call__(self, X):
        type(self).calls += len(X)
        return X[:, 0] + "a string"


def test_a_model_bug_ends_the_study_at_the_first_chunk():
    X = np.random.default_rng(0).uniform(size=(2048, 3))
    _BuggyModel.calls = 0
    with pytest.raises(ModelError, match="TypeError"):
        evaluate(_BuggyModel(), X, workers=1, chunksize=16)
    assert _BuggyModel.calls < 64  # one chunk and its row-by-row isolation, not 256 rows


def test_an_output_folder_that_cannot_be_written_is_said_before_the_work(tmp_path, cli):
    # a path through a file: no folder can be made there (root, as CI runs, passes permission
    # checks, so a file stands for the read-only folder)
    (tmp_path / "a_file").write_text("x")
    record = tmp_path / "bench.csv"  # a valid stiffness record: the refusal must not be about the data
    t = np.linspace(0.0, 10.0, 400)
    torque = 40.0 * np.sin(2.0 * np.pi * t / 5.0)
    angle = torque / 3e4 + 1e-6 * np.random.default_rng(0).normal(size=t.size)
    record.write_text("# test: stiffness\ntime_s,torque_Nm,angle_rad\n"
                      + "".join(f"{a},{b},{c}\n" for a, b, c in zip(t, torque, angle)))
    blocked = tmp_path / "a_file"
    for args in (["simulate", "lost_motion", "--out", blocked / "out"],
                 ["demo", "--out", blocked / "demo"],
                 ["sobol", "--function", "ishigami", "--n", "64", "--workers", "1", "--out", blocked / "study.h5"],
                 ["diagnose", record, "--report", blocked / "report"],
                 ["fit", record, "--report", blocked / "report"]):
        code, out, err = cli(*args)
        assert code == 2 and len(err.strip().splitlines()) == 1 and "cannot write into" in err, (args[0], err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file", "bench.csv"]


@pytest.mark.parametrize("number, code", [(errno.ENOSPC, 2), (errno.EACCES, 2), (errno.EROFS, 2), (errno.ENOENT, 1)])
def test_a_full_or_read_only_disk_met_while_writing_is_bad_input_other_os_errors_are_bugs(
        number, code, tmp_path, cli, monkeypatch):
    from hdsim.cli import _common

    def full(*_args, **_kwargs):
        raise OSError(number, os.strerror(number), str(tmp_path / "out" / "lost_motion.h5"))

    from hdsim.cli import simulate

    monkeypatch.setattr(simulate, "run_scenario", lambda model, scenario, **_: None)  # the write fails, not the run
    monkeypatch.setattr(_common, "write_outputs", full)
    got, _, err = cli("simulate", "lost_motion", "--out", str(tmp_path / "out"))
    assert got == code and len(err.strip().splitlines()) == 1
    assert ("internal error" in err) == (code == 1)


def test_a_disk_that_fills_during_a_study_keeps_the_finished_rows_and_says_how_to_resume(tmp_path, cli,
                                                                                         monkeypatch):
    from hdsim.sensitivity import store as study_store

    out = tmp_path / "study.h5"
    args = ["sobol", "--function", "ishigami", "--n", "64", "--workers", "1", "--chunksize", "64",
            "--out", out]
    written, write = [], study_store.H5Store.write

    def fills_after_two_chunks(self, rows, y, key, errors):
        if len(written) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        written.append(len(rows))
        return write(self, rows, y, key, errors)

    monkeypatch.setattr(study_store.H5Store, "write", fills_after_two_chunks)
    code, _, err = cli(*args)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "No space left on device" in err and "kept" in err and "--resume" in err
    monkeypatch.setattr(study_store.H5Store, "write", write)
    code, out_text, err = cli(*args, "--resume", "--json")
    assert code == 0, err
    import json

    summary = json.loads(out_text)
    assert summary["reused"] == sum(written) == 128 and summary["evaluations"] == 64 * 5
