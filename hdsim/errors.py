"""Exceptions that the command line turns into one line and exit status 2.

Everything a user can get wrong (a file, a name, a number out of range) raises
`InputError`; a solver that gives up raises `SolverError`. Both are
reported without a traceback by `hdsim.cli`.
"""

from __future__ import annotations

import difflib


class InputError(ValueError):
    """Bad input from the user: out-of-range geometry, unknown name, malformed file."""


class SolverError(RuntimeError):
    """``solve_ivp`` did not reach the end of the requested time span."""


def unknown_name(kind: str, name: str, known) -> InputError:
    """An `InputError` for an unknown ``name``, suggesting close matches.

    Parameters
    ----------
    kind : str
        What was named, for the message (``'distribution'``, ``'unit'``, ...).
    name : str
        The unknown name.
    known : iterable of str
        The accepted names.

    Returns
    -------
    InputError
        The error to raise: ``unknown KIND 'NAME'; did you mean ...?`` or the known names.
    """
    known = sorted(known)
    # a dotted name given without its prefix (h_c for flexspline.h_c) is the closest match of all
    close = [k for k in known if k.endswith("." + name)][:3] or difflib.get_close_matches(name, known, n=3, cutoff=0.5)
    hint = f"; did you mean {', '.join(close)}?" if close else f"; known: {', '.join(known)}"
    return InputError(f"unknown {kind} '{name}'{hint}")


class SlowRunWarning(UserWarning):
    """A dynamic run of the locked bench that will take long, and why
    (`hdsim.scenarios.locked.slow_run_reason`)."""
