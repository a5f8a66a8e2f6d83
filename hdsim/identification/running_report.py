"""Figures and pages of a running-torque fit and diagnosis.

A fit (`hdsim fit` on a sweep) gets two figures beside its parameter file:

- ``torque_vs_speed``: the mean torque of every plateau against its speed (measured),
  the fitted law's running torque over the speed range, and the catalog's no-load
  running torque of the unit at 2000 rpm where it is known;
- ``ripple_vs_angle``: what the model without its ripple leaves on the plateaus, as a
  level (divided by the direction), binned over one wave-generator turn, with the
  fitted ripple.

A diagnosis (`hdsim diagnose --report DIR`) writes ``residual_vs_time.png`` (every
step), those two figures for the final model, ``error_fall.png`` and ``index.html`` /
``index.md`` with the outcome, the data checks, the rounds and the fitted law. Figures
use matplotlib's object API (no pyplot), so the calling process's backend is untouched.
"""

from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np

from hdsim.atomic import write_text_atomic
from hdsim.identification.report_page import (CHECK_HEAD, check_rows, html_page, html_table, md_table, new_figure,
                                              outcome_line, save)

__all__ = ["torque_vs_speed", "ripple_vs_angle", "fit_figures", "write_running_report", "RUNNING_FIGURES"]

RPM = 30.0 / math.pi
RUNNING_FIGURES = ("residual_vs_time.png", "torque_vs_speed.png", "ripple_vs_angle.png", "error_fall.png")


def _label(step) -> str:
    return "+".join(step.effects) or "base"


def torque_vs_speed(fit, path, catalog_running_torque: float | None = None) -> Path:
    """Plateau torque vs speed (measured), the fitted running torque, the catalog point.

    Parameters
    ----------
    fit : hdsim.identification.running_fit.RunningFit
        The fit.
    path : str or os.PathLike
        PNG to write.
    catalog_running_torque : float, optional
        Catalog no-load running torque on the input at 2000 rpm [N·m].

    Returns
    -------
    pathlib.Path
        The figure.
    """
    rec = fit.record
    side = abs(rec.side_factor)
    torque = np.asarray(rec.measurement.torque, dtype=float)
    fig = new_figure((7, 4.5))
    ax = fig.subplots()
    speeds = np.array([s.speed for s in rec.segments])
    levels = np.array([np.mean(torque[s.start:s.stop]) for s in rec.segments])
    ax.plot(speeds * RPM, levels, "o", color="0.3", label="measured, plateau means")
    top = max(float(np.max(np.abs(speeds))), 1e-6)
    w = np.concatenate([-np.geomspace(top, 1e-3 * top, 200), np.geomspace(1e-3 * top, top, 200)])
    ax.plot(w * RPM, side * fit.law.running_torque(w), "-", label=f"fitted law ({'+'.join(fit.families) or 'base'})")
    if catalog_running_torque:
        cat = side * catalog_running_torque
        ax.plot([2000.0, -2000.0], [cat, -cat], "s", mfc="none", color="C3", label="catalog, 2000 rpm, +20 °C")
    ax.axhline(0.0, color="0.8", lw=0.6)
    ax.set_xlabel("wave-generator speed [rpm]")
    ax.set_ylabel(f"torque on the {rec.measurement.torque_side} [N·m]")
    ax.set_title("running torque vs speed")
    ax.legend(fontsize=8)
    return save(fig, Path(path))


