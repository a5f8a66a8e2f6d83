"""The ``hdsim`` console script.

Each verb lives in its own module under `hdsim.cli` and exposes
``register(subparsers)``, which adds its parser and sets ``func``. This file only
dispatches and turns `hdsim.errors.InputError` and
`hdsim.errors.SolverError` into one line on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import json
import os
import re
import sys

from hdsim.errors import InputError, SolverError

VERBS = ("demo", "units", "simulate", "compliance", "sobol", "fit", "diagnose")


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The parser of every verb, or of verb ``only`` alone: a verb's module imports what
    the verb needs (the dynamic solvers, the FE), and a command should not pay for the others'."""
    parser = argparse.ArgumentParser(
        prog="hdsim",
        description="Harmonic drive simulator: stiffness, lost motion, kinematic error, "
        "Sobol sensitivity and model-vs-measurement diagnosis.",
    )
    from hdsim._version import __version__

    parser.add_argument("--version", action="version", version=f"hdsim {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the Python traceback of an error (anywhere on the command line; "
                             "or set HDSIM_DEBUG=1)")
    subparsers = parser.add_subparsers(dest="verb", metavar="VERB")
    for verb in VERBS if only is None else (only,):
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
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv  # accepted before or after the verb
    argv = [a for a in argv if a != "--debug"]
    first = next((a for a in argv if not a.startswith("-")), None)
    parser = build_parser(first if first in VERBS else None)
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    debug = debug or os.environ.get("HDSIM_DEBUG", "") not in ("", "0")
    try:
        return int(args.func(args) or 0)
    except (InputError, SolverError) as exc:
        if debug:
            raise
        print(f"hdsim {args.verb}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:
        # a folder without permission, a read-only or full disk: the machine the user must
        # fix, said in one line (exit 2); any other OSError is the program's failure (below)
        if debug or not environment_error(exc):
            if debug:
                raise
            return _internal_error(args.verb, exc)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"hdsim {args.verb}: error: {where}{exc.strerror or _one_line(exc)} (the machine refused it: "
              "permission, a read-only or full disk)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"hdsim {args.verb}: interrupted", file=sys.stderr)
        return 1
    except Exception as exc:  # noqa: BLE001 - the program failed, not the input: say so, exit 1
        if debug:
            raise
        return _internal_error(args.verb, exc)


def _internal_error(verb: str, exc: BaseException) -> int:
    print(f"hdsim {verb}: internal error: {type(exc).__name__}: {_one_line(exc)} "
          "(this is a bug in hdsim, not in your input; run again with --debug or HDSIM_DEBUG=1 "
          "for the traceback)", file=sys.stderr)
    return 1


#: errno of a machine that cannot take the output: no permission, read-only, full disk, quota
_ENVIRONMENT = {errno.EACCES, errno.EPERM, errno.EROFS, errno.ENOSPC, errno.EDQUOT}


def environment_error(exc: OSError) -> bool:
    """True for an OSError of the machine (permission, read-only, full disk), h5py's included
    (it reports the errno in its message)."""
    if exc.errno in _ENVIRONMENT:
        return True
    found = re.search(r"errno = (\d+)", str(exc))
    return bool(found) and int(found.group(1)) in _ENVIRONMENT


def _one_line(exc: BaseException) -> str:
    """The message of ``exc`` on one line (a traceback never reaches the user)."""
    return " ".join(str(exc).split()) or type(exc).__name__


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
