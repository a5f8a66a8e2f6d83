"""Atomic writes leave no temporary file behind, even after a writer killed outright."""

from __future__ import annotations

import os
import subprocess
import sys

from hdsim.atomic import write_text_atomic


def _dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_a_temporary_file_of_a_killed_writer_is_removed_by_the_next_write(tmp_path):
    target = tmp_path / "study.h5"
    orphan = tmp_path / f".study.h5.{_dead_pid()}.k2j4x9.tmp"  # a writer killed with SIGKILL
    writing = tmp_path / f".study.h5.{os.getpid()}.a1b2c3.tmp"  # a writer that still runs
    foreign = tmp_path / ".study.h5.notapid.tmp"  # not ours to judge
    other = tmp_path / f".other.h5.{_dead_pid()}.zz.tmp"  # another result's
    for path in (orphan, writing, foreign, other):
        path.write_bytes(b"\0" * 1024)
    write_text_atomic(target, "done")
    assert target.read_text() == "done"
    assert not orphan.exists()
    assert writing.exists() and foreign.exists() and other.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["study.h5", writing.name, foreign.name, other.name])


def test_a_write_leaves_no_temporary_file(tmp_path):
    write_text_atomic(tmp_path / "a.txt", "x")
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]


def test_a_device_or_pipe_is_never_replaced_by_a_result(tmp_path, cli):
    # `--out /dev/null` as root had replaced the system's /dev/null with a regular file
    import pytest

    pipe = tmp_path / "pipe"
    os.mkfifo(pipe)
    with pytest.raises(OSError, match="not a regular file"):
        write_text_atomic(pipe, "x")
    data = os.path.join(os.path.dirname(__file__), "data", "stiffness_example.csv")
    code, _, err = cli("fit", data, "--out", str(pipe), cwd=tmp_path)
    assert code == 2 and "is not a regular file (a device, pipe or socket)" in err
    assert len(err.strip().splitlines()) == 1
    assert pipe.is_fifo()
