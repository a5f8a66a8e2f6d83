"""The diagnosis report: PNG figures of every step plus an HTML and a Markdown page.

``write_report(diagnosis, folder, assessment)`` writes, in the order a person reads them,

- ``residual_vs_time.png``: residual vs time, every step (where stick-slip, drift and
  the joins of concatenated runs show first);
- ``measured_vs_model.png``: measured angle vs torque and the model of the first and the
  last step (offset removed);
- ``residual_vs_torque.png``: residual vs torque, loading and unloading in two colours,
  first and last step;
- ``residual_spectrum.png``: stiffness test: amplitude spectrum of the residual vs
  frequency; kinematic-error test: residual vs wave-generator angle and its order
  spectrum;
- ``residual_vs_rate.png``: the residual loop (unloading minus loading) per loading rate,
  only when the record has two rates or more (one point answers no rate question);
- ``error_fall.png``: rms and max error per step;
- ``index.html`` and ``index.md``: the outcome and the data checks first, then the
  before/after table, the ranking of every round, ambiguities, whiteness and the
  plain-sentence findings, with the figures.

Everything is written atomically. The figures are drawn with matplotlib's object API
(no pyplot, no backend selected), so writing a report leaves the backend of the
calling process as it was.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from hdsim.atomic import write_text_atomic
from hdsim.identification.report_page import (CHECK_HEAD, check_rows, html_page, html_table, md_table, new_figure,
                                              outcome_line, save)
from hdsim.identification.residuals import order_spectrum, views
from hdsim.units import ARCSEC_PER_RAD

__all__ = ["write_report", "FIGURES"]

FIGURES = ("residual_vs_time.png", "measured_vs_model.png", "residual_vs_torque.png",
           "residual_spectrum.png", "residual_vs_rate.png", "error_fall.png")


def _label(step) -> str:
    return "+".join(step.effects) or "base"


def _x(meas):
    """Angle relative to the kinematic ideal [rad] (stiffness test: the angle itself)."""
    if meas.wg_driven:
        return meas.kinematic_error
    return np.asarray(meas.angle, dtype=float)


def write_report(diagnosis, folder, assessment: dict | None = None) -> Path:
    """Write the figures and pages of a diagnosis into a folder.

    Parameters
    ----------
    diagnosis : hdsim.identification.diagnosis.Diagnosis
        The finished diagnosis.
    folder : str or os.PathLike
        Output folder, created if missing; the files of `FIGURES`, ``index.md`` and
        ``index.html`` in it are replaced.
    assessment : dict, optional
        ``outcome``, ``next_measurement`` and ``checks`` (as ``hdsim diagnose --json``
        gives them), shown at the top of the page.

    Returns
    -------
    pathlib.Path
        ``index.html``.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    meas = diagnosis.measurement
    steps = diagnosis.steps
    first, last = steps[0], steps[-1]
    T = np.asarray(meas.torque, dtype=float)
    t = np.asarray(meas.time, dtype=float)
    arcsec = ARCSEC_PER_RAD
    ends = (first, last) if last is not first else (first,)  # one curve per distinct model
    drawn = []

    # residual vs time: first, it shows stick-slip, drift and joins
    fig = new_figure((10, 3.5))
    ax = fig.subplots()
    for step in steps:
        ax.plot(t, step.fit.residual * arcsec, lw=0.6, label=_label(step))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("residual [arcsec]")
    ax.legend(fontsize=8)
    drawn.append(save(fig, folder / FIGURES[0]))

    # measured vs model
    fig = new_figure((7, 4.5))
    ax = fig.subplots()
    y = _x(meas)
    ax.plot(T, (y - first.fit.offset) * arcsec, ".", ms=2, color="0.6", label="measured")
    for step, style in zip(ends, ("--", "-")[-len(ends):]):
        model = step.fit.prediction - (np.asarray(meas.wg_angle) / meas.ratio if meas.wg_driven else 0)
        ax.plot(T, (model - first.fit.offset) * arcsec, style, lw=1, label=f"model: {_label(step)}")
    ax.set_xlabel("torque [N·m]")
    ax.set_ylabel("angle − offset [arcsec]")
    ax.set_title("measured vs model")
    ax.legend(fontsize=8)
    drawn.append(save(fig, folder / FIGURES[1]))

    # residual vs torque by direction
    fig = new_figure((10, 4))
    axes = fig.subplots(1, len(ends), sharey=True, squeeze=False)
    for ax, step in zip(axes[0], ends):
        v = views(meas, step.fit.residual)
        r = v["residual"] * arcsec
        ax.plot(T[v["direction"] > 0], r[v["direction"] > 0], ".", ms=2, color="tab:blue", label="loading")
        ax.plot(T[v["direction"] <= 0], r[v["direction"] <= 0], ".", ms=2, color="tab:red", label="unloading")
        ax.axvline(0, color="0.8", lw=0.8)
        ax.set_title(f"residual: {_label(step)}")
        ax.set_xlabel("torque [N·m]")
    axes[0][0].set_ylabel("residual [arcsec]")
    axes[0][0].legend(fontsize=8, markerscale=4)  # the colours mean the same in every panel
    drawn.append(save(fig, folder / FIGURES[2]))

    # spectrum
    if meas.wg_driven:
        fig = new_figure((10, 4))
        axes = fig.subplots(1, 2)
        wg = np.asarray(meas.wg_angle, dtype=float)
        for step in ends:
            axes[0].plot(np.mod(wg, 2 * np.pi), step.fit.residual * arcsec, ".", ms=1.5, label=_label(step))
            orders, amp = order_spectrum(wg, step.fit.residual, max_order=8.0, n_orders=400)
            axes[1].plot(orders, amp * arcsec, lw=0.8, label=_label(step))
        axes[0].set_xlabel("wave-generator angle mod 2π [rad]")
        axes[0].set_ylabel("residual [arcsec]")
        axes[1].set_xlabel("order of the wave-generator angle")
        axes[1].set_ylabel("amplitude [arcsec]")
        axes[1].legend(fontsize=8)
    else:
        fig = new_figure((7, 4))
        ax = fig.subplots()
        dt = float(np.median(np.diff(t)))
        for step in ends:
            r = step.fit.residual - np.mean(step.fit.residual)
            spec = np.abs(np.fft.rfft(r)) * 2.0 / r.size
            freq = np.fft.rfftfreq(r.size, dt)
            ax.loglog(freq[1:], spec[1:] * arcsec, lw=0.7, label=_label(step))
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("residual amplitude [arcsec]")
        ax.set_title("residual spectrum (white noise is flat)")
        ax.legend(fontsize=8)
    drawn.append(save(fig, folder / FIGURES[3]))

    # loop width vs rate: only with two rates or more
    loops = [(step, *_loop_by_rate(views(meas, step.fit.residual))) for step in steps]
    if all(len(rates) >= 2 for _, rates, _ in loops):
        fig = new_figure((7, 4))
        ax = fig.subplots()
        for step, rates, widths in loops:
            ax.plot(rates, np.array(widths) * arcsec, "o-", label=_label(step))
        ax.set_xlabel("loading rate |dT/dt| [N·m/s]")
        ax.set_ylabel("residual loop: unloading − loading [arcsec]")
        ax.axhline(0, color="0.8", lw=0.8)
        ax.legend(fontsize=8)
        drawn.append(save(fig, folder / FIGURES[4]))

    # error fall
    fig = new_figure((7, 4))
    ax = fig.subplots()
    labels = [_label(s) for s in steps]
    x = np.arange(len(steps))
    ax.bar(x - 0.2, [s.fit.rmse_rad * arcsec for s in steps], 0.4, label="rms error")
    ax.bar(x + 0.2, [s.fit.max_abs_rad * arcsec for s in steps], 0.4, label="max error")
    floor = diagnosis.whiteness["noise_floor_rad"] * arcsec
    ax.axhline(floor, color="k", ls=":", lw=1, label="noise floor (final residual)")
    ax.set_xticks(x, labels, rotation=15, fontsize=8)
    ax.set_ylabel("error [arcsec]")
    ax.set_yscale("log")
    ax.legend(fontsize=8)
    drawn.append(save(fig, folder / FIGURES[5]))

    names = [p.name for p in drawn]
    write_text_atomic(folder / "index.md", _markdown(diagnosis, assessment or {}, names))
    page = folder / "index.html"
    write_text_atomic(page, _html(diagnosis, assessment or {}, names))
    return page


