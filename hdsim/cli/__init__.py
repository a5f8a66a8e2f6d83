"""The ``hdsim`` console script.

Each verb lives in its own module under `hdsim.cli` and exposes
``register(subparsers)``, which adds its parser and sets ``func``. This file only
dispatches and turns `hdsim.errors.InputError` and
`hdsim.errors.SolverError` into one line on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys

from hdsim.errors import InputError, SolverError

VERBS = ("demo", "units", "simulate", "sobol", "fit", "diagnose")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hdsim",
        description="Harmonic drive simulator: stiffness, lost motion, kinematic error, "
        "Sobol sensitivity and model-vs-measurement diagnosis.",
    )
    from hdsim import __version__

    parser.add_argument("--version", action="version", version=f"hdsim {__version__}")
    subparsers = parser.add_subparsers(dest="verb", metavar="VERB")
    for verb in VERBS:
        try:
            module = importlib.import_module(f"hdsim.cli.{verb}")
        except ModuleNotFoundError as exc:  # a verb whose module has not landed yet
            if exc.name == f"hdsim.cli.{verb}":
                continue
            raise
        module.register(subparsers)
    return parser


def emit_json(obj) -> None:
    """Print exactly one JSON object on stdout (the contract of every ``--json``)."""
    json.dump(obj, sys.stdout, allow_nan=False, default=_json_default)
    sys.stdout.write("\n")
    sys.stdout.flush()


def _json_default(value):
    import numpy as np

    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return str(value)


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(args.func(args) or 0)
    except (InputError, SolverError) as exc:
        print(f"hdsim {args.verb}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"hdsim {args.verb}: interrupted", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