def ripple_vs_angle(fit, path, bins: int = 72) -> Path:
    """What the model without ripple leaves on the plateaus, vs WG angle, with the fitted ripple.

    Parameters
    ----------
    fit : hdsim.identification.running_fit.RunningFit
        The fit.
    path : str or os.PathLike
        PNG to write.
    bins : int
        Bins over one WG turn.

    Returns
    -------
    pathlib.Path
        The figure.
    """
    rec = fit.record
    side = abs(rec.side_factor)
    meas = rec.measurement
    plateau = rec.steady(1) | rec.steady(-1)
    flat = fit.law.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=())
    model = side * (flat.torque(rec.speed, meas.wg_angle) + fit.inertia * rec.accel)
    level = (np.asarray(meas.torque, dtype=float) - model) * np.sign(rec.speed)
    theta = np.mod(np.asarray(meas.wg_angle, dtype=float), 2.0 * math.pi)
    fig = new_figure((7, 4))
    ax = fig.subplots()
    edges = np.linspace(0.0, 2.0 * math.pi, bins + 1)
    which = np.digitize(theta[plateau], edges) - 1
    means = np.array([np.mean(level[plateau][which == b]) if np.any(which == b) else np.nan for b in range(bins)])
    ax.plot(np.degrees(theta[plateau]), level[plateau], ".", ms=1, color="0.8", label="residual without ripple")
    ax.plot(np.degrees(0.5 * (edges[1:] + edges[:-1])), means, "o-", ms=3, color="0.3", label="binned mean")
    grid = np.linspace(0.0, 2.0 * math.pi, 361)
    if fit.law.ripple_orders:
        ripple = side * fit.law.coulomb_torque * (fit.law.modulation(grid) - 1.0)
        ax.plot(np.degrees(grid), ripple, "-", color="C1", label="fitted ripple (WG orders)")
    ax.set_xlabel("wave-generator angle mod 360 [deg]")
    ax.set_ylabel(f"level [N·m, {meas.torque_side}]")
    ax.set_title("ripple vs wave-generator angle")
    ax.legend(fontsize=8)
    return save(fig, Path(path))


def fit_figures(fit, stem, catalog_running_torque: float | None = None) -> list[Path]:
    """Both figures of a running-torque fit, as ``<stem>.torque_vs_speed.png`` and ``<stem>.ripple.png``."""
    stem = Path(stem)
    return [torque_vs_speed(fit, stem.with_name(stem.name + ".torque_vs_speed.png"), catalog_running_torque),
            ripple_vs_angle(fit, stem.with_name(stem.name + ".ripple.png"))]


