"""Which files of a report folder hdsim wrote: a manifest, so that a report written again
into the folder removes the figures of the last one that it does not write again.

A folder reused for a second report (another record, another test kind, a fit after a
diagnosis) had kept the first report's figures beside the new page, where a reader takes
them for the current result. Only files the previous manifest lists are removed, and only
while they are still the files hdsim wrote (same size and modification time): a file of
the user's, or one the user has since changed, stays.

The manifest is ``.hdsim-report.json`` in the folder: ``{"format": "hdsim-report-files-1",
"files": [{"name", "size", "mtime_ns"}, ...]}``, plain file names of the folder only. A
writer that shares its folder with others (a Sobol study's summary beside its study file,
several studies to a folder) keeps a manifest of its own, named for what it writes
(``manifest``), so that it removes only its own earlier files. A file is listed in one
manifest: a writer that may find its files listed in another (``other``) takes them over.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from hdsim.atomic import write_text_atomic

MANIFEST = ".hdsim-report.json"
FORMAT = "hdsim-report-files-1"
#: the pages a report writes into its folder (`hdsim.identification.report_page.Page.write`)
REPORT_PAGES = ("index.html", "index.md")


def _stamp(path: Path) -> dict | None:
    """``{"name", "size", "mtime_ns"}`` of a regular file, None for anything else."""
    try:
        st = path.stat()
    except OSError:
        return None
    if not path.is_file():
        return None
    return {"name": path.name, "size": st.st_size, "mtime_ns": st.st_mtime_ns}


def previous_files(folder: Path, manifest: str = MANIFEST) -> list[dict]:
    """The entries of the folder's manifest ``manifest``; none when it is missing or not one
    of ours (a manifest edited by hand is no reason to remove anything). Only plain file
    names, and never a manifest."""
    try:
        data = json.loads((folder / manifest).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return []
    if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("files"), list):
        return []
    out = []
    for entry in data["files"]:
        if not isinstance(entry, dict):
            continue
        name = entry.get("name")
        if isinstance(name, str) and name and name not in (".", "..", MANIFEST, manifest) and Path(name).name == name \
                and os.sep not in name and "/" not in name:
            out.append(entry)
    return out


def stale_files(folder: Path, previous: list[dict], written: set[str]) -> list[Path]:
    """Files of the previous report that this one did not write again and that are still as
    hdsim left them (same size and modification time)."""
    out = []
    for entry in previous:
        if entry["name"] in written:
            continue
        now = _stamp(folder / entry["name"])
        if now is not None and now["size"] == entry.get("size") and now["mtime_ns"] == entry.get("mtime_ns"):
            out.append(folder / entry["name"])
    return out


def replace_report_files(folder, written, manifest: str = MANIFEST, other: str | None = None,
                         claimed=()) -> list[Path]:
    """After a report has written ``written`` (paths) into ``folder``: remove the previous
    report's files it did not write again (`stale_files`), then record ``written`` as the
    folder's manifest ``manifest`` (default the report folder's own). Returns the files
    removed.

    ``other`` is another manifest of the folder that may list files of this writer's (those
    named ``claimed``: a Sobol summary's are the report folder's under ``--report`` and its
    stem's beside ``--out``, and one folder may be both): what it lists of them is a previous
    file too, and its entries pass to ``manifest``, so that no file is listed twice.

    The manifest is replaced last: a report stopped between the two leaves the old
    manifest, and the next report removes what it lists.
    """
    folder = Path(folder)
    mine = [Path(p) for p in written if Path(p).resolve().parent == folder.resolve()]
    names = {p.name for p in mine}
    theirs = previous_files(folder, other) if other else []
    taken = [e for e in theirs if e["name"] in claimed]
    removed = []
    for path in stale_files(folder, previous_files(folder, manifest) + taken, names):
        try:
            path.unlink()
        except FileNotFoundError:
            continue
        removed.append(path)
    _record(folder, manifest, [s for s in (_stamp(folder / name) for name in sorted(names)) if s is not None])
    if taken:
        _record(folder, other, [e for e in theirs if e not in taken])
    return removed


def _record(folder: Path, manifest: str, stamps: list[dict]) -> None:
    """Write the manifest ``manifest`` listing ``stamps``; one that would list none goes."""
    if not stamps:
        return (folder / manifest).unlink(missing_ok=True)
    write_text_atomic(folder / manifest, json.dumps({"format": FORMAT, "files": stamps}, indent=1) + "\n")
