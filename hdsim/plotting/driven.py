"""Figures of a driven-wave-generator run (matplotlib, Agg-safe).

Like `hdsim.plotting.locked` for the locked bench: each function takes a
`hdsim.scenarios.run.Run` (sample 0 of a batch) and an optional axes and returns the
figure. Angles at the output in arcsec (deviations) or degrees, torques in N·m.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from hdsim.plotting import axes_for as _axes
from hdsim.units import rad_to_arcsec


def _ratio(run) -> float:
    return float(np.atleast_1d(np.asarray(run.model.drive.ratio, dtype=float))[0])


def plot_deviation(run, ax=None, sample: int = 0):
    """Deviation θ_out − θ_WG/N [arcsec] against output angle over the measured passes.

    Against time when the run has no ``forward``, ``reverse`` or ``constant`` window.

    Parameters
    ----------
    run : hdsim.scenarios.run.Run
        A driven run.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; default a new figure.
    sample : int
        Sample of a batch.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig, ax = _axes(ax, figsize=(8.0, 4.0))
    s, t = run.result.signals, run.result.t
    windows = run.result.metadata.get("windows", {})
    N = _ratio(run)
    passes = [w for w in ("forward", "reverse", "constant") if w in windows]
    deviation = rad_to_arcsec(s["deviation_rad"][sample])
    if passes:
        for name, colour in zip(passes, ("C0", "C3", "C0")):
            a, b = windows[name]
            m = (t >= a) & (t <= b)
            ax.plot(np.rad2deg(s["wg_angle_rad"][sample, m] / N), deviation[m], colour, lw=0.6, label=name)
        ax.set_xlabel("output angle [deg]")
        ax.legend(fontsize=8)
    else:
        ax.plot(t, deviation, "C0", lw=0.7)
        ax.set_xlabel("time [s]")
    ax.set_ylabel("θ_out − θ_WG/N [arcsec]")
    ax.set_title(f"{run.model.name}: {run.scenario.name}")
    ax.grid(alpha=0.3)
    return fig


def plot_driven_time(run, sample: int = 0):
    """Angles [deg], deviation and following error [arcsec], torques [N·m] against time [s].

    Parameters
    ----------
    run : hdsim.scenarios.run.Run
        A driven run.
    sample : int
        Sample of a batch.

    Returns
    -------
    matplotlib.figure.Figure
        Three stacked axes.
    """
    s, t = run.result.signals, run.result.t
    N = _ratio(run)
    fig = Figure(figsize=(8.0, 7.0), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    axes[0].plot(t, np.rad2deg(s["output_angle_rad"][sample]), "C0", label="output")
    axes[0].plot(t, np.rad2deg(s["reference_angle_rad"][sample] / N), "k--", lw=0.8, label="command / N")
    axes[0].set_ylabel("angle [deg]")
    axes[1].plot(t, rad_to_arcsec(s["output_angle_rad"][sample] - s["reference_angle_rad"][sample] / N), "C3",
                 lw=0.7, label="output − command/N")
    axes[1].plot(t, rad_to_arcsec(s["deviation_rad"][sample]), "C0", lw=0.7, label="output − WG/N")
    axes[1].set_ylabel("[arcsec]")
    axes[2].plot(t, s["drive_torque_Nm"][sample], "C0", lw=0.7, label="drive torque")
    axes[2].plot(t, s["load_torque_Nm"][sample], "C2", lw=0.8, label="load torque")
    axes[2].plot(t, N * s["motor_torque_Nm"][sample], "C1", lw=0.8, label="motor torque × N")
    axes[2].set_ylabel("[N·m]")
    axes[2].set_xlabel("time [s]")
    for axis in axes:
        axis.legend(fontsize=8)
        axis.grid(alpha=0.3)
    axes[0].set_title(f"{run.model.name}: {run.scenario.name}")
    return fig


def plot_running_torque(run, sample: int = 0):
    """No-load running torque against WG speed of a sweep (``running_torque_{rpm}rpm_mNm`` metrics),
    with the unit's catalog value at 2000 rpm; None for a run without a sweep.

    A measured sweep's plateau means (`hdsim fit` on a running-torque file) compare with it.
    """
    from hdsim.model.input_friction import catalog_values

    points = sorted((float(name[len("running_torque_"):-len("rpm_mNm")]), float(np.atleast_1d(value)[sample]))
                    for name, value in run.metrics.items()
                    if name.startswith("running_torque_") and name.endswith("rpm_mNm"))
    if not points:
        return None
    fig = Figure(figsize=(6, 4))
    ax = fig.subplots()
    speeds, torques = zip(*points)
    ax.plot(speeds, torques, "o-", label=f"simulated, {run.model.name}")
    catalog = catalog_values(run.model)
    derived = catalog.get("status", "").startswith("derived")
    ax.plot([2000.0], [1e3 * catalog["running_torque_2000rpm"]], "s", mfc="none", color="C3",
            label="catalog, 2000 rpm" + (f" ({catalog['status']})" if derived else ""))
    ax.set_xlabel("wave-generator speed [rpm]")
    ax.set_ylabel("no-load running torque on the input [mN·m]")
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.legend(fontsize=8)
    return fig
