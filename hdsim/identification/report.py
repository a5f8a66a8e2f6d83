"""The twist tests' figures of a diagnosis report (stiffness and kinematic error).

`twist_figures` draws, in the order a person reads them (beside the residual against time
and the error fall every report has, `hdsim.identification.report_page`):

- ``measured_vs_model.png``: measured angle vs torque and the model of the first and the
  last step (offset removed);
- ``residual_vs_torque.png``: residual vs torque, loading and unloading in two colours,
  first and last step;
- ``residual_spectrum.png``: stiffness test: amplitude spectrum of the residual vs
  frequency; kinematic-error test: residual vs wave-generator angle and its order
  spectrum;
- ``residual_vs_rate.png``: the residual loop (unloading minus loading) per loading rate,
  only when the record has two rates or more (one point answers no rate question).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hdsim.identification.problem import relative_angle
from hdsim.identification.report_page import new_figure, save, step_label
from hdsim.identification.residuals import order_spectrum, views
from hdsim.units import ARCSEC_PER_RAD

__all__ = ["twist_figures", "twist_fit_figure", "FIGURES"]

FIGURES = ("residual_vs_time.png", "measured_vs_model.png", "residual_vs_torque.png",
           "residual_spectrum.png", "residual_vs_rate.png", "error_fall.png")


def _by_direction(ax, T, meas, residual) -> None:
    """Residual [arcsec] against torque, loading and unloading in two colours."""
    v = views(meas, residual)
    r = v["residual"] * ARCSEC_PER_RAD
    ax.plot(T[v["direction"] > 0], r[v["direction"] > 0], ".", ms=2, color="tab:blue", label="loading")
    ax.plot(T[v["direction"] <= 0], r[v["direction"] <= 0], ".", ms=2, color="tab:red", label="unloading")


def twist_figures(diagnosis, folder) -> list[tuple[Path, str]]:
    """Draw the twist figures of ``diagnosis`` into ``folder``; [(path, caption)]."""
    folder = Path(folder)
    meas = diagnosis.measurement
    steps = diagnosis.steps
    first, last = steps[0], steps[-1]
    T = np.asarray(meas.torque, dtype=float)
    arcsec = ARCSEC_PER_RAD
    ideal = np.asarray(meas.wg_angle) / meas.ratio if meas.wg_driven else 0  # the kinematic angle of a driven record
    ends = (first, last) if last is not first else (first,)  # one curve per distinct model
    drawn = []

    # measured vs model
    ax = new_figure((7, 4.5)).subplots()
    y = relative_angle(meas)
    ax.plot(T, (y - first.fit.offset) * arcsec, ".", ms=2, color="0.6", label="measured")
    # each distinct model on the axis of `_x`, less the first offset [arcsec]: drawn whole and in the inset
    models = [(step.fit.prediction - ideal - first.fit.offset) * arcsec for step in ends]
    styles = ("--", "-")[-len(ends):]
    for step, style, model in zip(ends, styles, models):
        ax.plot(T, model, style, lw=1, label=f"model: {step_label(step)}")
    ax.set(xlabel="torque [N·m]", ylabel="angle − offset [arcsec]", title="measured vs model")
    ax.legend(fontsize=8, loc="upper left")
    # zoomed where the first model misses most: a misfit of arcseconds on a span of hundreds
    worst = int(np.argmax(np.abs(first.fit.residual)))
    near = np.abs(T - T[worst]) <= 0.08 * max(float(np.ptp(T)), 1e-12)
    inset = ax.inset_axes([0.6, 0.07, 0.37, 0.37])
    inset.plot(T[near], (y[near] - first.fit.offset) * arcsec, ".", ms=2, color="0.6")
    for style, model in zip(styles, models):
        # NaN outside the window: the legs that pass through it are drawn apart, not joined
        inset.plot(T, np.where(near, model, np.nan), style, lw=1)
    inset.set_xlim(float(np.min(T[near])), float(np.max(T[near])))
    inset.set_title("where the first model misses most", fontsize=7)
    inset.tick_params(labelsize=7)
    drawn.append((save(ax.figure, folder / FIGURES[1]), "Measured angle against torque with the first and the last "
                  "model; the inset zooms on the torque where the first model misses most."))

    # residual vs torque by direction
    fig = new_figure((10, 4))
    axes = fig.subplots(1, len(ends), sharey=True, squeeze=False)
    for ax, step in zip(axes[0], ends):
        _by_direction(ax, T, meas, step.fit.residual)
        ax.axvline(0, color="0.8", lw=0.8)
        ax.set(title=f"residual: {step_label(step)}", xlabel="torque [N·m]")
    axes[0][0].set_ylabel("residual [arcsec]")
    axes[0][0].legend(fontsize=8, markerscale=4)  # the colours mean the same in every panel
    drawn.append((save(fig, folder / FIGURES[2]), "Residual against torque, loading (blue) and unloading (red): "
                  "a loop left here is friction or backlash the model misses."))

    # spectrum
    fig = new_figure((10, 4) if meas.wg_driven else (7, 4))
    if meas.wg_driven:
        axes = fig.subplots(1, 2)
        wg = np.asarray(meas.wg_angle, dtype=float)
        for step in ends:
            axes[0].plot(np.mod(wg, 2 * np.pi), step.fit.residual * arcsec, ".", ms=1.5, label=step_label(step))
            orders, amp = order_spectrum(wg, step.fit.residual, max_order=8.0, n_orders=400)
            axes[1].plot(orders, amp * arcsec, lw=0.8, label=step_label(step))
        axes[0].set(xlabel="wave-generator angle mod 2π [rad]", ylabel="residual [arcsec]")
        axes[1].set(xlabel="order of the wave-generator angle", ylabel="amplitude [arcsec]")
        axes[1].legend(fontsize=8)
    else:
        ax = fig.subplots()
        dt = float(np.median(np.diff(np.asarray(meas.time, dtype=float))))
        for step in ends:
            r = step.fit.residual - np.mean(step.fit.residual)
            spec = np.abs(np.fft.rfft(r)) * 2.0 / r.size
            freq = np.fft.rfftfreq(r.size, dt)
            ax.loglog(freq[1:], spec[1:] * arcsec, lw=0.7, label=step_label(step))
        ax.set(xlabel="frequency [Hz]", ylabel="residual amplitude [arcsec]",
               title="residual spectrum (white noise is flat)")
        ax.legend(fontsize=8)
    drawn.append((save(fig, folder / FIGURES[3]), "Where the residual's energy lies: a line here is a periodic effect "
                  "the model misses; white noise is flat."))

    # loop width vs rate: only with two rates or more
    loops = [(step, *_loop_by_rate(views(meas, step.fit.residual))) for step in steps]
    if all(len(rates) >= 2 for _, rates, _ in loops):
        ax = new_figure((7, 4)).subplots()
        for step, rates, widths in loops:
            ax.plot(rates, np.array(widths) * arcsec, "o-", label=step_label(step))
        ax.set(xlabel="loading rate |dT/dt| [N·m/s]", ylabel="residual loop: unloading − loading [arcsec]")
        ax.axhline(0, color="0.8", lw=0.8)
        ax.legend(fontsize=8)
        drawn.append((save(ax.figure, folder / FIGURES[4]), "The residual loop per loading rate: a width that grows "
                      "with the rate is damping, a constant one friction."))

    return drawn


def _loop_by_rate(v):
    rate, direction, r = v["rate"], v["direction"], v["residual"]
    if np.count_nonzero(rate > 0) < 10:
        return [], []
    level = np.round(np.log(np.maximum(rate, 1e-300)) / 0.2)  # fifths of a natural log of the rate
    out_r, out_w = [], []
    for lv in np.unique(level[rate > 0]):
        m = level == lv
        if np.count_nonzero(m) < 40:
            continue
        down, up = m & (direction < 0), m & (direction > 0)
        if np.count_nonzero(down) < 10 or np.count_nonzero(up) < 10:
            continue
        out_r.append(float(np.median(rate[m])))
        out_w.append(float(np.mean(r[down]) - np.mean(r[up])))
    return out_r, out_w


def twist_fit_figure(result, folder) -> tuple[Path, str]:
    """Measured angle against torque with the fitted model, and the residual against torque
    below it (loading and unloading apart): the figure of a twist fit's page. A driven
    record's kinematic error is drawn against the output angle instead: against the torque
    it is a cloud, its load hardly moving while the error runs through its orders."""
    meas = result.measurement
    driven = meas.wg_driven
    T = np.asarray(meas.torque, dtype=float)
    x = np.degrees(np.asarray(meas.wg_angle, dtype=float) / meas.ratio) if driven else T
    measured = relative_angle(meas) - result.offset
    model = result.prediction - (np.asarray(meas.wg_angle) / meas.ratio if driven else 0) - result.offset
    fig = new_figure((7, 6))
    top, bottom = fig.subplots(2, 1, sharex=True)
    top.plot(x, measured * ARCSEC_PER_RAD, ".", ms=2, color="0.6", label="measured")
    top.plot(x, model * ARCSEC_PER_RAD, "-", lw=1, label="model: " + ("+".join(result.families) or "base"))
    top.set(ylabel=("kinematic error" if driven else "angle") + " − offset [arcsec]", title="measured vs fitted model")
    top.legend(fontsize=8)
    if driven:
        bottom.plot(x, np.asarray(result.residual) * ARCSEC_PER_RAD, ".", ms=2)
    else:
        _by_direction(bottom, T, meas, result.residual)
        bottom.legend(fontsize=8, markerscale=4)
    bottom.set(xlabel="output angle [deg]" if driven else "torque [N·m]", ylabel="residual [arcsec]")
    caption = ("Measured kinematic error against the output angle with the fitted model; below, the residual."
               if driven else "Measured angle against torque with the fitted model; below, the residual, loading "
               "and unloading apart.")
    return save(fig, Path(folder) / "measured_vs_model.png"), caption

