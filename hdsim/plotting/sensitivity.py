"""Figures of a Sobol' study: index bars with both intervals, and convergence in N.

Each function draws a new `matplotlib.figure.Figure` without pyplot and writes it with
`hdsim.plotting.save_figure` (see `hdsim.plotting`).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from hdsim.plotting import save_figure


def plot_indices(path, names, analysis: dict, analytic: dict | None = None,
                 title: str = "") -> Path:
    """Bars of S1 and ST with replicate (thick) and bootstrap (thin) intervals.

    Like Figure 7 of the seed paper (references in docs/physics.md), plus the error
    bars it lacked; with ``analytic`` the exact values are drawn as black ticks.

    Parameters
    ----------
    path : str or os.PathLike
        Figure file; the suffix gives the format.
    names : list of str
        Parameter names, one bar pair each.
    analysis : dict
        ``S1``, ``ST`` [-] and their half widths ``S1_conf``, ``ST_conf`` (bootstrap)
        and ``S1_conf_replicates``, ``ST_conf_replicates`` (replicates), one value per
        name.
    analytic : dict, optional
        Exact ``S1`` and ``ST`` [-], one value per name.
    title : str
        Figure title; empty for the default.

    Returns
    -------
    pathlib.Path
        The written file.
    """
    x, w = np.arange(len(names)), 0.38
    fig = Figure(figsize=(max(5.0, 0.9 * len(names) + 2.5), 3.6))
    ax = fig.add_subplot()
    for shift, key, colour, label in ((-w / 2, "S1", "tab:blue", "first order S1"),
                                      (w / 2, "ST", "tab:orange", "total ST")):
        ax.bar(x + shift, analysis[key], w, color=colour, alpha=0.8, label=label)
        # the two intervals in the legend, not only in the default title: a study's own
        # title (the command's: output and N) replaces it
        first = key == "S1"
        ax.errorbar(x + shift, analysis[key], yerr=analysis[f"{key}_conf"], fmt="none",
                    ecolor="0.45", elinewidth=0.8, capsize=5, label="bootstrap 95 % CI" if first else None)
        ax.errorbar(x + shift, analysis[key], yerr=analysis[f"{key}_conf_replicates"],
                    fmt="none", ecolor="k", elinewidth=2.2, capsize=0, label="replicate 95 % CI" if first else None)
        if analytic is not None:
            ax.scatter(x + shift, analytic[key], marker="_", s=300, color="k", zorder=3,
                       label="analytic" if key == "S1" else None)
    ax.set_xticks(x, names)
    ax.set_ylabel("Sobol' index [-]")
    ax.axhline(0, color="0.3", lw=0.6)
    ax.set_title(title or "Sobol' indices (thick: replicate 95 % CI, thin: SALib bootstrap)",
                 fontsize=9)
    ax.legend(fontsize=8, frameon=False)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_convergence(path, names, rows: list[dict], target_width: float | None = None,
                     analytic: dict | None = None) -> Path:
    """Indices (top) and interval full widths (bottom) against N, one figure.

    Parameters
    ----------
    path : str or os.PathLike
        Figure file; the suffix gives the format.
    names : list of str
        Parameter names.
    rows : list of dict
        One analysis per base sample size: ``n``, ``S1``, ``ST`` [-] and their
        half widths ``*_conf`` (bootstrap) and ``*_conf_replicates``.
    target_width : float, optional
        Full interval width the study aims for [-], drawn as a line.
    analytic : dict, optional
        Exact ``S1`` and ``ST`` [-], drawn as dotted lines.

    Returns
    -------
    pathlib.Path
        The written file.
    """
    n = np.array([r["n"] for r in rows])
    fig = Figure(figsize=(6.4, 6.0))
    top, bottom = fig.subplots(2, 1, sharex=True)
    colours = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, name in enumerate(names):
        c = colours[i % len(colours)]
        for key, style in (("S1", "--"), ("ST", "-")):
            est = np.array([r[key][i] for r in rows])
            half = np.array([r[f"{key}_conf_replicates"][i] for r in rows])
            top.plot(n, est, style, color=c, marker=".", label=f"{key} {name}")
            top.fill_between(n, est - half, est + half, color=c, alpha=0.12)
            if analytic is not None:
                top.axhline(analytic[key][i], color=c, lw=0.6, ls=":")
        bottom.plot(n, [2 * r["ST_conf_replicates"][i] for r in rows], "-", color=c,
                    marker=".", label=f"ST {name} (replicates)")
        bottom.plot(n, [2 * r["ST_conf"][i] for r in rows], ":", color=c)
    if target_width:
        bottom.axhline(target_width, color="k", lw=1, ls="-.", label="target width")
    # Early, tiny-N bands can span ±3; keep the axis on the range indices live in.
    top.set_ylim(-0.25, 1.1)
    top.set_ylabel("index [-]")
    top.set_title("S1 dashed, ST solid; bands: replicate 95 % CI", fontsize=9)
    top.legend(fontsize=6, ncol=2, frameon=False)
    bottom.set_xscale("log", base=2)
    bottom.set_yscale("log")
    bottom.set_xlabel("base points N")
    bottom.set_ylabel("95 % CI full width [-]")
    bottom.set_title("ST interval width: solid replicates, dotted SALib bootstrap", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)
