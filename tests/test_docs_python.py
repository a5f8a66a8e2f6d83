"""The Python section of the first tutorial runs as written and prints what the page shows.

`test_docs_numbers` re-runs the pages' command-line blocks; this runs a page's ``python``
blocks, in order and in one namespace, with a temporary folder as the working directory.
What a block prints is checked against the page in two places:

- a ``console`` block right after a ``python`` block is everything that block prints;
- a comment after a ``print(...)``, on its line or alone on the next, is what that print
  prints.

Numbers agree to the digits the page shows (`test_docs_numbers._agrees`), everything else
word for word, runs of spaces aside. The first tutorial keeps to these two conventions
throughout; other pages use comments to explain, so they are not read this way.
"""

from __future__ import annotations

import ast
import contextlib
import io
import re

import pytest

from test_docs_numbers import ROOT, _agrees

PAGE = ROOT / "docs" / "tutorial-first-simulation.md"
BLOCK = re.compile(r"```python\n(.*?)```(?:\s*```console\n(.*?)```)?", re.DOTALL)
NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[+-]?\d+)?")


def _same(shown: str, printed: str) -> bool:
    """``printed`` is ``shown``: the same words (runs of white space aside) and numbers that agree
    to the digits ``shown`` gives."""
    shown_numbers, printed_numbers = NUMBER.findall(shown), NUMBER.findall(printed)
    words = [" ".join(NUMBER.sub("#", text).split()) for text in (shown, printed)]
    return (words[0] == words[1] and len(shown_numbers) == len(printed_numbers)
            and all(_agrees(s, float(p)) for s, p in zip(shown_numbers, printed_numbers)))


def _comment_output(lines: list[str], statement: ast.stmt) -> str | None:
    """The output a page shows for a ``print(...)`` statement: the comment on its last line,
    or a line holding only a comment right after it."""
    call = statement.value if isinstance(statement, ast.Expr) else None
    if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and call.func.id == "print"):
        return None
    last = lines[statement.end_lineno - 1]
    tail = last[statement.end_col_offset:]
    if "#" in tail:
        return tail.split("#", 1)[1].strip()
    after = lines[statement.end_lineno] if statement.end_lineno < len(lines) else ""
    return after.strip()[1:].strip() if after.strip().startswith("#") else None


def _run_block(code: str, namespace: dict) -> tuple[str, list[tuple[str, str, str]]]:
    """Run ``code`` statement by statement: everything it printed, and (statement, shown,
    printed) for each print whose output the page shows in a comment."""
    lines = code.splitlines()
    everything, checked = io.StringIO(), []
    for statement in ast.parse(code).body:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(ast.Module([statement], []), str(PAGE), "exec"), namespace)
        everything.write(out.getvalue())
        shown = _comment_output(lines, statement)
        if shown is not None:
            checked.append((ast.get_source_segment(code, statement), shown, out.getvalue().strip()))
    return everything.getvalue(), checked


@pytest.fixture
def shared_runs(monkeypatch, default_lost_motion_run):
    """The page's run of the default unit's lost-motion scenario is the session's (the same
    model and scenario, checked); any other run is made here."""
    import hdsim

    own = hdsim.run_scenario

    def run(model, scenario, **kw):
        done = default_lost_motion_run
        if (not kw and model.batch_size == 1 and model.name == done.model.name
                and model.params() == done.model.params() and getattr(scenario, "data", None) == done.scenario.data):
            return done
        return own(model, scenario, **kw)

    monkeypatch.setattr(hdsim, "run_scenario", run)


def test_the_first_tutorials_python_prints_what_the_page_shows(tmp_path, monkeypatch, shared_runs):
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    shown_anything = 0
    for m in BLOCK.finditer(PAGE.read_text(encoding="utf-8")):
        printed, checked = _run_block(m.group(1), namespace)
        for statement, shown, out in checked:
            assert _same(shown, out), f"{statement}\n  the page shows: {shown}\n  it prints:      {out}"
        if m.group(2) is not None:
            assert _same(m.group(2), printed), f"the page shows:\n{m.group(2)}\nthe block prints:\n{printed}"
        shown_anything += len(checked) + (m.group(2) is not None)
    assert shown_anything >= 8, "the page's examples no longer show their output"


@pytest.mark.parametrize("shown, printed, same", [
    ("Radau 9265", "Radau 9231", False),
    ("[0.8987 0.8451]", "[0.89868663 0.84505668]", True),
    ("[0.8987 0.8451]", "[0.87810359 0.84505668]", False),
    ("['a', 'b']", "['a',  'b']", True),
    ("['a', 'b']", "['a', 'c']", False),
    ("31000", "31000 extra", False),
])
def test_output_is_compared_word_for_word_and_number_to_its_digits(shown, printed, same):
    assert _same(shown, printed) is same
