"""The scripts of ``validation/`` as modules, for the tests that run their cases or
grading (one definition of a battery's cases, in the battery)."""

from __future__ import annotations

import functools
import importlib.util
import sys
from pathlib import Path

VALIDATION = Path(__file__).resolve().parents[1] / "validation"


@functools.lru_cache(maxsize=None)
def load(name: str):
    """``validation/<name>.py`` as a module, loaded once per session and registered by its
    name (a battery's worker processes unpickle its functions by module name)."""
    path = VALIDATION / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    if str(VALIDATION) not in sys.path:
        sys.path.insert(0, str(VALIDATION))
    spec.loader.exec_module(module)
    return module
