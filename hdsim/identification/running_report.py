"""Figures and pages of a running-torque fit and diagnosis.

A fit (`hdsim fit` on a sweep) gets two figures beside its parameter file:

- ``torque_vs_speed``: the mean torque of every plateau against its speed (measured),
  the fitted law's running torque over the speed range, and the catalog's no-load
  running torque of the unit at 2000 rpm where it is known;
- ``ripple_vs_angle``: what the model without its ripple leaves on the plateaus, as a
  level (divided by the direction), binned over one wave-generator turn, with the
  fitted ripple.

A diagnosis report (`hdsim.identification.report_page`) shows those two figures for the
final model, and the fitted law and the sweep's metrics as tables. Figures use
matplotlib's object API (no pyplot), so the calling process's backend is untouched.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from hdsim.identification.report_page import new_figure, save
from hdsim.io.running_checks import turn_mean, whole_turns

__all__ = ["torque_vs_speed", "ripple_vs_angle", "fit_figures", "running_figures", "running_sections"]

RPM = 30.0 / math.pi


def torque_vs_speed(fit, path, catalog_running_torque: float | None = None) -> Path:
    """Plateau torque vs speed (measured), the fitted running torque of ``fit`` (a
    `RunningFit`) and the catalog point (``catalog_running_torque``: the no-load running
    torque on the input at 2000 rpm [N·m]), as the PNG ``path``; returns its path."""
    rec = fit.record
    side = abs(rec.side_factor)
    torque = np.asarray(rec.measurement.torque, dtype=float)
    ax = new_figure((7, 4.5)).subplots()
    # each plateau's running torque as the metrics define it (whole WG turns, per unit of angle),
    # so the points are the fit's numbers; a plateau shorter than a turn shows its plain mean
    speeds = np.array([s.speed for s in rec.segments])
    angle = rec.measurement.wg_angle
    levels = []
    for seg in rec.segments:
        rows = whole_turns(angle, [seg], int(np.sign(seg.speed)))
        levels.append(turn_mean(torque, angle, rows) if rows.any() else float(np.mean(torque[seg.start:seg.stop])))
    ax.plot(speeds * RPM, levels, "o", color="0.3", label="measured, each plateau over whole WG turns")
    top = max(float(np.max(np.abs(speeds))), 1e-6)
    w = np.concatenate([-np.geomspace(top, 1e-3 * top, 200), np.geomspace(1e-3 * top, top, 200)])
    ax.plot(w * RPM, side * fit.law.running_torque(w), "-", label=f"fitted law ({'+'.join(fit.families) or 'base'})")
    if catalog_running_torque:
        cat = side * catalog_running_torque
        ax.plot([2000.0, -2000.0], [cat, -cat], "s", mfc="none", color="C3", label="catalog, 2000 rpm, +20 °C")
    ax.axhline(0.0, color="0.8", lw=0.6)
    # symmetric log: a 28 rpm plateau and the Stribeck rise below it stay apart from 0
    ax.set_xscale("symlog", linthresh=max(0.5 * float(np.min(np.abs(speeds))) * RPM, 1e-3))
    ax.set(xlabel="wave-generator speed [rpm]", ylabel=f"torque on the {rec.measurement.torque_side} [N·m]",
           title="running torque vs speed")
    ax.legend(fontsize=8)
    return save(ax.figure, Path(path))


def ripple_vs_angle(fit, path, bins: int = 72) -> Path:
    """What the model without ripple leaves on the plateaus, vs WG angle in ``bins`` over one
    turn, with the fitted ripple of ``fit`` (a `RunningFit`), as the PNG ``path``; returns its path."""
    rec = fit.record
    side = abs(rec.side_factor)
    meas = rec.measurement
    plateau = np.zeros(rec.speed.size, dtype=bool)
    for seg in rec.segments:
        plateau[seg.start:seg.stop] = True
    flat = fit.law.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=())
    model = side * (flat.torque(rec.speed, meas.wg_angle) + fit.inertia * rec.accel)
    level = (np.asarray(meas.torque, dtype=float) - model) * np.sign(rec.speed)
    theta = np.mod(np.asarray(meas.wg_angle, dtype=float), 2.0 * math.pi)
    ax = new_figure((7, 4)).subplots()
    edges = np.linspace(0.0, 2.0 * math.pi, bins + 1)
    which = np.digitize(theta[plateau], edges) - 1
    means = np.array([np.mean(level[plateau][which == b]) if np.any(which == b) else np.nan for b in range(bins)])
    ax.plot(np.degrees(theta[plateau]), level[plateau], ".", ms=1, color="0.8", label="residual without ripple")
    ax.plot(np.degrees(0.5 * (edges[1:] + edges[:-1])), means, "o-", ms=3, color="0.3", label="binned mean")
    grid = np.linspace(0.0, 2.0 * math.pi, 361)
    if fit.law.ripple_orders:
        ripple = side * fit.law.coulomb_torque * (fit.law.modulation(grid) - 1.0)
        ax.plot(np.degrees(grid), ripple, "-", color="C1", label="fitted ripple (WG orders)")
    ax.set(xlabel="wave-generator angle mod 360 [deg]", ylabel=f"level [N·m, {meas.torque_side}]",
           title="ripple vs wave-generator angle")
    ax.legend(fontsize=8)
    return save(ax.figure, Path(path))


def fit_figures(fit, stem, catalog_running_torque: float | None = None) -> list[Path]:
    """Both figures of a running-torque fit, as ``<stem>.torque_vs_speed.png`` and ``<stem>.ripple.png``."""
    stem = Path(stem)
    return [torque_vs_speed(fit, stem.with_name(stem.name + ".torque_vs_speed.png"), catalog_running_torque),
            ripple_vs_angle(fit, stem.with_name(stem.name + ".ripple.png"))]


def running_figures(diagnosis, folder, catalog_running_torque: float | None = None) -> list[tuple[Path, str]]:
    """The sweep figures of the final model of a running-torque diagnosis; [(path, caption)]."""
    final = diagnosis.final.fit
    return [(torque_vs_speed(final, Path(folder) / "torque_vs_speed.png", catalog_running_torque),
             "Plateau means against speed with the fitted law's running torque, and the catalog point."),
            (ripple_vs_angle(final, Path(folder) / "ripple_vs_angle.png"),
             "What the law without its ripple leaves on the plateaus, against the wave-generator angle.")]


def running_sections(d: dict) -> list[tuple[str, tuple]]:
    """The fitted law and the sweep's metrics, as (heading, (head, rows)) of the report."""
    metrics = [(k, "not run" if v is None else f"{v:.4g}") for k, v in d["metrics"].items()]
    law = law_rows(d["final"]["law"], d["final"].get("derived", {}).get("starting_torque_basis"),
                   "friction.coulomb_asymmetry" in d["final"].get("not_determined", {}))
    return [("Fitted law (wave-generator shaft)", (("term", "value", "unit"), law)),
            ("Metrics", (("metric", "value"), metrics))]


