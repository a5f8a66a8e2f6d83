"""The layout keeps its promises: layers import downward only, modules stay readable.

Layers, bottom to top (docs/architecture.md): errors → units, typing, atomic, _version,
signals → physics → model → simulation → scenarios → io → identification, sensitivity
→ plotting → cli. Every import in the package, including one inside a function, is
checked against this order; two packages (or base modules) of one layer never import
each other, and no module reaches itself again through its imports (no import cycles).
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "hdsim"
LAYERS = {"errors": 0, "units": 1, "typing": 1, "atomic": 1, "_version": 1, "signals": 1,
          "physics": 2, "model": 3, "simulation": 4, "scenarios": 5, "io": 6,
          "identification": 7, "sensitivity": 7, "plotting": 8, "cli": 9}
#: top-level modules outside the layers: the facade and ``python -m hdsim`` may use every layer
UNLAYERED = {"__init__", "__main__"}
MAX_LINES = 600


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        yield path, parts


@functools.lru_cache(maxsize=None)
def _parsed(path) -> ast.AST:
    """A module's syntax tree, parsed once per session (the layer, cycle and sibling checks
    all read every module; the trees are only read)."""
    return ast.parse(path.read_text(encoding="utf-8"))


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
        tree = _parsed(path)
        for line, module in _imported(tree, parts):
            target = _layer(module)
            if target is not None and target > own:
                wrong.append(f"{path.relative_to(PACKAGE.parent)}:{line} imports hdsim.{'.'.join(module)}")
    assert not wrong, "imports from a higher layer:\n" + "\n".join(wrong)


def test_every_module_is_known_to_a_layer():
    unknown = sorted({parts[0] for _, parts in _modules() if parts[0] not in LAYERS.keys() | UNLAYERED})
    assert not unknown, f"packages or modules without a layer in docs/architecture.md: {unknown}"


def _name(parts) -> tuple[str, ...]:
    """A module's dotted parts below hdsim; a package is named by its ``__init__``'s folder."""
    return tuple(parts[:-1]) if parts[-1] == "__init__" else tuple(parts)


def _resolve(module: tuple[str, ...], known: set) -> tuple[str, ...]:
    """The module an import loads: the longest known prefix (``hdsim.model.catalog.load_unit``
    is no module; ``hdsim.model.catalog`` is); () is the facade ``hdsim/__init__.py``."""
    while module and module not in known:
        module = module[:-1]
    return module


def _import_graph() -> dict[tuple[str, ...], dict[tuple[str, ...], int]]:
    """Every module of hdsim and the modules it imports, with the line of the first import.

    Counts every import in the file, including one inside a function or under
    ``TYPE_CHECKING``: a cycle hidden in a function is still a cycle a reader must untangle.
    ``from hdsim.model import effects`` imports the module ``hdsim.model.effects``.
    """
    files = {_name(parts): (path, parts) for path, parts in _modules()}
    known = set(files)
    graph = {}
    for name, (path, parts) in files.items():
        edges: dict[tuple[str, ...], int] = {}
        for node in ast.walk(_parsed(path)):
            if isinstance(node, ast.ImportFrom):
                if node.level:  # relative: against the module's package
                    base = tuple(parts[:-node.level]) + (tuple(node.module.split(".")) if node.module else ())
                elif node.module and node.module.split(".")[0] == "hdsim":
                    base = tuple(node.module.split(".")[1:])
                else:
                    continue
                targets = [_resolve(base + (alias.name,), known) for alias in node.names]
            elif isinstance(node, ast.Import):
                targets = [_resolve(tuple(alias.name.split(".")[1:]), known)
                           for alias in node.names if alias.name.split(".")[0] == "hdsim"]
            else:
                continue
            for target in targets:
                if target != name:
                    edges.setdefault(target, node.lineno)
        graph[name] = edges
    return graph


def _strongly_connected(graph) -> list[list]:
    """Tarjan's strongly connected components (Tarjan, 1972), iterative so a deep chain
    of imports cannot hit Python's recursion limit."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(graph[root]))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is None:
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    found.append(component)
            elif child not in index:
                index[child] = low[child] = len(index)
                stack.append(child)
                on_stack.add(child)
                work.append((child, iter(graph.get(child, ()))))
            elif child in on_stack:
                low[node] = min(low[node], index[child])
    return found


def _dotted(name) -> str:
    return ".".join(("hdsim", *name))


def test_strongly_connected_finds_a_cycle():
    """The cycle finder itself: a ring of three and a self-contained pair are found, a chain is not."""
    graph = {"a": {"b": 1}, "b": {"c": 1}, "c": {"a": 1}, "d": {"a": 1, "e": 1}, "e": {"d": 1}, "f": {}}
    components = sorted(sorted(c) for c in _strongly_connected(graph) if len(c) > 1)
    assert components == [["a", "b", "c"], ["d", "e"]]


def test_no_import_cycles():
    """No two modules import each other, directly or around a ring, not even inside a function."""
    graph = _import_graph()
    cycles = [sorted(c) for c in _strongly_connected(graph) if len(c) > 1]
    lines = []
    for cycle in cycles:
        members = set(cycle)
        lines.append(" <-> ".join(_dotted(m) for m in cycle) + ": " + ", ".join(
            f"{_dotted(m)}:{graph[m][t]} imports {_dotted(t)}" for m in cycle for t in graph[m] if t in members))
    assert not cycles, "import cycles:\n" + "\n".join(lines)


def _sibling_imports(graph) -> list[str]:
    """Imports from one package into another package of the same layer."""
    wrong = []
    for name, edges in graph.items():
        if not name or LAYERS.get(name[0]) is None:  # the facade may use every layer
            continue
        for target, line in edges.items():
            if target and target[0] != name[0] and LAYERS.get(target[0]) == LAYERS[name[0]]:
                wrong.append(f"{_dotted(name)}:{line} imports {_dotted(target)}")
    return wrong


def test_sibling_check_finds_a_crossing():
    """The sibling check itself: identification using sensitivity is caught, using io is not."""
    graph = {("identification", "fit"): {("sensitivity", "design"): 7, ("io", "measurement"): 8},
             ("sensitivity", "design"): {}, ("io", "measurement"): {}}
    assert _sibling_imports(graph) == ["hdsim.identification.fit:7 imports hdsim.sensitivity.design"]


def test_siblings_stay_independent():
    """Packages on one layer (identification and sensitivity; units, atomic, signals, …) never
    import each other: each stands on the layers below alone."""
    wrong = _sibling_imports(_import_graph())
    assert not wrong, "imports between packages of one layer:\n" + "\n".join(wrong)


@pytest.mark.parametrize("path", [p for p, _ in _modules()], ids=lambda p: str(p.relative_to(PACKAGE)))
def test_module_fits_in_a_readers_head(path):
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{path.name} has {lines} lines (at most {MAX_LINES})"
