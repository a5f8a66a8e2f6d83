"""Sobol' indices from a checked design: SALib's estimate and bootstrap, plus replicates.

Two interval kinds are reported, both as half-widths at ``conf_level``:

``*_conf``
    SALib's row bootstrap on the pooled design: the arithmetic of
    ``SALib.analyze.sobol.analyze`` (its estimator functions, its resampling), run
    in bounded-memory batches (`salib_indices`). An iid bootstrap ignores the
    variance reduction of scrambled Sobol' points and is typically 3–6× too wide;
    kept because it is what SALib users know and compare against.
``*_conf_replicates``
    Student-t interval across the ``R`` independently scrambled replicates (each of
    ``N / R`` base points): the honest randomised-QMC error bar.

The point estimate is SALib's on all valid blocks pooled.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy import special

from hdsim.errors import InputError
from hdsim.sensitivity.design import (block_size, check_design, check_keys,
                                      first_order_view, replicate_seed, valid_blocks)

_EPS = np.finfo(float).eps


def estimates(blocks: np.ndarray, num_vars: int, second_order: bool) -> dict:
    """S1 (Saltelli 2010), ST (Jansen) and S2 (Saltelli 2002) from complete blocks.

    Same arithmetic as SALib 1.6 (output standardised first, variance of A ∪ B), so
    on the same rows it reproduces SALib's point estimates exactly.

    Parameters
    ----------
    blocks : numpy.ndarray
        Outputs ``(nb, k)``, one row per base point in the A, AB, [BA,] B layout.
    num_vars : int
        Number of inputs D.
    second_order : bool
        Whether the blocks hold BA rows (then S2 is estimated).

    Returns
    -------
    dict
        ``S1``, ``ST`` (D,) [-] and ``S2`` (D, D), upper triangle, or None [-].
    """
    D = num_vars
    Y = np.asarray(blocks, dtype=float)
    Y = (Y - Y.mean()) / (Y.std() or 1.0)
    A, B, AB = Y[:, 0], Y[:, -1], Y[:, 1:D + 1]
    var = np.var(np.r_[A, B])
    if var <= _EPS:  # constant output: nothing to apportion
        zero = np.zeros(D)
        return {"S1": zero, "ST": zero.copy(), "S2": np.zeros((D, D)) if second_order else None}
    S1 = np.mean(B[:, None] * (AB - A[:, None]), axis=0) / var
    ST = 0.5 * np.mean((A[:, None] - AB) ** 2, axis=0) / var
    S2 = None
    if second_order:
        BA = Y[:, D + 1:2 * D + 1]
        Vjk = (BA.T @ AB / len(Y) - np.mean(A * B)) / var  # Vjk[j, k] uses BA_j, AB_k
        S2 = np.triu(Vjk - S1[:, None] - S1[None, :], 1)
    return {"S1": S1, "ST": ST, "S2": S2}


def analyse(problem, X, Y, *, second_order: bool, replicates: int, key=None, evaluated=None,
            conf_level: float = 0.95, num_resamples: int = 100, seed: int = 0) -> dict:
    """Check the design, drop failed blocks and estimate the indices.

    Parameters
    ----------
    problem : Problem
        The study inputs.
    X : numpy.ndarray
        Design ``(R * M, D)`` in replicate-major row order.
    Y : numpy.ndarray
        Outputs ``(R * M,)``, row for row with ``X``.
    second_order : bool
        Whether the design holds BA rows.
    replicates : int
        Independently scrambled replicates R.
    key : ndarray of uint64, optional
        Fingerprints returned with the outputs; compared with ``X`` row by row.
    evaluated : ndarray of bool, optional
        Rows that have been evaluated (those whose key is checked).
    conf_level : float
        Confidence level of both interval kinds [-].
    num_resamples : int
        Bootstrap resamples of the SALib interval.
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    dict
        Arrays ``S1, S1_conf, ST, ST_conf, S1_conf_replicates, ST_conf_replicates``
        (and ``S2*`` with second order) [-], ``replicates`` (per-replicate S1/ST),
        ``blocks_used``, ``blocks_dropped``.

    Raises
    ------
    DesignError
        On a design without the Saltelli structure or an output filed under another row.
    InputError
        On mismatched sizes or too few successful blocks.
    """
    X, Y = np.asarray(X, dtype=float), np.asarray(Y, dtype=float)
    evaluated = np.isfinite(Y) if evaluated is None else np.asarray(evaluated, bool)
    check_outputs(problem, X, Y, second_order, key, evaluated)
    return indices(problem, Y, evaluated & np.isfinite(Y), second_order=second_order,
                   replicates=replicates, conf_level=conf_level,
                   num_resamples=num_resamples, seed=seed)


def check_outputs(problem, X, Y, second_order, key=None, evaluated=None) -> None:
    """The design check: block structure of ``X`` and the pairing of outputs with rows.

    Parameters
    ----------
    problem : Problem
        The study inputs.
    X : numpy.ndarray
        Design rows.
    Y : numpy.ndarray
        Outputs, row for row with ``X``.
    second_order : bool
        Whether the design holds BA rows.
    key : numpy.ndarray of uint64, optional
        Fingerprints returned with the outputs; with them every evaluated output must
        have been computed from its own row.
    evaluated : numpy.ndarray of bool, optional
        Rows whose key is checked; default: those with a finite output.

    Raises
    ------
    DesignError
        On a broken structure or a misfiled output.
    InputError
        When ``Y`` and ``X`` differ in length.
    """
    check_design(X, problem.num_vars, second_order)
    if len(Y) != len(X):
        raise InputError(f"{len(Y)} outputs for {len(X)} design rows")
    if key is not None:
        check_keys(X, key, np.isfinite(Y) if evaluated is None else evaluated)


def indices(problem, Y, ok, *, second_order: bool, replicates: int, conf_level=0.95,
            num_resamples=100, seed=0) -> dict:
    """Indices from outputs already checked against their design (see `analyse`).

    Parameters
    ----------
    problem : Problem
        The study inputs.
    Y : numpy.ndarray
        Outputs in replicate-major row order.
    ok : numpy.ndarray of bool
        Good rows; a block with any bad row is dropped whole.
    second_order : bool
        Whether the design holds BA rows.
    replicates : int
        Independently scrambled replicates R.
    conf_level : float
        Confidence level of both interval kinds [-].
    num_resamples : int
        Bootstrap resamples of the SALib interval.
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    dict
        As `analyse` returns.

    Raises
    ------
    InputError
        When ``Y`` does not split into replicates of whole blocks, or a replicate has
        fewer than two good blocks.
    """
    D, k, R = problem.num_vars, block_size(problem.num_vars, second_order), int(replicates)
    Y = np.asarray(Y, dtype=float)
    if len(Y) % (R * k):
        raise InputError(f"{len(Y)} outputs do not split into {R} replicates of "
                         f"{k}-row blocks")
    valid = valid_blocks(ok, k).reshape(R, -1)
    per_rep = Y.reshape(R, -1, k)
    if (valid.sum(axis=1) < 2).any():
        raise InputError("too few successful blocks to estimate indices "
                         f"({int(valid.sum())} of {valid.size}); see the failures above")
    pooled = np.concatenate([per_rep[r][valid[r]] for r in range(R)])
    out = salib_indices(problem, pooled.reshape(-1), second_order, conf_level, num_resamples,
                        seed)
    reps = [estimates(per_rep[r][valid[r]], D, second_order) for r in range(R)]
    for name in ("S1", "ST") + (("S2",) if second_order else ()):
        out[f"{name}_conf_replicates"] = t_halfwidth(np.stack([e[name] for e in reps]),
                                                     conf_level)
    out["replicates"] = {"S1": np.stack([e["S1"] for e in reps]),
                         "ST": np.stack([e["ST"] for e in reps])}
    out["blocks_used"], out["blocks_dropped"] = int(valid.sum()), int((~valid).sum())
    return out


def t_halfwidth(samples: np.ndarray, conf_level: float = 0.95) -> np.ndarray:
    """Half-width of the Student-t interval for the mean of ``samples`` (axis 0).

    Parameters
    ----------
    samples : numpy.ndarray
        One estimate per replicate along axis 0.
    conf_level : float
        Confidence level [-].

    Returns
    -------
    numpy.ndarray
        Half-width, in the unit of ``samples``.
    """
    R = len(samples)
    t = special.stdtrit(R - 1, 0.5 + conf_level / 2)  # Student's t quantile (scipy.stats.t.ppf's own)
    return t * np.std(samples, axis=0, ddof=1) / np.sqrt(R)


def bootstrap_seed(seed: int) -> int:
    # SALib only seeds its bootstrap when ``if seed:`` is true, so seed 0 would give
    # irreproducible intervals; derive a non-zero one instead.
    return replicate_seed(seed, 2**31 - 1) or 1


def salib_indices(problem, Y, second_order, conf_level, num_resamples, seed) -> dict:
    """SALib's Sobol' analysis (estimates and row bootstrap) in bounded memory.

    Does what ``SALib.analyze.sobol.analyze`` does — standardise Y, SALib's own
    ``first_order``/``total_order``/``second_order`` estimators, resample rows with
    ``default_rng(seed).integers(N, size=(N, B))``, half-width z·sd — but draws the
    ``B`` resamples in batches so memory does not grow with N × B. With
    ``N * B <= BOOT_ELEMENTS`` it is one batch and reproduces ``analyze`` exactly
    (tested); larger studies use a derived seed per batch.

    Parameters
    ----------
    problem : Problem
        The study inputs.
    Y : numpy.ndarray
        Outputs of complete blocks, pooled.
    second_order : bool
        Whether the blocks hold BA rows.
    conf_level : float
        Confidence level [-].
    num_resamples : int
        Bootstrap resamples B.
    seed : int
        Study seed (the bootstrap seed is derived from it).

    Returns
    -------
    dict
        ``S1``, ``ST``, ``S1_conf``, ``ST_conf`` (and ``S2``, ``S2_conf``) [-].
    """
    from SALib.analyze import sobol

    D = problem.num_vars
    k = block_size(D, second_order)
    Y = np.asarray(Y, dtype=float)
    Y = (Y - Y.mean()) / Y.std()
    N = len(Y) // k
    blocks = Y.reshape(N, k)
    A, B, AB = blocks[:, 0], blocks[:, -1], blocks[:, 1:D + 1]
    BA = blocks[:, D + 1:2 * D + 1] if second_order else None
    pairs = [(j, m) for j in range(D) for m in range(j + 1, D)] if second_order else []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # SALib's constant-output notices
        out = {}
        out["S1"] = np.array([sobol.first_order(A, AB[:, j], B) for j in range(D)])
        out["ST"] = np.array([sobol.total_order(A, AB[:, j], B) for j in range(D)])
        boot = {"S1": [], "ST": [], "S2": []}
        for r in _resample_batches(N, num_resamples, seed):
            boot["S1"].append(np.array([sobol.first_order(A[r], AB[r, j], B[r])
                                        for j in range(D)]).T)
            boot["ST"].append(np.array([sobol.total_order(A[r], AB[r, j], B[r])
                                        for j in range(D)]).T)
            if second_order:
                S2b = np.zeros((r.shape[1], D, D))
                for j, m in pairs:
                    S2b[:, j, m] = sobol.second_order(A[r], AB[r, j], AB[r, m], BA[r, j], B[r])
                boot["S2"].append(S2b)
    z = special.ndtri(0.5 + conf_level / 2)  # the normal quantile (scipy.stats.norm.ppf's own)
    constant = np.ptp(np.r_[A, B]) == 0.0  # SALib reports 0 rather than NaN then
    for name in ("S1", "ST") + (("S2",) if second_order else ()):
        samples = np.concatenate(boot[name])
        out[f"{name}_conf"] = np.zeros(samples.shape[1:]) if constant else \
            z * samples.std(axis=0, ddof=1)
    if second_order:
        S2 = np.zeros((D, D))
        for j, m in pairs:
            S2[j, m] = sobol.second_order(A, AB[:, j], AB[:, m], BA[:, j], B)
        out["S2"] = S2
    return out


BOOT_ELEMENTS = 2**18  # resample indices per batch (2 MiB of int64)


def _resample_batches(N, num_resamples, seed):
    """Yield index matrices ``(N, b)``; one SALib-identical batch when small enough."""
    per = max(2, BOOT_ELEMENTS // max(N, 1))
    if per >= num_resamples:
        yield np.random.default_rng(bootstrap_seed(seed)).integers(N, size=(N, num_resamples))
        return
    done, batch = 0, 0
    while done < num_resamples:
        b = min(per, num_resamples - done)
        rng = np.random.default_rng([bootstrap_seed(seed), batch])
        yield rng.integers(N, size=(N, b))
        done, batch = done + b, batch + 1


def convergence(problem, Y, *, second_order: bool, replicates: int, evaluated=None,
                conf_level: float = 0.95, num_resamples: int = 100, seed: int = 0,
                n_min: int | None = None) -> list[dict]:
    """Indices and both interval widths for every doubling of N up to the full study.

    The design is extensible, so the first ``n / R`` base points of every replicate
    *are* the study at ``n``: no extra evaluations. Only S1/ST are tracked (the BA
    rows of a second-order design are skipped).

    Parameters
    ----------
    problem : Problem
        The study inputs.
    Y : numpy.ndarray
        Outputs of the full study in replicate-major row order.
    second_order : bool
        Whether the design holds BA rows.
    replicates : int
        Independently scrambled replicates R.
    evaluated : numpy.ndarray of bool, optional
        Rows that have been evaluated; default: those with a finite output.
    conf_level : float
        Confidence level of both interval kinds [-].
    num_resamples : int
        Bootstrap resamples of the SALib interval.
    seed : int
        Seed of the bootstrap.
    n_min : int, optional
        Smallest N; default and floor ``4 R``.

    Returns
    -------
    list of dict
        One row per N with ``n``, ``S1``, ``ST``, ``S1_conf``, ``ST_conf``,
        ``S1_conf_replicates`` and ``ST_conf_replicates`` [-]; an N at which a
        replicate has fewer than two good blocks is left out.
    """
    D, R = problem.num_vars, int(replicates)
    k = block_size(D, second_order)
    Y = np.asarray(Y, dtype=float)
    ok = np.isfinite(Y) if evaluated is None else np.asarray(evaluated, bool) & np.isfinite(Y)
    n_full = len(Y) // k
    per_rep_blocks = n_full // R
    firsts = first_order_view(Y, D, second_order).reshape(R, per_rep_blocks, D + 2)
    good = valid_blocks(ok, k).reshape(R, per_rep_blocks)
    rows, n = [], max(n_min or 4 * R, 4 * R)
    while n <= n_full:
        m = n // R
        blocks = [firsts[r, :m][good[r, :m]] for r in range(R)]
        if min(len(b) for b in blocks) >= 2:
            res = salib_indices(problem, np.concatenate(blocks).reshape(-1), False, conf_level,
                         num_resamples, seed)
            reps = [estimates(b, D, False) for b in blocks]
            rows.append({"n": n, "S1": res["S1"], "ST": res["ST"],
                         "S1_conf": res["S1_conf"], "ST_conf": res["ST_conf"],
                         "S1_conf_replicates": t_halfwidth(np.stack([e["S1"] for e in reps]),
                                                           conf_level),
                         "ST_conf_replicates": t_halfwidth(np.stack([e["ST"] for e in reps]),
                                                           conf_level)})
        n *= 2
    return rows
