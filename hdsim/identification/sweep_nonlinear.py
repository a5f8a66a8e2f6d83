"""The non-linear parameters of a sweep's law (the Stribeck speed): refined between grid
points, and given their share of the fit's covariance.

The law is linear in its amplitudes once each family's non-linear parameter is fixed
(`hdsim.model.running_terms`), so `hdsim.identification.running_fit.fit_running` solves
the amplitudes on a short log-spaced grid of it. The grid's steps are wide (a factor of
1.7): the nearest point can lie many standard deviations from the best value, and an
amplitude that trades off against it (the Stribeck rise, and so the starting torque) is
then biased by as much. And a covariance of the amplitudes alone takes the non-linear
parameter as known. Here the best grid point is refined by a bounded scalar search in
``ln ω`` between its neighbours, and the covariance is that of the amplitudes and ``ln ω``
together: the model's derivative in ``ln ω`` at the optimum is one more column of the
Jacobian (Gauss–Newton at the least-squares point), so the amplitudes' variances include
what the record leaves of ``ω``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["refine_nonlinear", "nonlinear_columns", "LOG_STEP", "REFINE_TOLERANCE"]

#: relative step of the central difference in ln ω of the Jacobian column
LOG_STEP = 1e-4
#: the search in ln ω stops within this (0.1 % of ω: far below any record's uncertainty of it)
REFINE_TOLERANCE = 1e-3


def refine_nonlinear(solve, grids: dict, best: tuple) -> tuple:
    """The grid's best solution refined, one non-linear parameter at a time.

    Parameters
    ----------
    solve : callable
        ``solve(nonlinear) -> (rss, …)``: the amplitudes solved with the non-linear values
        ``nonlinear`` (family -> value); its first item is the residual sum of squares.
    grids : dict
        Family -> the grid of its non-linear parameter (increasing).
    best : tuple
        ``solve``'s result at the best grid point; its second item is that point's
        ``nonlinear`` dict.

    Returns
    -------
    tuple
        ``solve``'s result at the refined values, never worse than ``best``: each family's
        value searched (bounded, in ln ω) between the grid's neighbours of the current one.
    """
    from scipy.optimize import minimize_scalar  # imported with lsq_linear already

    for family, grid in grids.items():
        values = np.log(np.asarray(grid, dtype=float))
        i = int(np.argmin(np.abs(values - math.log(best[1][family]))))
        low, high = values[max(i - 1, 0)], values[min(i + 1, values.size - 1)]
        if high <= low:
            continue
        fixed, kept = dict(best[1]), []

        def cost(log_value, fixed=fixed, family=family, kept=kept):
            # only the best trial is kept (each holds its design matrix): the search's answer is
            # the point where its best cost was last updated, so `<=` keeps that trial
            trial = solve({**fixed, family: math.exp(log_value)})
            if not kept or trial[0] <= kept[0][0]:
                kept[:] = [trial]
            return trial[0]

        minimize_scalar(cost, bounds=(low, high), method="bounded", options={"xatol": REFINE_TOLERANCE})
        if kept[0][0] < best[0]:
            best = kept[0]
    return best


def nonlinear_columns(design, nonlinear: dict, x: np.ndarray) -> np.ndarray:
    """The model's derivative in ``ln ω`` of each family's non-linear parameter at the
    amplitudes ``x``: one column per family, in the order of ``nonlinear`` (central
    differences of ``design(nonlinear) @ x``; ``design`` gives the full design matrix)."""
    cols = []
    for family, value in nonlinear.items():
        up = design({**nonlinear, family: value * math.exp(LOG_STEP)})
        down = design({**nonlinear, family: value * math.exp(-LOG_STEP)})
        cols.append((up - down) @ x / (2.0 * LOG_STEP))
    return np.column_stack(cols) if cols else np.zeros((0, 0))
