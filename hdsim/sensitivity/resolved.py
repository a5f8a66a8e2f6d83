"""Time- (or angle-) resolved Sobol' indices of a vector output.

For an output ``y(t)`` sampled on a fixed grid, each grid point is its own scalar
study on one shared Saltelli design: the same rows, one column of outputs per
point. The point estimates are SALib's (``analysis.estimates``) and the intervals
are the replicate t-intervals; the SALib bootstrap is left out here, since it
would be run once per grid point and the replicate interval is the honest one for
scrambled designs (docs/sensitivity.md, section 4).

Evaluated in memory, not through the resumable store: a resolved study is a
figure for a handful of parameters, not a long campaign.
"""

from __future__ import annotations

import numpy as np

from hdsim.sensitivity.analysis import estimates, t_halfwidth
from hdsim.sensitivity.design import block_size, check_design, check_sizes, replicate_seed, sample_replicate


def resolved_indices(func, problem, n: int, *, seed: int = 0, replicates: int = 4,
                     chunksize: int | None = None, conf_level: float = 0.95) -> dict:
    """S1 and ST at every point of a vector output.

    Parameters
    ----------
    func : callable
        ``f(X: (rows, D)) -> (rows, T)``, the output on a grid of ``T`` points.
    problem : Problem
        The study inputs.
    n : int
        Base points N (power of 2), split into ``replicates`` scrambles.
    seed : int
        Study seed; each replicate's scramble seed is derived from it.
    replicates : int
        Independently scrambled replicates R (power of 2, at least 2).
    chunksize : int, optional
        Rows per call of ``func``; default ``func.chunksize`` if it has one, else 1024.
    conf_level : float
        Confidence level of the replicate intervals [-].

    Returns
    -------
    dict
        ``S1``, ``ST`` (T, D) [-], their ``*_conf_replicates`` half-widths (T, D) [-],
        and ``variance`` (T,), the output variance at each point [output unit²].

    Raises
    ------
    InputError
        On a bad N or R.
    ValueError
        When ``func`` returns another number of rows than it was given.
    """
    check_sizes(n, replicates)
    D, k = problem.num_vars, block_size(problem.num_vars, False)
    designs = [sample_replicate(problem, n // replicates, replicate_seed(seed, r), False)
               for r in range(replicates)]
    for X in designs:
        check_design(X, D, False)
    X = np.concatenate(designs)
    size = int(chunksize or getattr(func, "chunksize", None) or 1024)
    Y = np.concatenate([np.atleast_2d(np.asarray(func(X[i:i + size]), dtype=float))
                        for i in range(0, len(X), size)])
    if Y.shape[0] != len(X):
        raise ValueError(f"model returned {Y.shape[0]} rows for {len(X)} design rows")
    blocks = Y.reshape(replicates, -1, k, Y.shape[1])          # (R, nb, k, T)
    T = Y.shape[1]
    out = {name: np.zeros((T, D)) for name in ("S1", "ST", "S1_conf_replicates", "ST_conf_replicates")}
    out["variance"] = np.var(Y[:, :], axis=0)
    for t in range(T):
        pooled = estimates(blocks[..., t].reshape(-1, k), D, False)
        per_rep = [estimates(blocks[r, :, :, t], D, False) for r in range(replicates)]
        for name in ("S1", "ST"):
            out[name][t] = pooled[name]
            out[f"{name}_conf_replicates"][t] = t_halfwidth(np.stack([e[name] for e in per_rep]),
                                                            conf_level)
    return out
