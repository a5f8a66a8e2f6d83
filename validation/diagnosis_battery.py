"""The diagnosis battery of issue 5's done-when list, with its rates printed.

    python validation/diagnosis_battery.py [--seeds 10] [--first-seed 0] [--workers 2]
                                           [--only full,nothing] [--merge earlier.json]

Data come from ``tests/truth.py`` (independent forms: Bouc–Wen friction, cubic/sinh
hardening, a smooth series dead zone, constant-damping-ratio damping, a springpot
outside the library), so this measures discovery, not self-consistency. Every case is
one ``diagnose`` call; the table lists, per group, how often the hidden family was
ranked first and added first, how often the final error was at most half the baseline,
and for the control groups how often anything was added or success claimed. Results
go to ``validation/results/diagnosis_battery.json`` (atomically).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE.parent))  # this checkout's hdsim, whatever an editable install points at

FAMILIES = ("hardening", "backlash", "friction", "damping")
#: group name -> list of (hidden families, baseline families)
GROUPS = {
    **{f"full:{f}": ((f,), tuple(g for g in FAMILIES if g != f)) for f in FAMILIES},
    **{f"companion:{f}": ((f,), ("hardening",) if f in ("friction", "backlash") else ("friction",))
       for f in FAMILIES},
    "ke:kinematic_error": (("kinematic_error",), ("friction",)),
    **{f"nothing:{'+'.join(b)}": ((), b) for b in
       (("hardening", "friction"), ("friction", "damping"), ("hardening", "backlash"), FAMILIES)},
    "two:hardening+backlash": (("hardening", "backlash"), ()),
    "two:friction+damping": (("friction", "damping"), ("hardening", "backlash")),
    "outside:rate_dependent_unknown": (("rate_dependent_unknown",), ("hardening",)),
}


def run_case(group: str, seed: int) -> dict:
    import truth
    from hdsim.identification.diagnosis import diagnose
    from hdsim.io.measurement import make_measurement

    hidden, base = GROUPS[group]
    start = time.perf_counter()
    if group.startswith("ke:"):
        cols, _ = truth.make_ke_data(set(hidden), set(base), seed=seed)
        meas = make_measurement("kinematic_error", cols["time_s"], cols["torque_Nm"],
                                cols["output_angle_rad"], wg_angle=cols["wg_angle_rad"],
                                ratio=100.0, rated_torque=87.0)
    else:
        cols, _ = truth.make_stiffness_data(set(hidden), set(base), seed=seed)
        meas = make_measurement("stiffness", cols["time_s"], cols["torque_Nm"], cols["angle_rad"],
                                rated_torque=87.0)
    report = diagnose(meas, list(base))
    j = report.to_json()
    return {"group": group, "seed": seed, "hidden": list(hidden), "added": j["added"],
            "ranking": [(r["family"], r["score"]) for r in j["ranking"]],
            "baseline_rmse": j["baseline"]["rmse_rad"], "final_rmse": j["final"]["rmse_rad"],
            "success": bool(report.success), "seconds": time.perf_counter() - start}


def summarise(rows: list[dict]) -> list[str]:
    lines = [f"{'group':34s} {'n':>3s} {'first':>6s} {'halved':>6s} {'added':>6s} {'success':>7s}"]
    for group in GROUPS:
        sel = [r for r in rows if r["group"] == group]
        if not sel:
            continue
        n = len(sel)
        hidden = sel[0]["hidden"]
        if group.startswith(("nothing", "outside")):
            first = "—"  # nothing of the library is hidden: only "added" and "success" apply
        elif len(hidden) == 1:
            first = f"{sum(bool(r['ranking']) and r['ranking'][0][0] == hidden[0] and r['added'][:1] == hidden for r in sel) / n:.0%}"
        else:  # two hidden: both added
            first = f"{sum(set(hidden) <= set(r['added']) for r in sel) / n:.0%}"
        halved = sum(r["final_rmse"] <= 0.5 * r["baseline_rmse"] for r in sel)
        added = sum(bool(r["added"]) for r in sel)
        success = sum(r["success"] for r in sel)
        lines.append(f"{group:34s} {n:3d} {first:>6s} {halved / n:6.0%} {added / n:6.0%} "
                     f"{success / n:7.0%}")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--only", default="", help="comma-separated group prefixes (full, nothing …)")
    parser.add_argument("--merge", type=Path, action="append", default=[],
                        help="add the cases of an earlier run's JSON to the table")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "diagnosis_battery.json")
    args = parser.parse_args(argv)
    prefixes = [p for p in args.only.split(",") if p]
    groups = [g for g in GROUPS if not prefixes or any(g.startswith(p) for p in prefixes)]
    cases = [(g, s) for g in groups for s in range(args.first_seed, args.first_seed + args.seeds)]
    from tqdm import tqdm

    rows = []
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [pool.submit(run_case, g, s) for g, s in cases]
        for future in tqdm(futures, desc="battery", unit="case"):
            rows.append(future.result())
    for earlier in args.merge:
        rows += json.loads(earlier.read_text())["cases"]
    lines = summarise(rows)
    print("\n".join(lines))
    from hdsim.atomic import write_text_atomic

    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(args.out, json.dumps({"table": lines, "cases": rows}, indent=1))


if __name__ == "__main__":
    main()
