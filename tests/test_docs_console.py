"""The tutorial's friction-sweep blocks are what `hdsim fit` and `hdsim diagnose` print.

The blocks of ``docs/tutorial-find-missing-effect.md`` that run them on
``docs/figures/friction_sweep_log.csv`` shorten the output with ``...``: every line they do
show must be printed. (Every other ``$ hdsim …`` block of the docs, the fit and the
diagnosis of docs/cli.md among them, is run again line by line in
``tests/test_docs_numbers.py``.)
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

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
