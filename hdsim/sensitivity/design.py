"""The Saltelli/Sobol' design: sampling, replicate seeds and the structure check.

Layout of one *block* (one base point of the Sobol' sequence), as
`SALib.sample.sobol.sample` writes it::

    A, AB_1 … AB_D, [BA_1 … BA_D,] B        (D + 2 or 2D + 2 rows)

A study is ``R`` independent replicates, each a scrambled design of ``N / R`` base
points with its own seed derived from the base seed. Rows are numbered
replicate-major: row ``g`` is row ``g % M`` of replicate ``g // M``, where
``M = (N / R) * block_size``. The analyser never trusts row order alone: every block
is checked here, and every output carries a fingerprint of the inputs it was
computed from (`fingerprint`).
"""

from __future__ import annotations

import warnings

import numpy as np

from hdsim.errors import InputError
from hdsim.sensitivity.problem import PYTHON_WORDING, Wording


class DesignError(InputError):
    """The samples or outputs do not have the A/AB/BA/B structure the estimator needs."""


def block_size(num_vars: int, second_order: bool) -> int:
    """Rows per base point: ``D + 2``, or ``2D + 2`` with second order."""
    return 2 * num_vars + 2 if second_order else num_vars + 2


def is_power_of_two(n: int) -> bool:
    return (isinstance(n, (int, np.integer)) and not isinstance(n, bool)) and n > 0 and (n & (n - 1)) == 0


def check_sizes(n: int, replicates: int, wording: Wording = PYTHON_WORDING) -> int:
    """Validate the base points N and the replicates R of a study.

    Parameters
    ----------
    n : int
        Base points N; a power of 2, at least 4 per replicate.
    replicates : int
        Replicates R; a power of 2, at least 2.
    wording : Wording
        How the messages name the options: ``n`` and ``replicates`` (the Python API,
        default) or ``--n`` and ``--replicates`` (`CLI_WORDING`).

    Returns
    -------
    int
        Base points per replicate, ``N / R``.

    Raises
    ------
    InputError
        On an N or R that breaks these rules; for N, with the nearest N that is valid with R.
    """
    if not is_power_of_two(replicates) or replicates < 2:
        raise InputError(f"{wording.replicates} must be a power of 2 and at least 2, got {replicates!r}")
    if not is_power_of_two(n):
        raise InputError(f"{wording.n} must be a power of 2 (Sobol' balance), got {n!r}; "
                         f"nearest: {nearest_valid_n(n, replicates)}")
    if n < 4 * replicates:
        raise InputError(f"{wording.given(wording.n, n)} is too small for "
                         f"{wording.given(wording.replicates, replicates)}: "
                         f"need {wording.n} >= {4 * replicates} (4 base points per replicate)")
    return n // replicates


def nearest_valid_n(n, replicates: int = 4) -> int:
    """The power of 2 nearest ``n`` (on a log scale) that `check_sizes` accepts with
    ``replicates``: at least 4 base points per replicate."""
    try:
        n = max(float(n), 1.0)
    except (TypeError, ValueError):
        n = 1024.0
    if not np.isfinite(n):
        n = 1024.0
    return max(1 << max(0, round(np.log2(n))), 4 * replicates)


def replicate_seed(seed: int, replicate: int) -> int:
    """Scramble seed of one replicate, derived from the study seed.

    ``SeedSequence`` spawning gives statistically independent streams for every
    ``(seed, replicate)``, and is the same on every machine and executor.
    """
    ss = np.random.SeedSequence(int(seed), spawn_key=(int(replicate),))
    return int(ss.generate_state(1, dtype=np.uint32)[0])


def sample_replicate(problem, n_base: int, seed: int, second_order: bool,
                     start: int = 0) -> np.ndarray:
    """Scaled design rows of base points ``start … start + n_base - 1`` of one replicate.

    SALib's design is extensible: with the same seed, the ``n_base`` design is the
    first rows of the ``2 * n_base`` design, so doubling N reuses every earlier run.
    A slice (``start > 0``) uses SALib's ``skip_values``, which fast-forwards the same
    scrambled sequence; the store builds big designs piece by piece this way, so
    memory does not grow with N (tests check pieces == whole).

    Parameters
    ----------
    problem : Problem
        The study inputs.
    n_base : int
        Base points to generate.
    seed : int
        Scramble seed of the replicate (`replicate_seed`).
    second_order : bool
        Add the BA rows that second-order indices need.
    start : int
        First base point.

    Returns
    -------
    numpy.ndarray
        ``(n_base * k, D)`` rows in the inputs' own units, ``k`` from `block_size`.
    """
    from SALib.sample import sobol

    with warnings.catch_warnings():
        # SALib warns when skip_values is not a power of 2 or is below N: advice for
        # users who skip points as a design choice. Here it only cuts the very same
        # sequence into pieces, so those warnings (and scipy's balance note) are moot.
        warnings.filterwarnings("ignore", message="(?s).*(balance properties|skip_values|"
                                "Convergence).*")
        return sobol.sample(problem.to_salib(), int(n_base), calc_second_order=second_order,
                            scramble=True, seed=int(seed), skip_values=int(start))


