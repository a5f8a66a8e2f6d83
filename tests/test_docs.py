"""The documentation builds without a single warning (``mkdocs build --strict``).

The build renders every page, the API reference from the docstrings (mkdocstrings) and
checks every link, anchor and image, so a renamed function, a broken cross-reference or
a figure that was not regenerated fails here (a few seconds; no time limit is asserted:
speed belongs in benchmarks/). Skipped with a clear reason when the docs tool chain
(``pip install -e ".[docs]"``) is not installed.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS_TOOLS = {"mkdocs": "mkdocs", "material": "mkdocs-material",
              "mkdocstrings": "mkdocstrings", "mkdocstrings_handlers.python": "mkdocstrings[python]"}


def _missing_tools() -> list[str]:
    missing = []
    for module, package in DOCS_TOOLS.items():
        try:
            found = importlib.util.find_spec(module) is not None
        except ModuleNotFoundError:  # parent package absent
            found = False
        if not found:
            missing.append(package)
    return missing


def test_mkdocs_build_strict_has_no_warnings(tmp_path):
    missing = _missing_tools()
    if missing:
        pytest.skip(f"docs tool chain not installed ({', '.join(missing)}); "
                    "install it with: pip install -e '.[docs]'")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1", PYTHONPATH=str(ROOT))
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--clean",
         "--config-file", str(ROOT / "mkdocs.yml"), "--site-dir", str(tmp_path / "site")],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    log = proc.stdout + proc.stderr
    warnings = [line for line in log.splitlines() if re.match(r"\s*(WARNING|ERROR)\b", line)]
    assert proc.returncode == 0 and not warnings, (
        f"mkdocs build --strict failed (exit {proc.returncode}):\n" + "\n".join(warnings or [log[-3000:]]))
    assert (tmp_path / "site" / "index.html").is_file()
    assert (tmp_path / "site" / "api" / "index.html").is_file()
    # offline: no page fetches a script or a stylesheet (or a font) from the network, and the
    # equations are typeset by the vendored MathJax
    fetched = re.compile(r"""<(?:script|link)\b[^>]*\b(?:src|href)=["']?(?:https?:)?//""", re.IGNORECASE)
    pages = sorted((tmp_path / "site").rglob("*.html"))
    remote = [f"{p.relative_to(tmp_path / 'site')}: {m.group(0)}" for p in pages
              for m in fetched.finditer(p.read_text(encoding="utf-8"))]
    assert not remote, "pages fetch from the network:\n" + "\n".join(remote[:10])
    physics = (tmp_path / "site" / "physics" / "index.html").read_text(encoding="utf-8")
    assert "javascripts/mathjax/es5/tex-mml-chtml.js" in physics
    assert (tmp_path / "site" / "javascripts" / "mathjax" / "es5" / "output" / "chtml" / "fonts" / "woff-v2"
            / "MathJax_Main-Regular.woff").is_file()


def test_nomenclature_lists_every_parameter_of_the_default_unit():
    """Every dotted parameter name of the default unit appears on the nomenclature page."""
    from hdsim.model.catalog import load_unit

    page = (ROOT / "docs" / "nomenclature.md").read_text(encoding="utf-8")
    absent = [name for name in load_unit().params() if f"`{name}`" not in page]
    assert not absent, f"docs/nomenclature.md does not list {absent}"


PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _resolve(dotted: str):
    """The object a dotted name ``hdsim.module.Name.attr`` names (the longest importable module,
    then attributes)."""
    import importlib

    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for name in parts[k:]:
            obj = getattr(obj, name)
        return obj
    raise ImportError(dotted)


def test_every_hdsim_name_the_pages_give_exists():
    """A name in backquotes, ``hdsim.physics.friction.dahl_slip_rates``, is importable: a page
    that names a function renamed since fails here (mkdocs checks links, not code spans)."""
    missing = []
    for page in PAGES:
        for name in sorted(set(re.findall(r"`(hdsim(?:\.\w+)+)(?:\(\))?`", page.read_text(encoding="utf-8")))):
            try:
                _resolve(name)
            except (ImportError, AttributeError):
                missing.append(f"{page.name}: {name}")
    assert not missing, "names the code does not have:\n" + "\n".join(missing)


def test_the_nomenclature_constants_are_the_classes_own():
    """Each row of the fixed-constants table names a class constant that exists and holds the
    value the row gives."""
    from hdsim.model import effects

    page = (ROOT / "docs" / "nomenclature.md").read_text(encoding="utf-8")
    table = page.split("### Fixed numerical constants", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| [^|]+ \| ([^|]+) \| `(\w+)\.(\w+)` \|$", table, re.MULTILINE)
    assert len(rows) == 6, rows
    for cell, cls, attr in rows:
        # "$0.03\,T_1/K_1$" -> 0.03, "$10^{-6}$ rad/s" -> 1e-6, "4" -> 4
        value = re.sub(r"10\^\{(-?\d+)\}", r"1e\1", cell.strip("$ ").split("\\,")[0].split("$")[0])
        assert getattr(getattr(effects, cls), attr) == pytest.approx(float(value)), (cls, attr, cell)


def test_every_code_fence_stands_on_a_line_of_its_own():
    """A fence with text after it (a closing ```` ``` ```` followed by prose) leaves its block
    open and swallows the page's next paragraphs into code."""
    bad = []
    for page in PAGES:
        lines = page.read_text(encoding="utf-8").splitlines()
        fences = [(i, line) for i, line in enumerate(lines, 1) if "```" in line]
        bad += [f"{page.name}:{i}: {line.strip()}" for i, line in fences
                if not re.fullmatch(r"\s*```[\w-]*(?: title=\"[^\"]*\")?", line)]
        if len(fences) % 2:
            bad.append(f"{page.name}: an odd number of fences ({len(fences)})")
    assert not bad, "\n".join(bad)