def write_running_report(diagnosis, folder, assessment: dict | None = None,
                         catalog_running_torque: float | None = None) -> Path:
    """Write the figures and pages of a running-torque diagnosis into a folder.

    Parameters
    ----------
    diagnosis : hdsim.identification.engine.Diagnosis
        The finished diagnosis.
    folder : str or os.PathLike
        Output folder, created if missing.
    assessment : dict, optional
        ``outcome``, ``next_measurement`` and ``checks`` as ``hdsim diagnose --json`` gives them.
    catalog_running_torque : float, optional
        Catalog no-load running torque on the input at 2000 rpm [N·m].

    Returns
    -------
    pathlib.Path
        ``index.html``.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    assessment = assessment or {}
    meas = diagnosis.measurement
    t = np.asarray(meas.time, dtype=float)
    fig = new_figure((10, 3.5))
    ax = fig.subplots()
    for step in diagnosis.steps:
        r = np.where(step.fit.rows, step.fit.residual, np.nan)
        ax.plot(t, r, lw=0.6, label=_label(step))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("residual [N·m]")
    ax.legend(fontsize=8)
    drawn = [save(fig, folder / RUNNING_FIGURES[0])]
    final = diagnosis.final.fit
    drawn.append(torque_vs_speed(final, folder / RUNNING_FIGURES[1], catalog_running_torque))
    drawn.append(ripple_vs_angle(final, folder / RUNNING_FIGURES[2]))
    fig = new_figure((6, 3.5))
    ax = fig.subplots()
    ax.plot(range(len(diagnosis.steps)), [s.fit.rmse_Nm for s in diagnosis.steps], "o-", label="rms")
    ax.axhline(diagnosis.whiteness["noise_floor_Nm"], ls=":", color="0.5", label="noise floor")
    ax.set_xticks(range(len(diagnosis.steps)), [_label(s) for s in diagnosis.steps], fontsize=8)
    ax.set_ylabel("error [N·m]")
    ax.legend(fontsize=8)
    drawn.append(save(fig, folder / RUNNING_FIGURES[3]))
    names = [p.name for p in drawn]
    write_text_atomic(folder / "index.md", _markdown(diagnosis, assessment, names))
    page = folder / "index.html"
    write_text_atomic(page, _html(diagnosis, assessment, names))
    return page


HEAD = ("step", "effects", "rms [N·m]")
ROUND = ("family", "effect", "score", "rms [N·m]", "share explained", "decision")


def _tables(diagnosis):
    d = diagnosis.to_json()
    steps = [(str(r["step"]), "+".join(r["effects"]) or "base", f"{r['rmse_Nm']:.4g}") for r in d["table"]]
    rounds = []
    for n, r in enumerate(d["rounds"], start=1):
        rows = [(c["family"], c["effect"], "—" if c["score"] is None else f"{c['score']:.1f}",
                 "—" if c["rmse_Nm"] is None else f"{c['rmse_Nm']:.4g}",
                 f"{100 * c.get('share_explained', 0.0):.0f} %", c["why"]) for c in r["candidates"]]
        if rows:
            rounds.append((n, "+".join(r["effects"]) or "base", rows))
    law = [(k, str(v)) for k, v in d["final"]["law"].items()]
    metrics = [(k, "not run" if v is None else f"{v:.4g}") for k, v in d["metrics"].items()]
    return d, steps, rounds, law, metrics


def _markdown(diagnosis, assessment, figures) -> str:
    d, steps, rounds, law, metrics = _tables(diagnosis)
    parts = [f"# Diagnosis of {diagnosis.measurement.source}", ""]
    if outcome_line(assessment):
        parts += [f"**{outcome_line(assessment)}**", ""]
    if check_rows(assessment):
        parts += ["## The data", "", md_table(CHECK_HEAD, check_rows(assessment)), ""]
    parts += [f"running-torque test, {len(diagnosis.measurement)} rows; hold-out by {d['holdout']}.", "",
              f"**Verdict:** {d['verdict']}", "", "## Before and after", "", md_table(HEAD, steps), ""]
    for n, effects, rows in rounds:
        parts += [f"## Round {n} (model: {effects})", "", md_table(ROUND, rows), ""]
    parts += ["## Fitted law (wave-generator shaft)", "", md_table(("field", "value"), law), "",
              md_table(("metric", "value"), metrics), "", "## Figures", ""]
    parts += [f"![{f}]({f})" for f in figures]
    return "\n".join(parts) + "\n"


def _html(diagnosis, assessment, figures) -> str:
    d, steps, rounds, law, metrics = _tables(diagnosis)
    body = [f"<h1>Diagnosis of {html.escape(str(diagnosis.measurement.source))}</h1>"]
    if outcome_line(assessment):
        body.append(f"<p><b>{html.escape(outcome_line(assessment))}</b></p>")
    if check_rows(assessment):
        body += ["<h2>The data</h2>", html_table(CHECK_HEAD, check_rows(assessment))]
    body += [f"<p>running-torque test, {len(diagnosis.measurement)} rows.</p>",
             f"<p><b>Verdict:</b> {html.escape(d['verdict'])}</p>", "<h2>Before and after</h2>",
             html_table(HEAD, steps)]
    for n, effects, rows in rounds:
        body += [f"<h2>Round {n} (model: {html.escape(effects)})</h2>", html_table(ROUND, rows)]
    body += ["<h2>Fitted law (wave-generator shaft)</h2>", html_table(("field", "value"), law),
             html_table(("metric", "value"), metrics)]
    body.append("<h2>Figures</h2>" + "".join(f'<p><img src="{f}" alt="{f}"></p>' for f in figures))
    return html_page("hdsim diagnosis", body)
