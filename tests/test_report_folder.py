"""A report folder used again holds only the new report: the figures of the last one that
the new page does not show are removed, and nothing hdsim did not write (docs/cli.md,
``--report DIR``). Hand-built pages; every report page is written by `Page.write`."""

from __future__ import annotations

import json
import os

from hdsim.io.report_files import MANIFEST
from hdsim.identification.report_page import Page


def _page(folder, *figures):
    page = Page("report")
    for name in figures:
        (folder / name).write_bytes(b"PNG of " + name.encode())  # as save() leaves it, before the page
        page.figure(folder / name, name)
    return page.write(folder)


def test_a_second_report_removes_the_figures_of_the_first_it_does_not_show(tmp_path):
    _page(tmp_path, "error_fall.png", "residual_vs_time.png", "residual_spectrum.png")
    (tmp_path / "notes.txt").write_text("mine")
    _page(tmp_path, "residual_vs_time.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == [MANIFEST, "index.html", "index.md", "notes.txt",
                                                          "residual_vs_time.png"]
    listed = json.loads((tmp_path / MANIFEST).read_text())["files"]
    assert [e["name"] for e in listed] == ["index.html", "index.md", "residual_vs_time.png"]
    _page(tmp_path)  # a page without figures (a record of the wrong test) leaves none of the last
    assert sorted(p.name for p in tmp_path.iterdir()) == [MANIFEST, "index.html", "index.md", "notes.txt"]


def test_a_listed_file_the_user_has_changed_since_stays(tmp_path):
    _page(tmp_path, "a.png", "b.png")
    (tmp_path / "b.png").write_bytes(b"the user's own figure, saved over hdsim's")
    os.utime(tmp_path / "b.png", ns=(1, 1))
    _page(tmp_path, "c.png")
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["b.png", "c.png"]


def test_a_manifest_that_is_not_hdsims_removes_nothing(tmp_path):
    (tmp_path / "keep.png").write_bytes(b"x")
    outside = tmp_path.parent / f"{tmp_path.name}-outside.png"
    outside.write_bytes(b"x")
    # each entry with its own file's size and time: only the name may protect the file outside
    entries = [{"name": n, "size": 1, "mtime_ns": path.stat().st_mtime_ns}
               for n, path in (("keep.png", tmp_path / "keep.png"), (f"../{outside.name}", outside))]
    (tmp_path / MANIFEST).write_text(json.dumps({"format": "something else", "files": entries}))
    _page(tmp_path)
    assert (tmp_path / "keep.png").exists() and outside.exists()
    (tmp_path / MANIFEST).write_text(json.dumps({"format": "hdsim-report-files-1", "files": entries[1:]}))
    _page(tmp_path)  # a name outside the folder is never one of its files
    assert outside.exists()