def fingerprint(X: np.ndarray) -> np.ndarray:
    """A 64-bit hash of every row's exact bytes (FNV-1a style, vectorised).

    Workers return it with each output, computed from the inputs the model actually
    received; the analyser compares it with the design row the output is filed
    under. Any mix-up of outputs and rows (completion order, shifted chunks) is then
    caught, whatever the model.
    """
    X = np.ascontiguousarray(np.atleast_2d(X), dtype=np.float64)
    u = X.view(np.uint64)
    h = np.full(len(X), 0xCBF29CE484222325, dtype=np.uint64)
    prime = np.uint64(0x100000001B3)
    with np.errstate(over="ignore"):
        for j in range(u.shape[1]):
            h ^= u[:, j]
            h *= prime
            h ^= h >> np.uint64(29)
    return h


def check_design(X: np.ndarray, num_vars: int, second_order: bool) -> None:
    """Raise `DesignError` unless every block has the Saltelli structure.

    AB_i must equal A in every column except i and equal B in column i; BA_i the
    reverse. Scaling is column-wise and deterministic, so exact equality holds.

    Parameters
    ----------
    X : numpy.ndarray
        Design ``(n * k, D)``.
    num_vars : int
        Number of inputs D.
    second_order : bool
        Whether the blocks hold BA rows.

    Raises
    ------
    DesignError
        On a wrong shape or the first row that breaks the structure.
    """
    D, k = num_vars, block_size(num_vars, second_order)
    X = np.asarray(X)
    if X.ndim != 2 or X.shape[1] != D or len(X) % k:
        raise DesignError(f"design has shape {X.shape}; expected (n * {k}, {D}) "
                          f"for {D} parameters{' with second order' if second_order else ''}")
    blocks = X.reshape(-1, k, D)
    A, B = blocks[:, 0, :], blocks[:, k - 1, :]
    eye = np.eye(D, dtype=bool)
    expect_ab = np.where(eye[None], B[:, None, :], A[:, None, :])  # (nb, D, D)
    _compare(blocks[:, 1:D + 1, :], expect_ab, k, offset=1, label="AB")
    if second_order:
        expect_ba = np.where(eye[None], A[:, None, :], B[:, None, :])
        _compare(blocks[:, D + 1:2 * D + 1, :], expect_ba, k, offset=D + 1, label="BA")


def _compare(got, expect, k, offset, label):
    bad = ~((got == expect) | (np.isnan(got) & np.isnan(expect)))
    if bad.any():
        b, i, j = map(int, np.argwhere(bad)[0])
        raise DesignError(
            f"design row {b * k + offset + i} ({label}_{i + 1} of block {b}) differs from "
            f"its A/B rows in column {j}: not a Saltelli design (was X altered or mixed up?)")


def check_keys(X: np.ndarray, keys: np.ndarray, done: np.ndarray) -> None:
    """Raise `DesignError` if an output was computed for other inputs than its row.

    Parameters
    ----------
    X : numpy.ndarray
        Design rows.
    keys : numpy.ndarray of uint64
        Fingerprints returned with the outputs (`fingerprint` of what each worker saw).
    done : numpy.ndarray of bool
        Rows whose output is on record (only those are compared).

    Raises
    ------
    DesignError
        Naming how many outputs are misfiled and the first row.
    """
    done = np.asarray(done, dtype=bool)
    mismatch = done & (fingerprint(X) != np.asarray(keys, dtype=np.uint64))
    if mismatch.any():
        rows = np.flatnonzero(mismatch)
        raise DesignError(
            f"{len(rows)} outputs are filed under rows whose inputs they were not computed "
            f"from (first: row {rows[0]}); outputs must be matched to rows by index, "
            f"never by completion order")


def valid_blocks(ok: np.ndarray, k: int) -> np.ndarray:
    """Boolean per block: True when all its ``k`` rows have a good output."""
    return np.asarray(ok, dtype=bool).reshape(-1, k).all(axis=1)


def first_order_view(Y: np.ndarray, num_vars: int, second_order: bool) -> np.ndarray:
    """Drop the BA rows of every block, giving the ``D + 2`` layout (for S1/ST only)."""
    if not second_order:
        return Y
    D = num_vars
    blocks = np.asarray(Y).reshape(-1, 2 * D + 2)
    return np.concatenate([blocks[:, :D + 1], blocks[:, -1:]], axis=1).reshape(-1)
