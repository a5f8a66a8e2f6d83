"""One version number: pyproject.toml states it, hdsim._version holds it, the facade shows it."""

from __future__ import annotations

import tomllib
from pathlib import Path

import hdsim
from hdsim._version import __version__

PYPROJECT = Path(__file__).resolve().parents[1] / "pyproject.toml"


def test_pyproject_and_package_state_the_same_version():
    """pyproject.toml keeps a static version (the build reads no module); it must be the
    number run files and ``hdsim --version`` report."""
    project = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))["project"]
    assert project["version"] == __version__


def test_the_facade_shows_the_version_module():
    assert hdsim.__version__ is __version__
