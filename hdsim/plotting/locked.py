"""Figures of a locked-wave-generator run.

Each function takes a `hdsim.scenarios.run.Run` (sample 0 of a batch) and returns a
`matplotlib.figure.Figure`, so notebooks and the CLI share one code path; `plot_loop`
draws into the axes it is given. No pyplot, no backend (see `hdsim.plotting`). Angles
are shown in arcmin, torques in N·m.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from hdsim.plotting import axes_for
from hdsim.units import rad_to_arcmin


def plot_loop(run, ax=None, window_fraction: float = 0.04, sample: int = 0):
    """Torque against twist (the hysteresis loop), loading and unloading in two colours.

    The ±``window_fraction`` T_N window is drawn as two dashed lines. An inset shows the
    twist less its straight-line fit against the torque: the loop opens there, where on
    the full scale the two branches lie on one line (a loop a tenth of an arcmin wide on
    a span of one).

    Parameters
    ----------
    run : hdsim.scenarios.run.Run
        A finished locked-wave-generator run.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; None makes a new figure.
    window_fraction : float
        The torque window as a fraction of T_N [-].
    sample : int
        Which sample of a batch run to draw.

    Returns
    -------
    matplotlib.figure.Figure
        The figure holding the axes.
    """
    fig, ax = axes_for(ax)
    torque = run.result.signal("torque_Nm", sample)
    twist = rad_to_arcmin(run.result.signal("twist_rad", sample))
    rated = float(np.asarray(run.model.drive.rated_torque).reshape(-1)[sample])
    loading = np.gradient(torque) >= 0
    for rows, colour, label in ((loading, "C0", "loading"), (~loading, "C3", "unloading")):
        ax.plot(np.where(rows, twist, np.nan), torque, lw=1.2, color=colour,
                label=f"{run.model.name}: {run.scenario.name}, {label}")
    window = window_fraction * rated
    for level in (-window, window):
        ax.axhline(level, color="C1", ls="--", lw=0.8, label=f"±{window_fraction:.0%} T_N" if level > 0 else None)
    if "lost_motion_arcmin" in run.metrics:
        ax.set_title(f"lost motion {run.metric('lost_motion_arcmin', sample):.3f} arcmin "
                     f"(±{window_fraction:.0%} T_N, full span)")
    elif "K1_Nm_per_rad" in run.metrics:
        # a segment the cycle does not load into is absent from the metrics
        ax.set_title(", ".join(f"{k} {run.metric(f'{k}_Nm_per_rad', sample):.3g}" for k in ("K1", "K2", "K3")
                               if f"{k}_Nm_per_rad" in run.metrics) + " N·m/rad")
    ax.axhline(0, color="0.6", lw=0.6)
    ax.axvline(0, color="0.6", lw=0.6)
    ax.set_xlabel("twist [arcmin]")
    ax.set_ylabel("output torque [N·m]")
    ax.legend(loc="upper left", fontsize="small")
    ax.grid(alpha=0.3)
    # the loop magnified: the twist less its straight line through the whole run
    slope, offset = np.polyfit(torque, twist, 1)
    inset = ax.inset_axes([0.62, 0.08, 0.35, 0.35])
    for rows, colour in ((loading, "C0"), (~loading, "C3")):
        inset.plot(torque, np.where(rows, twist - (slope * torque + offset), np.nan), lw=0.9, color=colour)
    inset.set_xlabel("torque [N·m]", fontsize="x-small")
    inset.set_ylabel("twist − line [arcmin]", fontsize="x-small")
    inset.tick_params(labelsize="x-small")
    inset.grid(alpha=0.3)
    return fig


def plot_time(run, sample: int = 0):
    """Torque and twist against time, one above the other.

    Parameters
    ----------
    run : hdsim.scenarios.run.Run
        A finished locked-wave-generator run.
    sample : int
        Which sample of a batch run to draw.

    Returns
    -------
    matplotlib.figure.Figure
        A new figure with two axes.
    """
    fig = Figure(figsize=(6.4, 4.8), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    t = run.result.t
    top.plot(t, run.result.signal("torque_Nm", sample), color="C0")
    top.set_ylabel("torque [N·m]")
    bottom.plot(t, rad_to_arcmin(run.result.signal("twist_rad", sample)), color="C2")
    bottom.set_ylabel("twist [arcmin]")
    bottom.set_xlabel("time [s]")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    top.set_title(f"{run.model.name}: {run.scenario.name}")
    return fig

