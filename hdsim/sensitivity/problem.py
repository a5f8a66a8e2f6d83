"""Study inputs: parameter names, bounds and distributions.

A `Problem` is the model-agnostic half of a Sobol study. It maps one-to-one
onto SALib's problem dictionary (``names``, ``bounds``, ``dists``) and can be
built from nominal values with a range (``--range 10%``, ``range=0.1``) or from explicit
bounds (``(low, high)`` per parameter). The command line parses its text into these
(`parse_range`, `parse_bounds`); `build_problem` takes typed values and words its
messages as the caller spells its options (`CLI_WORDING`, `PYTHON_WORDING`).

Distributions (SALib names):

``unif``
    uniform on ``[lo, hi]``.
``logunif``
    log-uniform on ``[lo, hi]``, both > 0.
``norm``
    normal; SALib stores ``[mean, sd]`` in place of the bounds.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from hdsim.errors import InputError, unknown_name

DISTS = ("unif", "logunif", "norm")
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


@dataclass(frozen=True)
class Wording:
    """How a study's messages name its options: as the command line (``--n``) or the Python
    API (``n``, of `hdsim.sobol`, `hdsim.sensitivity.run_study`) spells them. Templates take
    ``{name}`` (and ``{text}``)."""

    bounds: str     # the bounds option, e.g. "--bounds"
    dists: str      # the distributions option
    range: str      # the range option, with how a value looks
    bounds_of: str  # explicit bounds of one parameter
    dist_of: str    # a distribution of one parameter, ``{text}`` its value
    python: bool    # True: bounds are (low, high) pairs, checked with the API's wording
    # the study's other options (`hdsim.sensitivity.design.check_sizes`, `open_executor`,
    # `run_study`, `open_store`)
    n: str = "--n"
    replicates: str = "--replicates"
    workers: str = "--workers"
    executor: str = "--executor"
    target_width: str = "--target-width"
    out: str = "--out"
    resume: str = "--resume"            # as it is switched on
    retry: str = "--resume --retry-failed"
    retry_failed: str = "--retry-failed"
    second_order: str = "--second-order"
    chunksize: str = "--chunksize"
    output_of: str = "--output {name}"      # the output studied, ``{name}`` a metric
    scenario_of: str = "--scenario {name}"  # a scenario named, ``{name}`` a built-in name or a file

    def given(self, option: str, value) -> str:
        """An option with the value it was given: ``--n 8`` or ``n=8``."""
        return f"{option}={value!r}" if self.python else f"{option} {value}"


CLI_WORDING = Wording("--bounds", "--dist", "--range P%", "--bounds {name}=LO:HI", "--dist {name}={text}", False)
PYTHON_WORDING = Wording("bounds", "dists", "range=FRACTION", "bounds={{'{name}': (low, high)}}",
                         "dists={{'{name}': '{text}'}}", True, n="n", replicates="replicates",
                         workers="workers", executor="executor", target_width="target_width", out="out",
                         resume="resume=True", retry="resume=True, retry_failed=True",
                         retry_failed="retry_failed=True", second_order="second_order=True", chunksize="chunksize",
                         output_of="output='{name}'", scenario_of="scenario='{name}'")


@dataclass(frozen=True)
class Problem:
    """Names, bounds (or ``[mean, sd]`` for ``norm``) and distributions of the inputs."""

    names: tuple[str, ...]
    bounds: tuple[tuple[float, float], ...]
    dists: tuple[str, ...]

    def __post_init__(self):
        if not self.names:
            raise InputError("a Sobol study needs at least one parameter")
        if len(set(self.names)) != len(self.names):
            raise InputError(f"duplicate parameter names in {', '.join(self.names)}")
        if not len(self.names) == len(self.bounds) == len(self.dists):
            raise InputError("names, bounds and dists must have the same length")
        for name, (lo, hi), dist in zip(self.names, self.bounds, self.dists):
            _check_one(name, lo, hi, dist)

    @property
    def num_vars(self) -> int:
        return len(self.names)

    def to_salib(self) -> dict:
        """The problem dictionary SALib's sampler and analyser take."""
        return {
            "num_vars": self.num_vars,
            "names": list(self.names),
            "bounds": [list(b) for b in self.bounds],
            "dists": list(self.dists),
        }

    def to_dict(self) -> dict:
        """JSON-friendly form, stored in the study file and compared on resume."""
        return {"names": list(self.names), "bounds": [list(b) for b in self.bounds],
                "dists": list(self.dists)}

    @classmethod
    def from_dict(cls, d: dict) -> "Problem":
        return cls(tuple(d["names"]), tuple(tuple(float(v) for v in b) for b in d["bounds"]),
                   tuple(d["dists"]))

    def variances(self) -> np.ndarray:
        """Variance of each input under its distribution [unit of the input squared]."""
        return np.array([input_variance(d, lo, hi)
                         for (lo, hi), d in zip(self.bounds, self.dists)])


