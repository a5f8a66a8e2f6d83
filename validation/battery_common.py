"""What the validation batteries share: running cases in processes, and writing results.

A case is a ``(group, seed)`` pair and a runner a picklable function of it that never
raises; a worker that dies anyway still gives a row (``failed_row``), so a battery never
crashes on one case. Results are written atomically (`hdsim.atomic.write_text_atomic`).
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path


def run_in_processes(run_case, cases, workers: int, description: str, failed_row, progress: bool = True) -> list:
    """``[run_case(group, seed) for group, seed in cases]``, in ``workers`` processes when > 1.

    Parameters
    ----------
    run_case : callable
        ``run_case(group, seed) -> dict`` (picklable: a module-level function or a partial of one).
    cases : list of tuple
        ``(group, seed)`` pairs.
    workers : int
        Processes (1: in this process).
    description : str
        Label of the progress bar (tqdm, when installed).
    failed_row : callable
        ``failed_row(group, seed, error_text) -> dict``: the row of a case whose worker died.
    progress : bool
        Show a progress bar.

    Returns
    -------
    list of dict
        One row per case, in case order.
    """
    try:
        from tqdm import tqdm
    except ImportError:  # progress is a nicety
        tqdm = None
    show = (lambda items: tqdm(items, desc=description, unit="case")) if tqdm and progress else (lambda items: items)
    if workers <= 1:
        return [run_case(g, s) for g, s in show(cases)]
    rows = []
    with ProcessPoolExecutor(workers) as pool:
        futures = [pool.submit(run_case, g, s) for g, s in cases]
        for (g, s), future in zip(cases, show(futures)):
            try:
                rows.append(future.result())
            except Exception as exc:  # a worker died: still a failed case, not a crash
                rows.append(failed_row(g, s, f"worker failed: {type(exc).__name__}: {exc}"))
    return rows


def added_rates(rows: list, hidden) -> dict:
    """What a group's diagnoses added against what its truth hid: ``runs``, ``errors`` (rows
    whose ``added`` is None), ``first_pick`` (first addition a hidden family; None when
    nothing is hidden), ``exactly_hidden`` and ``spurious`` (anything beyond the hidden),
    the rates over all runs."""
    hidden = set(hidden)
    ok = [r for r in rows if r["added"] is not None]
    first = [r for r in ok if r["added"][:1] and r["added"][0] in hidden]
    return {"runs": len(rows), "errors": len(rows) - len(ok),
            "first_pick": len(first) / len(rows) if hidden else None,
            "exactly_hidden": sum(set(r["added"]) == hidden for r in ok) / len(rows),
            "spurious": sum(bool(set(r["added"]) - hidden) for r in ok) / len(rows)}


def write_json_atomic(path: Path, obj) -> None:
    """Write ``obj`` as indented JSON to ``path`` atomically (temporary file, then rename)."""
    from hdsim.atomic import write_text_atomic

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, json.dumps(obj, indent=1, default=str))


def battery_main(doc: str, groups, run_case, failed_row, table, *, seeds: int, out: str, label: str,
                 argv=None, here: Path | None = None) -> int:
    """The command line of a small battery: ``--seeds``, ``--first-seed``, ``--workers``,
    ``--only`` (group prefixes) and ``--out`` (a name in ``results/``); runs every
    (group, seed), prints ``table(rows)`` one line per group and writes the rows and the
    table atomically."""
    import argparse

    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=seeds)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--only", default="", help="comma-separated group prefixes")
    ap.add_argument("--out", default=out)
    args = ap.parse_args(argv)
    chosen = [g for g in groups if not args.only or any(g.startswith(x) for x in args.only.split(","))]
    cases = [(g, s) for g in chosen for s in range(args.first_seed, args.first_seed + args.seeds)]
    rows = run_in_processes(run_case, cases, args.workers, label, failed_row)
    summary = table(rows)
    for group, line in summary.items():
        print(f"{group:24s} " + "  ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                                          for k, v in line.items()))
    write_json_atomic((here or Path(__file__).resolve().parent) / "results" / args.out,
                      {"seeds": [args.first_seed, args.first_seed + args.seeds - 1], "summary": summary,
                       "rows": rows})
    return 0

