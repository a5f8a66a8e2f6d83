"""The report page of a diagnosis, the same for every test kind.

A page is a list of blocks (headings, paragraphs, tables, lists, figures) rendered twice:
``index.html``, self-contained (each figure embedded as a base64 PNG, nothing fetched),
and ``index.md`` (figures by file name). The sections every diagnosis has (outcome,
verdict, data checks, before/after table, the rounds, how sure, other forms, ambiguous
pairs, where the model fails) are written here from the diagnosis and its JSON, in the
kind's report unit; a test kind adds its own figures and sections
(`hdsim.identification.test_kinds.TestKind.report_figures` / ``report_sections``).

Figures use matplotlib's object API (no pyplot, no backend selected), so writing a report
leaves the backend of the calling process as it was; every file is written atomically.
"""

from __future__ import annotations

import base64
import hashlib
import html
import math
import sys
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from hdsim.atomic import write_text_atomic
from hdsim.io.report_files import replace_report_files
from hdsim.io.figures import save_figure

__all__ = ["Page", "new_figure", "save", "step_label", "diagnosis_page", "wrong_test_page", "rounded", "provenance",
           "fit_page"]

STYLE = ("body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}"
         "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 8px;font-size:90%}"
         "img{max-width:100%}figcaption{font-size:90%;color:#444}")
CHECK_HEAD = ("status", "check", "what the data say")
#: column names of the error figures a kind reports (its JSON key less the unit)
ERROR_NAMES = {"rmse": "rms", "max_abs_error": "max", "holdout_rmse": "hold-out rms"}


def new_figure(figsize: tuple[float, float]):
    """A matplotlib figure of ``figsize`` [in] (matplotlib is imported on first use:
    reading a diagnosis does not need it)."""
    from matplotlib.figure import Figure

    return Figure(figsize=figsize)


def save(fig, path: Path) -> Path:
    return save_figure(fig, path, dpi=110, bbox_inches="tight")


def step_label(step) -> str:
    return "+".join(step.effects) or "base"


@dataclass
class Page:
    """Blocks of a page, in reading order; `write` renders them as HTML and Markdown."""

    title: str
    blocks: list = field(default_factory=list)

    def _add(self, kind: str, value, shown=True) -> "Page":
        """Append a block, unless ``shown`` is empty (an empty text, table or list is left out)."""
        if shown:
            self.blocks.append((kind, value))
        return self

    def heading(self, text: str) -> "Page":
        return self._add("h2", text)

    def text(self, text: str, strong: bool = False) -> "Page":
        return self._add("strong" if strong else "p", text, text)

    def table(self, head, rows) -> "Page":
        rows = [tuple(r) for r in rows]  # any iterable: a generator is empty only once read
        return self._add("table", (tuple(head), rows), rows)

    def bullets(self, items) -> "Page":
        items = list(items)
        return self._add("ul", items, items)

    def figure(self, path: Path, caption: str) -> "Page":
        return self._add("figure", (Path(path), caption))

    def markdown(self) -> str:
        out = [f"# {self.title}", ""]
        for kind, value in self.blocks:
            if kind == "h2":
                out += [f"## {value}", ""]
            elif kind in ("p", "strong"):
                out += [f"**{value}**" if kind == "strong" else value, ""]
            elif kind == "table":
                head, rows = value
                out += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
                out += ["| " + " | ".join(r) + " |" for r in rows] + [""]
            elif kind == "ul":
                out += [f"- {item}" for item in value] + [""]
            else:
                path, caption = value
                out += [f"![{caption}]({path.name})", "", f"*{caption}*", ""]
        return "\n".join(out)

    def html(self) -> str:
        esc = html.escape
        body = [f"<h1>{esc(self.title)}</h1>"]
        for kind, value in self.blocks:
            if kind == "h2":
                body.append(f"<h2>{esc(value)}</h2>")
            elif kind in ("p", "strong"):
                body.append(f"<p><b>{esc(value)}</b></p>" if kind == "strong" else f"<p>{esc(value)}</p>")
            elif kind == "table":
                head, rows = value
                body.append("<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in head) + "</tr>"
                            + "".join("<tr>" + "".join(f"<td>{esc(c)}</td>" for c in r) + "</tr>" for r in rows)
                            + "</table>")
            elif kind == "ul":
                body.append("<ul>" + "".join(f"<li>{esc(item)}</li>" for item in value) + "</ul>")
            else:  # embedded: the page is one file that can be sent on its own
                path, caption = value
                data = base64.b64encode(path.read_bytes()).decode("ascii")
                body.append(f'<figure><img src="data:image/png;base64,{data}" alt="{esc(caption)}">'
                            f"<figcaption>{esc(caption)}</figcaption></figure>")
        return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{esc(self.title)}</title>"
                f"<style>{STYLE}</style></head><body>{''.join(body)}</body></html>\n")

    def write(self, folder) -> Path:
        """Write ``index.md`` and ``index.html`` into ``folder``; returns ``index.html``. The
        files of an earlier report in ``folder`` that this page does not show are removed
        (`hdsim.io.report_files`): a reader takes every figure there for this one's."""
        folder = Path(folder)
        write_text_atomic(folder / "index.md", self.markdown())
        write_text_atomic(folder / "index.html", self.html())
        figures = [value[0] for kind, value in self.blocks if kind == "figure"]
        replace_report_files(folder, [folder / "index.md", folder / "index.html", *figures])
        return folder / "index.html"