def law_rows(law: dict, starting_basis: str | None = None,
             one_way: bool = False) -> list[tuple[str, str, str]]:
    """A fit's law table (`RunningFit.law_table`) as a reader's rows: 4 significant digits,
    and the ripple as torques [N·m] (the table keeps them as fractions of the level);
    ``starting_basis`` (`hdsim.identification.sweep_start`) follows a starting torque the
    record does not determine; ``one_way``: the asymmetry is held at 0, not determined
    (`RunningFit.held_at_zero`)."""
    def shown(values):
        return ", ".join(f"{float(v):.4g}" for v in values) if values else "none"

    level = law["starting_torque_Nm"] * law["coulomb_share"]
    start = shown([law["starting_torque_Nm"]])
    if starting_basis and "not determined" in starting_basis:
        start += f" ({starting_basis.split(';')[0]})"
    return [("starting torque F_s", start, "N·m"),
            ("Coulomb level F_c", shown([level]), "N·m"),
            ("Stribeck speed ω_s", shown([law["stribeck_speed_rpm"]]), "rpm"),
            ("viscous b", shown([law["viscous_Nms"]]), "N·m·s/rad"),
            ("direction asymmetry Δ", shown([law["coulomb_asymmetry_Nm"]])
             + (" (not determined by the record: it runs one way)" if one_way else ""), "N·m"),
            ("ripple orders", shown(law["ripple_orders"]), "per WG turn"),
            ("ripple amplitudes", shown([level * r for r in law["ripple_amplitudes_of_level"]]), "N·m"),
            ("ripple phases", shown(law["ripple_phases"]), "rad"),
            ("position torque orders", shown(law["position_torque_orders"]), "per WG turn"),
            ("position torque amplitudes", shown(law["position_torque_amplitudes_Nm"]), "N·m"),
            ("position torque phases", shown(law["position_torque_phases"]), "rad")]
