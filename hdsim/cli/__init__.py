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
import warnings

from hdsim.errors import InputError, SlowRunWarning, SolverError

VERBS = ("demo", "units", "simulate", "compliance", "sobol", "fit", "diagnose")


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The parser of every verb, or of verb ``only`` alone: a verb's module imports what
    the verb needs (the dynamic solvers, the FE), and a command should not pay for the others'."""
    parser = OneLineErrorParser(
        prog="hdsim",
        description="Harmonic drive simulator: stiffness, lost motion, kinematic error, "
        "Sobol sensitivity and model-vs-measurement diagnosis.",
    )
    from hdsim._version import __version__

    parser.add_argument("--version", action="version", version=f"hdsim {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the Python traceback of an error (anywhere on the command line; "
                             "or set HDSIM_DEBUG=1)")
    # each verb's parser is a OneLineErrorParser too (argparse's default parser_class is the parent's type)
    subparsers = parser.add_subparsers(dest="verb", metavar="VERB", parser_class=OneLineErrorParser)
    for verb in VERBS if only is None else (only,):
        try:
            module = importlib.import_module(f"hdsim.cli.{verb}")
        except ModuleNotFoundError as exc:  # a verb whose module has not landed yet
            if exc.name == f"hdsim.cli.{verb}":
                continue
            raise
        module.register(subparsers)
    return parser


class OneLineErrorParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, like every other refusal of hdsim.

    argparse's own is the usage block and then ``hdsim: error: …``, even after a verb; here it
    is ``hdsim VERB: error: MESSAGE (hdsim VERB --help lists the options)``, exit status 2.
    """

    def error(self, message):
        argument_error(self.prog, message)


def argument_error(prog: str, message: str):
    """Print an argument error of ``prog`` (``hdsim`` or ``hdsim VERB``) as one line; exit 2."""
    message = " ".join(str(message).split())
    expected = re.match(r"argument (-[-\w]+)(?:/\S+)?: expected one argument", message)
    if expected:  # '--range -10%': argparse takes a value that begins with '-' for an option
        message += f"; a value that begins with '-' is written {expected.group(1)}=VALUE"
    sys.stderr.write(f"{prog}: error: {message} ({prog} --help lists the options)\n")
    raise SystemExit(2)


def emit_json(obj) -> None:
    """Print exactly one JSON object on stdout (the contract of every ``--json``).

    The whole text is made before any of it is printed: a value JSON cannot hold (NaN,
    infinity) then fails with nothing on stdout, never half an object.
    """
    text = json.dumps(obj, allow_nan=False, default=_json_default)
    sys.stdout.write(text + "\n")
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
    args, extras = parser.parse_known_args(argv)
    if extras:  # found by the top parser after the verb's: said as the verb's error
        argument_error(f"hdsim {args.verb}" if args.verb else "hdsim",
                       f"unrecognized arguments: {' '.join(extras)}")
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    debug = debug or os.environ.get("HDSIM_DEBUG", "") not in ("", "0")
    with warnings.catch_warnings():
        if not debug:
            hide_library_warnings(args.verb)
        return _dispatch(args, debug)


def _dispatch(args, debug: bool) -> int:
    """Run the verb; bad input and the machine's refusals as one line (exit 2), the
    program's own failures as an internal error (exit 1)."""
    try:
        return int(args.func(args) or 0)
    except (InputError, SolverError) as exc:
        if debug:
            raise
        # the library names its keyword (evaluator='dynamic'); the command line says its option
        print(f"hdsim {args.verb}: error: {_command_words(_one_line(exc))}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # the reader stopped reading (`hdsim units | head -1`): neither the input's fault nor the
        # program's. Python's own advice: point stdout at devnull, so that flushing it at exit
        # does not fail again, and end quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
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


#: packages whose Python warnings are advice to programmers, not to the user of the command
_LIBRARIES = frozenset({"numpy", "scipy", "SALib", "h5py", "matplotlib", "numba", "pandas", "dask",
                        "distributed", "skfem", "tomli_w"})


#: a library warning's advice in the Python API's words, and the same in the command's
_OPTION_WORDS = (("evaluator='dynamic' or 'auto'", "--evaluator dynamic or auto"),
                 ("evaluator='quasistatic'", "--evaluator quasistatic"),
                 ("and 'auto' takes it", "and --evaluator auto takes it"))


def _command_words(text: str) -> str:
    """A library message that names the evaluator keyword (evaluator='dynamic') in the
    command's words (--evaluator dynamic)."""
    for python, option in _OPTION_WORDS:
        text = text.replace(python, option)
    return text


def hide_library_warnings(verb: str | None = None) -> None:
    """Keep the numerical libraries' Python warnings off the user's stderr (``--debug`` shows them).

    A record with one absurd cell made numpy print a dozen lines of overflow warnings before
    the one-line refusal. hdsim says what the user must know itself, on lines of its own
    (``hdsim fit: warn: …``, printed, not warned), so nothing of hdsim's is hidden here.
    Call inside ``warnings.catch_warnings()``: the filter and the hook are undone on leaving it.
    """
    # numpy's floating-point warnings (overflow, divide by zero, invalid value) come from its C
    # loops and are attributed to the line that called them, often hdsim's own: only their
    # category names them. hdsim raises no RuntimeWarning of its own (nor its RankWarning subclass).
    warnings.filterwarnings("ignore", category=RuntimeWarning)
    # a library's other warnings (scipy's 'rtol is too small') may be attributed, by their
    # stacklevel, to the hdsim line that called it; the frame that issued them is the library's
    shown = warnings.showwarning

    def show_unless_library(message, category, filename, lineno, file=None, line=None):
        if _issued_by_library():
            return
        if verb and issubclass(category, SlowRunWarning):  # hdsim's own advice: a line of the command's
            print(f"hdsim {verb}: warn: {_command_words(str(message))}", file=sys.stderr)
            return
        shown(message, category, filename, lineno, file, line)

    warnings.showwarning = show_unless_library


def _issued_by_library() -> bool:
    """Whether the warning being shown was issued (``warnings.warn`` called) by a library's code."""
    frame = sys._getframe(2)  # beyond _issued_by_library and show_unless_library
    while frame is not None and frame.f_globals.get("__name__") in ("warnings", __name__):
        frame = frame.f_back
    issuer = frame.f_globals.get("__name__", "") if frame is not None else ""
    return issuer.split(".")[0] in _LIBRARIES


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