def uniform(names, bounds) -> Problem:
    """A problem with every input uniform on its ``(lo, hi)``.

    Parameters
    ----------
    names : sequence of str
        Input names.
    bounds : sequence of (float, float)
        Lower and upper bound of each input [its unit].

    Returns
    -------
    Problem
        The problem.
    """
    return Problem(tuple(names), tuple((float(lo), float(hi)) for lo, hi in bounds),
                   ("unif",) * len(names))


def _check_one(name, lo, hi, dist):
    if dist not in DISTS:
        raise unknown_name("distribution", dist, DISTS)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise InputError(f"bounds of '{name}' must be finite numbers, got {lo}:{hi}")
    if dist == "norm":
        if hi <= 0:
            raise InputError(f"normal '{name}' needs a standard deviation > 0, got {hi}")
    elif not lo < hi:
        raise InputError(f"bounds of '{name}' must have lo < hi, got {lo}:{hi}")
    elif dist == "logunif" and lo <= 0:
        raise InputError(f"log-uniform '{name}' needs bounds > 0, got {lo}:{hi}")


def input_variance(dist: str, a: float, b: float) -> float:
    """Variance of one input under its distribution.

    Parameters
    ----------
    dist : str
        ``'unif'``, ``'logunif'`` or ``'norm'``.
    a, b : float
        Bounds, or mean and standard deviation for ``norm`` [unit of the input].

    Returns
    -------
    float
        Variance [unit of the input squared].

    Raises
    ------
    InputError
        On an unknown distribution.
    """
    if dist == "unif":
        return (b - a) ** 2 / 12.0
    if dist == "norm":
        return b**2
    if dist == "logunif":  # x = exp(u), u ~ U(ln a, ln b)
        L = math.log(b / a)
        m1, m2 = (b - a) / L, (b**2 - a**2) / (2 * L)
        return m2 - m1**2
    raise unknown_name("distribution", dist, DISTS)


def parse_range(text: str) -> float:
    """``'10%'`` -> 0.10: the half-width of the interval as a fraction of nominal."""
    m = re.fullmatch(rf"\s*({_NUMBER})\s*%\s*", text or "")
    if not m:
        raise InputError(f"--range must look like '10%', got '{text}'")
    frac = float(m.group(1)) / 100.0
    if not 0 < frac < 10:
        raise InputError(f"--range must be between 0% and 1000% (exclusive), got '{text}'")
    return frac


def parse_assignments(items, option: str) -> dict[str, str]:
    """``['a=1:2', 'b=3:4']`` -> ``{'a': '1:2', 'b': '3:4'}`` (one line error otherwise: a
    malformed item, or a name given twice, whose last value had won without a word)."""
    out = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise InputError(f"{option} expects NAME=VALUE, got '{item}'")
        name = name.strip()
        if name in out:
            raise InputError(f"{option} {name} is given twice ({out[name]} and {value.strip()}); give it once")
        out[name] = value.strip()
    return out


def parse_bounds(text: str, name: str) -> tuple[float, float]:
    """``'0.5e-3:0.7e-3'`` -> ``(0.0005, 0.0007)`` (the command line's ``--bounds NAME=LO:HI``)."""
    m = re.fullmatch(rf"({_NUMBER}):({_NUMBER})", text.replace(" ", ""))
    if not m:
        raise InputError(f"--bounds {name}= expects LO:HI (two numbers), got '{text}'")
    return float(m.group(1)), float(m.group(2))


def parse_bounds_options(items) -> dict[str, tuple[float, float]]:
    """``['a=1:2', 'b=3:4']`` -> ``{'a': (1.0, 2.0), 'b': (3.0, 4.0)}``: ``--bounds`` as typed bounds."""
    return {name: parse_bounds(text, name) for name, text in parse_assignments(items, "--bounds").items()}


def bounds_pair(name: str, value) -> tuple[float, float]:
    """Typed bounds of one parameter: two finite numbers ``(low, high)`` with low < high.

    Parameters
    ----------
    name : str
        The parameter, for the message.
    value : sequence of two numbers
        ``(low, high)`` [SI unit of the parameter]; a tuple, list or array.

    Returns
    -------
    tuple of float
        ``(low, high)``.

    Raises
    ------
    InputError
        ``bounds for 'NAME' must be (low, high) with low < high, got …`` for text, a
        boolean, a count other than two, a non-finite number or low >= high.
    """
    bad = InputError(f"bounds for '{name}' must be (low, high) with low < high, got {value!r}")
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise bad
    items = list(value)
    if len(items) != 2 or any(isinstance(v, (bool, np.bool_, str, bytes)) for v in items):
        raise bad
    try:
        lo, hi = (float(v) for v in items)
    except (TypeError, ValueError):
        raise bad from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise bad
    return lo, hi


