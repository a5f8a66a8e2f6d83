"""The `hdsim fit` and `hdsim diagnose` console blocks of the docs are what the commands print.

Each block of docs/cli.md that runs one of them on the tutorial's bench file
(``docs/figures/tutorial_bench.csv``) is run again here, in this process, and compared
line by line with what the command writes to stdout and stderr: a change of wording, of
a number or of the units shown fails here until the page is updated. The tutorial's
friction-sweep blocks (``docs/figures/friction_sweep_log.csv``) shorten the output with
``...``: every line they do show must be printed. (The ``simulate`` and ``demo`` blocks
are checked figure by figure in ``tests/test_docs_numbers.py``.)
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = "docs/figures/tutorial_bench.csv"
BLOCK = re.compile(r"```console\n\$ (hdsim (?:fit|diagnose) " + re.escape(BENCH) + r"[^\n]*)\n(.*?)```", re.DOTALL)


def _blocks():
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    return [pytest.param(m.group(1), m.group(2), id=m.group(1)) for m in BLOCK.finditer(text)]


@pytest.mark.parametrize("command, shown", _blocks())
def test_a_console_block_of_the_cli_page_is_what_the_command_prints(command, shown, cli, tmp_path):
    (tmp_path / "docs" / "figures").mkdir(parents=True)
    shutil.copy(ROOT / BENCH, tmp_path / BENCH)
    code, out, err = cli(*command.split()[1:], cwd=tmp_path)
    assert code == 0, err
    printed = [line for line in (out + err).splitlines() if line.strip()]
    quoted = [line for line in shown.splitlines() if line.strip()]
    assert sorted(printed) == sorted(quoted), "\n".join(
        [f"docs/cli.md, '{command}': the page shows lines the command does not print, or misses some:"]
        + [f"  page only:    {line}" for line in quoted if line not in printed]
        + [f"  printed only: {line}" for line in printed if line not in quoted])


def test_both_blocks_are_found():
    assert sorted(p.values[0].split()[1] for p in _blocks()) == ["diagnose", "fit"]


SWEEP = "friction_sweep_log.csv"


def _sweep_blocks():
    text = (ROOT / "docs" / "tutorial-find-missing-effect.md").read_text(encoding="utf-8")
    options = re.search(r'^A="([^"]+)"$', text, re.MULTILINE).group(1)
    command = r"```bash\n(?:(?!```)[^\n]*\n)*?(hdsim (?:fit|diagnose) " + re.escape(SWEEP) + r" \$A)[^\n]*\n```"
    found = re.finditer(command + r"\s*```console\n(.*?)```", text, re.DOTALL)
    return [pytest.param(m.group(1).replace("$A", options), m.group(2), id=m.group(1)) for m in found]


@pytest.mark.parametrize("command, shown", _sweep_blocks())
def test_the_tutorials_sweep_blocks_show_lines_the_command_prints(command, shown, cli, tmp_path):
    shutil.copy(ROOT / "docs" / "figures" / SWEEP, tmp_path / SWEEP)
    code, out, err = cli(*command.split()[1:], cwd=tmp_path)
    assert code == 0, err
    printed = set((out + err).splitlines())
    missing = [line for line in shown.splitlines() if line.strip() and line.strip() != "..." and line not in printed]
    assert not missing, f"docs/tutorial-find-missing-effect.md, '{command}': lines it shows that the command " \
        "does not print:\n" + "\n".join(missing)


def test_both_sweep_blocks_are_found():
    assert sorted(p.values[0].split()[1] for p in _sweep_blocks()) == ["diagnose", "fit"]