def _loop_by_rate(v):
    rate, direction, r = v["rate"], v["direction"], v["residual"]
    pos = rate[rate > 0]
    if pos.size < 10:
        return [], []
    levels = np.unique(np.round(np.log(pos) / 0.2))
    out_r, out_w = [], []
    for lv in levels:
        m = np.abs(np.round(np.log(np.maximum(rate, 1e-300)) / 0.2) - lv) < 0.5
        if np.count_nonzero(m) < 40:
            continue
        down, up = m & (direction < 0), m & (direction > 0)
        if np.count_nonzero(down) < 10 or np.count_nonzero(up) < 10:
            continue
        out_r.append(float(np.median(rate[m])))
        out_w.append(float(np.mean(r[down]) - np.mean(r[up])))
    return out_r, out_w


def _rows(diagnosis):
    arcsec = ARCSEC_PER_RAD
    rows = []
    for row in diagnosis.table():
        score = "" if row["score"] is None else f"{row['score']:.1f}"
        hold = ", ".join(f"{h * arcsec:.2f}" for h in row["holdout_rmse_rad"])
        changed = ", ".join(f"{f} as {e}" for f, e in (row.get("other_form") or {}).items())
        held = f"{row['provisional']} (stand-in, not added)" if row.get("provisional") else ""
        rows.append([str(row["step"]), "+".join(row["effects"]) or "base", row["added"] or changed or held,
                     f"{row['rmse_rad'] * arcsec:.2f}", f"{row['max_abs_error_rad'] * arcsec:.2f}",
                     hold, score])
    return rows