def build_problem(names, nominal=None, range_frac=None, bounds=None, dists=None,
                  wording: Wording = CLI_WORDING) -> Problem:
    """Build a `Problem` from nominal values, a range, explicit bounds and distributions.

    Parameters
    ----------
    names : list of str
        Parameter names, in study order.
    nominal : dict, optional
        Name -> nominal value (in the parameter's SI unit).
    range_frac : float, optional
        Half-width as a fraction of ``|nominal|`` (``0.1`` for ``--range 10%``). For a
        ``norm`` input without explicit numbers it is the standard deviation instead.
    bounds : dict, optional
        Name -> ``(low, high)`` [SI]; overrides the range for that parameter. ``'LO:HI'``
        text is read as ``--bounds`` reads it.
    dists : dict, optional
        Name -> ``'unif'``, ``'logunif'``, ``'norm'`` or ``'norm:MEAN:SD'``.
    wording : Wording
        How messages name the options (`CLI_WORDING`, `PYTHON_WORDING`); with
        `PYTHON_WORDING` every pair is checked by `bounds_pair`.

    Returns
    -------
    Problem
        Bounds in the parameters' SI units.

    Raises
    ------
    InputError
        On an option naming a parameter the study does not vary, an unknown distribution,
        unreadable bounds, or a parameter with neither bounds nor a usable nominal and range.
    """
    names = list(names)
    nominal, bounds, dists = dict(nominal or {}), dict(bounds or {}), dict(dists or {})
    for option, given in ((wording.bounds, bounds), (wording.dists, dists)):
        for name in given:
            if name not in names:
                raise _not_studied(name, option, names, wording)
    out_bounds, out_dists = [], []
    for name in names:
        dist, explicit = _parse_dist(dists.get(name, "unif"), name, wording)
        if explicit is not None and name in bounds:  # the bounds would be dropped without a word
            raise InputError(f"'{name}' is given both {wording.dist_of.format(name=name, text='norm:MEAN:SD')} and "
                             f"{wording.bounds}: a normal input has no bounds; give one of them")
        if explicit is None and name in bounds:
            if dist == "norm":  # LO:HI would silently become MEAN:SD in SALib
                raise InputError(f"'{name}' is normal: give {wording.dist_of.format(name=name, text='norm:MEAN:SD')} "
                                 f"instead of {wording.bounds}")
            explicit = _explicit(name, bounds[name], wording)
        if explicit is None:
            explicit = _from_range(name, nominal, range_frac, dist, wording)
        out_bounds.append(explicit)
        out_dists.append(dist)
    return Problem(tuple(names), tuple(out_bounds), tuple(out_dists))


def _not_studied(name, option, names, wording) -> InputError:
    if wording.python:
        return InputError(f"unknown parameter '{name}' in {option}: the study varies {', '.join(names)}")
    return unknown_name(f"parameter in {option}", name, names)


def _explicit(name, value, wording) -> tuple[float, float]:
    """One parameter's explicit bounds: text as ``--bounds`` reads it, a pair as given
    (the API's pairs checked here; the command line's by `Problem` with its wording)."""
    if isinstance(value, str) and not wording.python:
        return parse_bounds(value, name)
    if wording.python:
        return bounds_pair(name, value)
    lo, hi = value
    return float(lo), float(hi)


def _parse_dist(text: str, name: str, wording: Wording = CLI_WORDING):
    if not isinstance(text, str):
        raise InputError(f"{wording.dist_of.format(name=name, text=text)}: a distribution is one of "
                         f"{', '.join(DISTS)} (or norm:MEAN:SD)")
    kind, _, rest = text.partition(":")
    if kind not in DISTS:
        raise unknown_name(f"distribution for '{name}'", kind, DISTS)
    if not rest:
        return kind, None
    if kind != "norm":
        raise InputError(f"{wording.dist_of.format(name=name, text=text)}: only 'norm' takes numbers "
                         "(norm:MEAN:SD)")
    m = re.fullmatch(rf"({_NUMBER}):({_NUMBER})", rest.replace(" ", ""))
    if not m:
        raise InputError(f"{wording.dist_of.format(name=name, text=text)}: expects norm:MEAN:SD (two numbers)")
    return kind, (float(m.group(1)), float(m.group(2)))


def _from_range(name, nominal, frac, dist, wording: Wording = CLI_WORDING):
    give = wording.bounds_of.format(name=name)
    if frac is None:
        raise InputError(f"no bounds for '{name}': give {wording.range} or {give}")
    if name not in nominal:
        raise InputError(f"no nominal value for '{name}' to apply {wording.range} to; give {give}")
    x0 = float(nominal[name])
    if x0 == 0 or not math.isfinite(x0):
        raise InputError(f"'{name}' has nominal {x0}: a ±% range needs a finite non-zero "
                         f"nominal; give {give}")
    if dist == "norm":
        return x0, abs(x0) * frac  # one standard deviation = the range
    lo, hi = sorted((x0 * (1 - frac), x0 * (1 + frac)))
    return lo, hi
