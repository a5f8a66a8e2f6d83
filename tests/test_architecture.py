"""The layout keeps its promises: layers import downward only, modules stay readable.

Layers, bottom to top (docs/architecture.md): physics → model → simulation → scenarios
→ io → identification, sensitivity → plotting → cli. Every import in the package,
including one inside a function, is checked against this order.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "hdsim"
LAYERS = {"errors": 0, "units": 0, "typing": 0, "atomic": 0, "physics": 1, "model": 2, "simulation": 3,
          "scenarios": 4, "io": 5, "identification": 6, "sensitivity": 6, "plotting": 7, "cli": 8}
MAX_LINES = 600


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        yield path, parts


def _layer(parts) -> int | None:
    head = parts[0]
    return LAYERS.get(head)


def _imported(tree: ast.AST, parts) -> list[tuple[int, tuple[str, ...]]]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:  # relative import: resolve against the module's package
                base = list(parts[:-node.level])
                module = base + (node.module.split(".") if node.module else [])
            elif node.module and node.module.split(".")[0] == "hdsim":
                module = node.module.split(".")[1:]
            else:
                continue
            if module:
                found.append((node.lineno, tuple(module)))
            else:  # from hdsim import name: name is a subpackage or module
                found += [(node.lineno, (alias.name,)) for alias in node.names]
        elif isinstance(node, ast.Import):
            for alias in node.names:
                names = alias.name.split(".")
                if names[0] == "hdsim" and len(names) > 1:
                    found.append((node.lineno, tuple(names[1:])))
    return found


def test_imports_point_down_the_layers():
    wrong = []
    for path, parts in _modules():
        own = _layer(parts)
        if own is None:  # hdsim/__init__.py (the facade) and __main__ may use every layer
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for line, module in _imported(tree, parts):
            target = _layer(module)
            if target is not None and target > own:
                wrong.append(f"{path.relative_to(PACKAGE.parent)}:{line} imports hdsim.{'.'.join(module)}")
    assert not wrong, "imports from a higher layer:\n" + "\n".join(wrong)


def test_every_module_is_known_to_a_layer():
    unknown = sorted({parts[0] for _, parts in _modules() if len(parts) > 1 and parts[0] not in LAYERS})
    assert not unknown, f"packages without a layer in docs/architecture.md: {unknown}"


@pytest.mark.parametrize("path", [p for p, _ in _modules()], ids=lambda p: str(p.relative_to(PACKAGE)))
def test_module_fits_in_a_readers_head(path):
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{path.name} has {lines} lines (at most {MAX_LINES})"