def _rounds(diagnosis):
    arcsec = ARCSEC_PER_RAD
    out = []
    for i, step in enumerate(diagnosis.steps):
        if not step.candidates:
            continue
        lines = []
        tried = [(c, c.family) for c in sorted(step.candidates, key=lambda c: c.score)]
        tried += [(c, f"{c.family} in another form") for c in sorted(step.reshapes, key=lambda c: c.score)]
        for c, label in tried:
            if c.fit is None:  # could not be fitted: the reason says why
                lines.append([label, c.effect, "–", "–", "–", c.reason])
                continue
            lines.append([label, c.effect, f"{c.score:.1f}", f"{c.fit.rmse_rad * arcsec:.2f}",
                          f"{100 * c.figures['pooled_holdout_gain']:.0f} % ("
                          + ", ".join(f"{100 * g:.0f} %" for g in c.holdout_gain) + ")", c.reason])
        out.append((i + 1, "+".join(step.effects) or "base", lines))
    return out


TABLE_HEAD = ["step", "effects", "added", "rms [arcsec]", "max [arcsec]", "hold-out rms [arcsec]",
              "score"]
ROUND_HEAD = ["family", "effect", "score", "rms [arcsec]", "hold-out gain, pooled (per fold)",
              "decision"]


CONFIDENCE_HEAD = ("model", "Δelpd [nats]", "SE", "P(added)")


def _confidence_rounds(d: dict) -> list:
    """[(round, rows)] of the comparison tables with each model's probability of being added."""
    conf = d.get("confidence") or {}
    out = []
    for r in conf.get("rounds", []):
        probs = r["probabilities"]
        rows = []
        for c in r["comparison"]:
            key = "none" if c["model"].startswith("(") else c["model"]
            p = probs.get(key)
            se = "–" if c["se_diff"] is None else f"{c['se_diff']:.1f}"
            rows.append((c["model"], f"{c['elpd_diff']:.1f}", se, "–" if p is None else f"{p:.2f}"))
        out.append((r["round"], rows))
    return out


def _ambiguity_text(a: dict) -> str:
    first, second = a["families"][:2]
    if a.get("other_form"):
        form = a["other_form"][second]
        return (f"{first}, and {second} as {form} instead, explain the residual about equally well; {first} "
                f"was added; to separate them: {a['measurement']}")
    if a.get("added") is False:
        held = (f"{a['provisional']} stood in the model for the loss (not added) while the other families "
                f"were tried against it; " if a.get("provisional") else "")
        return (f"{first} and {second}: this record cannot tell them apart, so neither was added; "
                f"{held}to separate them: {a['measurement']}")
    return f"{first} and {second} explain the residual about equally well; to separate them: {a['measurement']}"


def _reshape_text(r: dict) -> str:
    if r["instead_of"] is None:  # no candidate passed against the baseline; this form did
        return (f"round {r['round']}: no family passed against the baseline, but {r['family']} as {r['to']} "
                f"instead of {r['from']} explained the residual (score {r['score']:.1f}): the candidates were "
                f"tried again against this form")
    return (f"round {r['round']}: {r['family']} as {r['to']} instead of {r['from']} explained the residual "
            f"better (score {r['score']:.1f}) than adding the round's best candidate, {r['instead_of']}: that "
            f"part of the residual was the shape of the {r['family']}; the next round started from this form")


def _confidence_intro(d: dict) -> str:
    conf = d.get("confidence") or {}
    return (f"Hold-out predictions compared by their expected log predictive density (the best model "
            f"first; SE of the difference over {conf.get('blocks', 0)} blocks: "
            f"{conf.get('block_rule', '')}); P(added): share of {conf.get('resamples', 0)} block-bootstrap "
            f"resamples of the record in which the rule adds that family in that round.")


