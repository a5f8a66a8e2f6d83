"""The parts every report page shares, whatever its test kind: figures drawn with
matplotlib's object API, tables in HTML and Markdown, the outcome line and the checks.

The figures use no pyplot and select no backend, so writing a report leaves the backend
of the calling process as it was; everything is written atomically.
"""

from __future__ import annotations

import html
from pathlib import Path

from hdsim.atomic import write_text_atomic
from hdsim.io.figures import save_figure

__all__ = ["new_figure", "save", "html_table", "md_table", "outcome_line", "check_rows", "CHECK_HEAD",
           "html_page", "write_wrong_test_report"]

CHECK_HEAD = ("status", "check", "what the data say")
STYLE = ("body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}"
         "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 8px;"
         "font-size:90%}img{max-width:100%}")


def new_figure(figsize: tuple[float, float]):
    """A matplotlib figure of ``figsize`` [in] (matplotlib is imported on first use:
    reading a diagnosis does not need it)."""
    from matplotlib.figure import Figure

    return Figure(figsize=figsize)


def save(fig, path: Path) -> Path:
    save_figure(fig, path, dpi=110, bbox_inches="tight")
    return path


def md_table(head, rows) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def html_table(head, rows) -> str:
    out = ["<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>"]
    out += ["<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in rows]
    return "\n".join(out) + "</table>"


def outcome_line(assessment: dict) -> str:
    """The outcome and what to record next, in words, or '' without an assessment."""
    if not assessment.get("outcome"):
        return ""
    text = f"Outcome: {assessment['outcome'].replace('_', ' ')}"
    return text + (f"; to decide, record {assessment['next_measurement']}" if assessment.get("next_measurement")
                   else "")


def check_rows(assessment: dict) -> list:
    return [(c["status"], c["check"], c["message"]) for c in assessment.get("checks", [])]


def html_page(title: str, body: list[str]) -> str:
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{STYLE}</style></head><body>{''.join(body)}</body></html>\n")


def write_wrong_test_report(measurement, folder, summary: dict) -> Path:
    """The page of a record that is not the test it claims: the verdict and the checks that
    say what it looks like (nothing was fitted). Returns ``index.html``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    title = f"Diagnosis of {measurement.source}"
    md = [f"# {title}", "", f"**{outcome_line(summary)}**", "", summary["verdict"], "", "## The data", "",
          md_table(CHECK_HEAD, check_rows(summary)), ""]
    write_text_atomic(folder / "index.md", "\n".join(md))
    body = [f"<h1>{html.escape(title)}</h1>", f"<p><b>{html.escape(outcome_line(summary))}</b></p>",
            f"<p>{html.escape(summary['verdict'])}</p>", "<h2>The data</h2>",
            html_table(CHECK_HEAD, check_rows(summary))]
    page = folder / "index.html"
    write_text_atomic(page, html_page("hdsim diagnosis", body))
    return page