def rounded(value: float, sigma: float | None) -> str:
    """``value ± sigma`` with the value rounded to the uncertainty's second significant digit
    (no more digits than the data determine); the value to 4 digits when there is none."""
    if sigma is None or not math.isfinite(sigma) or sigma <= 0:
        return f"{value:.4g}"
    scientific = abs(value) >= 1e5 or abs(value) < 1e-3  # then the mantissa to the uncertainty's digits
    exponent = int(math.floor(math.log10(abs(value)))) if scientific and value else 0
    scale = 10.0 ** exponent
    digits = 1 - int(math.floor(math.log10(sigma / scale)))  # negative: tens, hundreds … (14624 ± 37247)
    shown = f"{round(value / scale, digits):.{max(digits, 0)}f} ± {round(sigma / scale, digits):.{max(digits, 0)}f}"
    return f"({shown})e{exponent:+d}" if scientific else shown


def provenance(measurement) -> list[tuple[str, str]]:
    """What reproduces a page: the hdsim version, the date, the command and the data's SHA-256."""
    from hdsim._version import __version__

    rows = [("hdsim", __version__), ("written", datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")),
            ("command", " ".join(["hdsim", *sys.argv[1:]]) if Path(sys.argv[0]).name == "hdsim"
             else "Python: " + " ".join(sys.argv)), ("data", str(measurement.source))]
    source = Path(str(measurement.source))
    if source.is_file():
        rows.append(("data SHA-256", hashlib.sha256(source.read_bytes()).hexdigest()))
    return rows


def _floor_key(kind) -> str:
    """The JSON key of the noise floor in the kind's error unit (``noise_floor_rad`` …)."""
    return "noise_floor_" + kind.error_key.split("_", 1)[1]


def _summary_box(page: Page, d: dict, kind) -> None:
    """One sentence of outcome, the families added, the error before → after against the
    noise floor, and the next measurement: the page in four lines."""
    unit, scale = kind.report_unit
    key, floor = kind.error_key, d["whiteness"].get(_floor_key(kind))
    page.table(("summary", ""), [
        ("outcome", d.get("outcome", "").replace("_", " ") or "—"),
        ("added", ", ".join(d["added"]) or "nothing"),
        (f"rms [{unit}]", f"{d['baseline'][key] * scale:.3g} → {d['final'][key] * scale:.3g}"
         + (f" (noise floor {floor * scale:.3g})" if floor else "")),
        ("next measurement", d.get("next_measurement")
         or ("none needed" if d.get("outcome") in ("found", "nothing_missing") else "—"))])


def _parameters(page: Page, fitted: dict, kind, result) -> None:
    """The fitted values (a fit's JSON: ``params`` or ``fitted``, and ``uncertainty``) rounded
    to their uncertainty, with each one's unit (`TestKind.parameter_unit`)."""
    values = fitted.get("params") or fitted.get("fitted") or {}
    sigma = fitted.get("uncertainty") or {}
    rows = [(name, f"{float(v):.4g} (not determined by the record)" if name in sigma and sigma[name] is None
             else rounded(float(v), sigma.get(name)), kind.parameter_unit(result, name)) for name, v in values.items()]
    if rows:
        page.heading(kind.parameters_heading).table(("parameter", "value ± standard uncertainty", "unit"), rows)


def _predictions(page: Page, kind, fit, scale_numbers, whiteness: dict | None = None) -> None:
    """What the fitted drive predicts for the maker's tests, with 95 % bands
    (`TestKind.predictions`), and beside them the caveat of a model the verdict does not call
    explained (`hdsim.identification.predictions.misfit_caveat`; ``whiteness``: the dict the
    page's verdict reads, default `TestKind.residual_whiteness` of ``fit``); nothing for a
    kind without predictions."""
    from hdsim.identification.predictions import misfit_caveat

    predictions = kind.predictions(fit, scale_numbers)
    if not predictions:
        return
    rows = []
    for p in predictions:
        banded = math.isfinite(p.low) and math.isfinite(p.high) and p.high > p.low
        # every number of a row to the band's second significant digit: no digit the fit
        # does not determine
        digits = 1 - int(math.floor(math.log10((p.high - p.low) / 2))) if banded else None

        def shown(x, d=digits):
            if d is None:
                return f"{x:.4g}"
            if d > 6 and x:  # a tiny figure: its mantissa to the same digit, not a row of zeros
                return f"{x:.{max(int(math.floor(math.log10(abs(x)))) + d, 0)}e}"
            return f"{round(x, d):.{max(d, 0)}f}"

        rows.append((p.label, f"{shown(p.value)} {p.unit}", f"{shown(p.low)} – {shown(p.high)}" if banded else "—",
                     "—" if p.datasheet is None else f"{p.datasheet:.6g}", p.method))
    page.heading("What the fitted drive predicts")
    page.text("The fitted drive put through the tests of the maker's datasheet, each with a 95 % band "
              "propagated from the fit's covariance.")
    # on the pages only: neither `fit --json` nor `diagnose --json` carries the predictions (no key
    # added to the JSON contract), and there the verdict and ``whiteness.explained`` say it already
    page.text(misfit_caveat(kind.residual_whiteness(fit) if whiteness is None else whiteness), strong=True)
    page.table(("test", "fitted drive", "95 % band", "datasheet", "band by"), rows)


def _top(page: Page, summary: dict) -> Page:
    """Outcome, verdict and the data checks: what a reader needs before any table."""
    if summary.get("outcome"):
        line = f"Outcome: {summary['outcome'].replace('_', ' ')}"
        if summary.get("next_measurement"):
            line += f"; to decide, record {summary['next_measurement']}"
        page.text(line, strong=True)
    page.text(f"Verdict: {summary['verdict']}" if summary.get("verdict") else "")
    return _checks(page, summary)


def _checks(page: Page, summary: dict) -> Page:
    """The data checks of ``summary`` as a table under "The data" (nothing without checks)."""
    checks = [(c["status"], c["check"], c["message"]) for c in summary.get("checks", [])]
    return page.heading("The data").table(CHECK_HEAD, checks) if checks else page


def wrong_test_page(measurement, folder, summary: dict) -> Path:
    """The page of a record that is not the test it claims: the verdict and the checks that
    say what it looks like (nothing was fitted). Returns ``index.html``."""
    page = _top(Page(f"Diagnosis of {measurement.source}"), summary)
    return page.heading("Reproduce").table(("", ""), provenance(measurement)).write(folder)


def _number(value, scale: float) -> str:
    if value is None:
        return ""
    if isinstance(value, (list, tuple)):
        return ", ".join(_number(v, scale) for v in value)
    return f"{value * scale:.4g}"


def _before_after(kind, d: dict, unit: str, scale: float):
    # the error columns of the table: those in the kind's error unit (``_rad`` …)
    keys = [k for k in d["table"][0] if k.endswith("_" + kind.error_key.split("_", 1)[1])]
    head = ["step", "effects", "added"] + [
        f"{ERROR_NAMES.get(k.rsplit('_', 1)[0], k)} [{unit}]" for k in keys] + ["score"]
    rows = []
    for row in d["table"]:
        changed = ", ".join(f"{f} as {e}" for f, e in (row.get("other_form") or {}).items())
        held = f"{row['provisional']} (stand-in, not added)" if row.get("provisional") else ""
        rows.append([str(row["step"]), "+".join(row["effects"]) or "base", row["added"] or changed or held]
                    + [_number(row[k], scale) for k in keys]
                    + ["" if row["score"] is None else f"{row['score']:.1f}"])
    return head, rows


def _round_rows(kind, step, scale: float, by_share: bool) -> list:
    tried = [(c, c.family) for c in sorted(step.candidates, key=lambda c: c.score)]
    tried += [(c, f"{c.family} in another form") for c in sorted(step.reshapes, key=lambda c: c.score)]
    rows = []
    for c, label in tried:
        if c.fit is None:  # could not be fitted: the reason says why
            rows.append([label, c.effect, "–", "–", "–"] + (["–"] if by_share else []) + [c.reason])
            continue
        gain = ", ".join(_percent(g) for g in c.holdout_gain)
        if "pooled_holdout_gain" in c.figures:
            gain = f"{_percent(c.figures['pooled_holdout_gain'])} ({gain})"
        rows.append([label, c.effect, f"{c.score:.1f}", _number(kind.fit_errors(c.fit)[kind.error_key], scale),
                     gain] + ([_percent(c.share)] if by_share else []) + [c.reason])
    return rows


def _percent(fraction: float) -> str:
    """A fraction as a whole percentage; a value that rounds to zero is "0 %", never "-0 %"."""
    return f"{round(100 * fraction) + 0:.0f} %"


def _ambiguity_text(a: dict) -> str:
    first, second = a["families"][:2]
    if a.get("other_form"):
        held = "was added" if a.get("added") else "was in the baseline"
        return (f"{first}, and {second} as {a['other_form'][second]} instead, explain the residual about "
                f"equally well; {first} {held}; to separate them: {a['measurement']}")
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


def _confidence(page: Page, conf: dict) -> None:
    if not conf.get("rounds"):
        return
    page.heading("How sure").text(
        f"Hold-out predictions compared by their expected log predictive density (the best model first; SE "
        f"of the difference over {conf.get('blocks', 0)} blocks: {conf.get('block_rule', '')}); P(added): "
        f"share of {conf.get('resamples', 0)} block-bootstrap resamples of the record in which the rule adds "
        f"that family in that round.")
    for r in conf["rounds"]:
        rows = []
        for c in r["comparison"]:
            p = r["probabilities"].get("none" if c["model"].startswith("(") else c["model"])
            rows.append((c["model"], f"{c['elpd_diff']:.1f}", "–" if c["se_diff"] is None else f"{c['se_diff']:.1f}",
                         "–" if p is None else f"{p:.2f}"))
        page.text(f"Round {r['round']}:").table(("model", "Δelpd [nats]", "SE", "P(added)"), rows)


def _residual_vs_time(measurement, fits: list, folder: Path, unit: str, scale: float) -> tuple:
    """Residual against time of each (label, fit): stick-slip, drift and the joins of
    concatenated runs show there first."""
    t = np.asarray(measurement.time, dtype=float)
    ax = new_figure((10, 3.5)).subplots()
    for label, fit in fits:
        rows = getattr(fit, "rows", None)
        r = np.asarray(fit.residual, dtype=float)
        ax.plot(t, (r if rows is None else np.where(rows, r, np.nan)) * scale, lw=0.6, label=label)
    ax.set(xlabel="time [s]", ylabel=f"residual [{unit}]", title="residual vs time")
    ax.legend(fontsize=8)
    return save(ax.figure, folder / "residual_vs_time.png"), "Residual (measured − model) against time."


def _error_fall(diagnosis, folder: Path, unit: str, scale: float) -> tuple:
    """The error of every step against the noise floor."""
    kind, steps = diagnosis.kind, diagnosis.steps
    ax = new_figure((7, 4)).subplots()
    keys = list(kind.fit_errors(steps[0].fit))
    x = np.arange(len(steps))
    width = 0.8 / len(keys)
    for j, key in enumerate(keys):
        ax.bar(x + (j - (len(keys) - 1) / 2) * width, [kind.fit_errors(s.fit)[key] * scale for s in steps], width,
               label=f"{ERROR_NAMES.get(key.rsplit('_', 1)[0], key)} error")
    floor = diagnosis.whiteness.get(_floor_key(kind))
    if floor:
        ax.axhline(floor * scale, color="k", ls=":", lw=1, label="noise floor (final residual)")
    ax.set_xticks(x, [step_label(s) for s in steps], rotation=15, fontsize=8)
    ax.set(ylabel=f"error [{unit}]", yscale="log", title="error after each step")
    ax.legend(fontsize=8)
    return save(ax.figure, folder / "error_fall.png"), "The error of every step's model against the noise floor."


def diagnosis_page(diagnosis, folder, summary: dict, scale_numbers) -> Path:
    """Write the figures and the page of a diagnosis of any test kind into ``folder``.

    Parameters
    ----------
    diagnosis : hdsim.identification.engine.Diagnosis
        The finished diagnosis.
    folder : str or os.PathLike
        Output folder, created if missing.
    summary : dict
        The diagnosis JSON with ``outcome``, ``next_measurement`` and ``checks``, as
        ``hdsim diagnose --json`` prints it (a bare ``diagnosis.to_json()`` does too).
    scale_numbers : hdsim.model.datasheet.DriveScale or None
        The drive's datasheet numbers, for the kind's figures.

    Returns
    -------
    pathlib.Path
        ``index.html``.
    """
    folder = Path(folder)
    kind = diagnosis.kind
    unit, scale = kind.report_unit
    d = {**diagnosis.to_json(), **summary}
    page = Page(f"Diagnosis of {diagnosis.measurement.source}")
    _summary_box(page, d, kind)
    page = _top(page, d)
    page.text(f"{kind.name.replace('_', ' ')} test, {len(diagnosis.measurement)} rows; hold-out folds by "
              f"{d['holdout']}.")
    page.heading("Before and after").table(*_before_after(kind, d, unit, scale))
    by_share = kind.thresholds.min_share > 0
    head = (["family", "effect", "score", f"rms [{unit}]", "hold-out gain"] + (["share explained"] if by_share else [])
            + ["decision"])
    for n, step in enumerate(diagnosis.steps, start=1):
        if step.candidates:
            page.heading(f"Round {n} (model: {step_label(step)})").table(head, _round_rows(kind, step, scale, by_share))
    _confidence(page, d.get("confidence") or {})
    if d["reshaped"]:
        page.heading("Other forms").bullets(_reshape_text(r) for r in d["reshaped"])
    if d["ambiguous"]:
        page.heading("Ambiguous").bullets(_ambiguity_text(a) for a in d["ambiguous"])
    if d["findings"]["baseline"] or d["findings"]["final"]:
        page.heading("Where the model fails").text("Baseline:").bullets(d["findings"]["baseline"])
        page.text("Final model:").bullets(d["findings"]["final"])
    w = d["whiteness"]
    page.text(f"Ljung–Box Q = {w['ljung_box_q']:.1f}, p = {w['p_value']:.3g}." if "ljung_box_q" in w else "")
    _parameters(page, d["final"], kind, diagnosis.final.fit)
    _predictions(page, kind, diagnosis.final.fit, scale_numbers, diagnosis.whiteness)  # the verdict's
    for heading, head_rows in kind.report_sections(diagnosis, d):
        page.heading(heading).table(*head_rows)
    fits = [(step_label(step), step.fit) for step in diagnosis.steps]
    figures = [_residual_vs_time(diagnosis.measurement, fits, folder, unit, scale)]
    figures += kind.report_figures(diagnosis, folder, scale_numbers) + [_error_fall(diagnosis, folder, unit, scale)]
    return _close(page, figures, diagnosis.measurement, folder)


def fit_page(result, folder, summary: dict, kind, scale_numbers=None) -> Path:
    """Write the page of a fit (``hdsim fit --report DIR``) into ``folder``: a summary, the
    data checks, the fitted parameters rounded to their uncertainty, the residual against
    time and the kind's figures of a fit (`TestKind.fit_figures`), and how to reproduce it.
    Returns ``index.html``."""
    folder = Path(folder)
    unit, scale = kind.report_unit
    meas = result.measurement
    floor = summary.get(_floor_key(kind)) or (summary.get("whiteness") or {}).get(_floor_key(kind))
    page = Page(f"Fit of {meas.source}")
    page.table(("summary", ""), [
        ("test", meas.test.replace("_", " ")), ("effects", ", ".join(result.families) or "the base model"),
        ("rows fitted", str(summary.get("rows", result.n))),
        (f"rms [{unit}]", f"{summary[kind.error_key] * scale:.3g}" + (f" (noise floor {floor * scale:.3g})"
                                                                     if floor else ""))])
    _checks(page, summary)
    for heading, (head, rows) in kind.fit_sections(result, summary):
        page.heading(heading).table(head, rows)
    _parameters(page, summary, kind, result)
    _predictions(page, kind, result, scale_numbers)
    figures = [_residual_vs_time(meas, [("+".join(result.families) or "base", result)], folder, unit, scale)]
    figures += kind.fit_figures(result, folder, scale_numbers)
    return _close(page, figures, meas, folder)


def _close(page: Page, figures: list, measurement, folder: Path) -> Path:
    """The figures and how to reproduce the page, the end of every page with figures; writes
    the page into ``folder`` and returns ``index.html``."""
    page.heading("Figures")
    for path, caption in figures:
        page.figure(path, caption)
    return page.heading("Reproduce").table(("", ""), provenance(measurement)).write(folder)

