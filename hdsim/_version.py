"""The version of hdsim, in a module of its own so that any layer can read it.

The facade (`hdsim/__init__.py`) re-exports it as ``hdsim.__version__``; run files and
the command line import it from here, so nothing inside the package imports the facade.
pyproject.toml states the same number (tests/test_version.py checks they agree).
"""

__version__ = "0.1.0"