def _markdown(diagnosis, assessment: dict, figures) -> str:
    d = diagnosis.to_json()
    parts = [f"# Diagnosis of {diagnosis.measurement.source}", ""]
    if outcome_line(assessment):
        parts += [f"**{outcome_line(assessment)}**", ""]
    if check_rows(assessment):
        parts += ["## The data", "", md_table(CHECK_HEAD, check_rows(assessment)), ""]
    parts += [f"{d['test']} test, {len(diagnosis.measurement)} rows; hold-out folds by {d['holdout']}.", "",
             f"**Verdict:** {d['verdict']}", "", "## Before and after", "",
             md_table(TABLE_HEAD, _rows(diagnosis)), ""]
    for n, effects, lines in _rounds(diagnosis):
        parts += [f"## Round {n} (model: {effects})", "", md_table(ROUND_HEAD, lines), ""]
    if _confidence_rounds(d):
        parts += ["## How sure", "", _confidence_intro(d), ""]
        for n, rows in _confidence_rounds(d):
            parts += [f"Round {n}:", "", md_table(CONFIDENCE_HEAD, rows), ""]
    if d["reshaped"]:
        parts += ["## Other forms", ""]
        parts += [f"- {_reshape_text(r)}" for r in d["reshaped"]]
        parts.append("")
    if d["ambiguous"]:
        parts += ["## Ambiguous", ""]
        parts += [f"- {_ambiguity_text(a)}" for a in d["ambiguous"]]
        parts.append("")
    parts += ["## Where the model fails", "", "Baseline:", ""]
    parts += [f"- {s}" for s in d["findings"]["baseline"]]
    parts += ["", "Final model:", ""]
    parts += [f"- {s}" for s in d["findings"]["final"]]
    w = d["whiteness"]
    parts += ["", f"Ljung–Box Q = {w['ljung_box_q']:.1f} over {w['lags']} lags, p = {w['p_value']:.3g}; "
              f"noise floor {w['noise_floor_rad'] * ARCSEC_PER_RAD:.2f} arcsec.", "", "## Figures", ""]
    parts += [f"![{f}]({f})" for f in figures]
    return "\n".join(parts) + "\n"


def _html(diagnosis, assessment: dict, figures) -> str:
    d = diagnosis.to_json()
    body = [f"<h1>Diagnosis of {html.escape(str(diagnosis.measurement.source))}</h1>"]
    if outcome_line(assessment):
        body.append(f"<p><b>{html.escape(outcome_line(assessment))}</b></p>")
    if check_rows(assessment):
        body += ["<h2>The data</h2>", html_table(CHECK_HEAD, check_rows(assessment))]
    body += [f"<p>{d['test']} test, {len(diagnosis.measurement)} rows; hold-out folds by "
            f"{html.escape(d['holdout'])}.</p>",
            f"<p><b>Verdict:</b> {html.escape(d['verdict'])}</p>", "<h2>Before and after</h2>",
            html_table(TABLE_HEAD, _rows(diagnosis))]
    for n, effects, lines in _rounds(diagnosis):
        body += [f"<h2>Round {n} (model: {html.escape(effects)})</h2>", html_table(ROUND_HEAD, lines)]
    if _confidence_rounds(d):
        body += ["<h2>How sure</h2>", f"<p>{html.escape(_confidence_intro(d))}</p>"]
        for n, rows in _confidence_rounds(d):
            body += [f"<p>Round {n}:</p>", html_table(CONFIDENCE_HEAD, rows)]
    if d["reshaped"]:
        body.append("<h2>Other forms</h2><ul>" + "".join(
            f"<li>{html.escape(_reshape_text(r))}</li>" for r in d["reshaped"]) + "</ul>")
    if d["ambiguous"]:
        body.append("<h2>Ambiguous</h2><ul>" + "".join(
            f"<li>{html.escape(_ambiguity_text(a))}</li>" for a in d["ambiguous"]) + "</ul>")
    body.append("<h2>Where the model fails</h2><p>Baseline:</p><ul>" +
                "".join(f"<li>{html.escape(s)}</li>" for s in d["findings"]["baseline"]) +
                "</ul><p>Final model:</p><ul>" +
                "".join(f"<li>{html.escape(s)}</li>" for s in d["findings"]["final"]) + "</ul>")
    body.append("<h2>Figures</h2>" + "".join(f'<p><img src="{f}" alt="{f}"></p>' for f in figures))
    return html_page("hdsim diagnosis", body)
