"""The running-torque diagnosis battery: does ``diagnose`` find the family hidden in a friction sweep?

    python validation/running_torque_battery.py [--seeds 6] [--first-seed 0] [--workers 2]
                                                [--only nothing,friction,two] [--max-rows N]

Data come from ``tests/truth_running.py`` (independent laws: an algebraic smooth sign,
Stribeck excess of power (exponent 0.5-1.5) or Lorentzian shape and/or direction
asymmetry, viscous or power-law churning, a von-Mises 2x ripple added or modulating the
level, plus current noise and quantisation, cogging, encoder steps and a temperature
drift that are no family). Every case writes the contract's CSV into a temporary
folder, reads it with ``load_measurement`` and runs ``diagnose(meas, [])`` (baseline: the
base model, no family). The table lists per group how often the hidden family was
ranked first and added first (single groups), both were added (two hidden), nothing
was added (nothing hidden), and how often a family that is not hidden was added
(spurious). The issue's criterion: each hidden family found first, and nothing added
when nothing is hidden, in >= 90 % of the runs of every such group, >= 5 seeds per
group. A case that raises is a failed case (its text is kept), never a crash of the
battery. Results go to ``validation/results/running_torque_battery.json`` (atomically).
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
import tempfile
import time
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))  # truth_running lives with the tests
sys.path.insert(0, str(HERE.parent))  # this checkout's hdsim, whatever an editable install points at
sys.path.insert(0, str(HERE))

from battery_common import run_in_processes, write_json_atomic  # noqa: E402

#: group name -> hidden families (the baseline is always the base model: no family)
GROUPS = {
    "nothing": (),
    "friction": ("friction",),
    "damping": ("damping",),
    "ripple": ("ripple",),
    "two:friction+damping": ("friction", "damping"),
    "two:friction+ripple": ("friction", "ripple"),
    "two:damping+ripple": ("damping", "ripple"),
}
#: groups whose hidden ripple is the position torque (it does not reverse with the motion:
#: cogging, an unbalance; ``truth_running``'s on-request ``conservative`` form), and the form
#: the diagnosis must pick for it
GROUPS.update({"ripple:position_torque": ("ripple",),
               "three:friction+damping+position_torque": ("friction", "damping", "ripple")})
GROUP_OVERRIDES = {"ripple:position_torque": {"ripple_form": "conservative"},
                   "three:friction+damping+position_torque": {"ripple_form": "conservative"}}
EXPECTED_FORMS = {group: {"ripple": "position_torque"} for group in GROUP_OVERRIDES}
#: groups the issue's >= 90 % criterion is about
CRITERION_GROUPS = ("nothing", "friction", "damping", "ripple", "ripple:position_torque")
TARGET = 0.9
MIN_SEEDS = 5
OUT = HERE / "results" / "running_torque_battery.json"


def _draws(truth: dict) -> dict:
    """The drawn forms and nuisances of a case, small and JSON-safe, to explain a failure."""
    p, nz = truth["params"], truth["params"]["nuisance"]
    return {"layout": truth["layout"], "rows": int(truth["clean"]["time_s"].size),
            "levels_rpm": [round(float(w) * 60 / (2 * 3.141592653589793), 1)
                           for w in truth["profile"]["levels_rad_s"]],
            "F_c_Nm": float(p["base"]["F_c"]),
            "friction": p["friction"] and p["friction"]["form"],
            "damping": p["damping"] and p["damping"]["form"],
            "ripple": p["ripple"] and f"{p['ripple']['form']} {p['ripple']['total_frac']:.2f}",
            "noise_over_F_c": float(nz["sigma"] / p["base"]["F_c"]),
            "cogging": bool(nz["cog_on"]), "temperature": bool(nz["temp_on"])}


def run_case(group: str, seed: int, **overrides) -> dict:
    """One battery case: generate, write, read, diagnose; never raises.

    Parameters
    ----------
    group : str
        A key of :data:`GROUPS`.
    seed : int
        Truth seed.
    **overrides
        Passed to ``truth_running.make_running_data`` (e.g. ``max_rows=6000``).

    Returns
    -------
    dict
        ``group``, ``seed``, ``hidden``, ``added``, ``ranking`` (families, best first),
        ``scores``, ``baseline_rmse_Nm``, ``final_rmse_Nm``, ``outcome``, ``draws``,
        ``seconds`` [s] and ``error`` (None, or the exception's text).
    """
    hidden = list(GROUPS[group])
    row = {"group": group, "seed": int(seed), "hidden": hidden, "added": [], "ranking": [],
           "scores": [], "baseline_rmse_Nm": None, "final_rmse_Nm": None, "outcome": None,
           "draws": None, "seconds": None, "error": None}
    start = time.perf_counter()
    try:
        import truth_running

        cols, meta, truth = truth_running.make_running_data(set(hidden), seed,
                                                            **{**overrides, **GROUP_OVERRIDES.get(group, {})})
        row["draws"] = _draws(truth)
        from hdsim.identification.diagnosis import diagnose
        from hdsim.io.measurement import load_measurement

        with tempfile.TemporaryDirectory(prefix="running_battery_") as folder:
            path = Path(folder) / f"running_{group.replace(':', '_').replace('+', '_')}_{seed}.csv"
            truth_running.write_csv(path, cols, meta)
            meas = load_measurement(path)
            report = diagnose(meas, [])
            j = report.to_json()
        row["added"] = list(j["added"])
        row["forms"] = {s["added"]: next(c["effect"] for c in s["candidates"] if c["family"] == s["added"])
                        for s in j["rounds"] if s["added"]}
        row["ranking"] = [r["family"] for r in j["ranking"]]
        row["scores"] = [r.get("score") for r in j["ranking"]]
        row["baseline_rmse_Nm"] = j["baseline"].get("rmse_Nm")
        row["final_rmse_Nm"] = j["final"].get("rmse_Nm")
        # the outcome may be a word or an object: keep it as JSON can hold it
        row["outcome"] = json.loads(json.dumps(j.get("outcome"), default=str))
    except Exception as exc:  # a failed case, not a failed battery
        tail = traceback.format_exc().strip().splitlines()[-6:]
        row["error"] = f"{type(exc).__name__}: {exc}\n" + "\n".join(tail)
    row["seconds"] = round(time.perf_counter() - start, 3)
    return row


# --------------------------------------------------------------------------- rates


def case_ok(row: dict) -> bool:
    """Whether a case met its group's criterion (an errored case never does)."""
    if row["error"]:
        return False
    if any(row.get("forms", {}).get(f) != form for f, form in EXPECTED_FORMS.get(row["group"], {}).items()):
        return False  # the family found in the wrong form
    hidden, added = row["hidden"], row["added"]
    if not hidden:
        return not added
    if len(hidden) == 1:
        return bool(row["ranking"]) and row["ranking"][0] == hidden[0] and added[:1] == hidden
    return set(hidden) <= set(added)


def rates(rows: list[dict]) -> dict:
    """Per group: ``n``, ``errors``, ``ok`` (the group's criterion), ``first`` (ranked and
    added first; single groups), ``both`` (two hidden), ``nothing_added`` (nothing group),
    ``spurious`` (a family added that is not hidden) as fractions, ``median_s`` [s]."""
    out = {}
    for group, hidden in GROUPS.items():
        sel = [r for r in rows if r["group"] == group]
        if not sel:
            continue
        n = len(sel)
        frac = lambda pred: sum(bool(pred(r)) for r in sel) / n  # noqa: E731
        times = sorted(r["seconds"] or 0.0 for r in sel)
        out[group] = {
            "n": n, "errors": sum(bool(r["error"]) for r in sel), "ok": frac(case_ok),
            "first": frac(case_ok) if len(hidden) == 1 else None,
            "both": frac(case_ok) if len(hidden) == 2 else None,
            "nothing_added": frac(case_ok) if not hidden else None,
            "spurious": frac(lambda r: not r["error"] and set(r["added"]) - set(r["hidden"])),
            "median_s": times[n // 2],
        }
    return out


def verdict(table: dict) -> dict:
    """The issue's criterion over :data:`CRITERION_GROUPS`: every group >= 90 %, >= 5 seeds."""
    groups = [g for g in CRITERION_GROUPS if g in table]
    missing = [g for g in CRITERION_GROUPS if g not in table or table[g]["n"] < MIN_SEEDS]
    hits = sum(round(table[g]["ok"] * table[g]["n"]) for g in groups)
    total = sum(table[g]["n"] for g in groups)
    low = [g for g in groups if table[g]["ok"] < TARGET]
    return {"pooled": hits / total if total else None, "below_target": low,
            "too_few_seeds": missing, "met": bool(groups) and not low and not missing}


def summarise(rows: list[dict]) -> list[str]:
    """The printed table (one line per group) and the criterion line."""
    table = rates(rows)
    pct = lambda x: "—" if x is None else f"{x:.0%}"  # noqa: E731
    lines = [f"{'group':24s} {'n':>3s} {'err':>4s} {'first':>6s} {'both':>6s} {'none+':>6s} "
             f"{'spur.':>6s} {'med s':>6s}"]
    for group, r in table.items():
        lines.append(f"{group:24s} {r['n']:3d} {r['errors']:4d} {pct(r['first']):>6s} {pct(r['both']):>6s} "
                     f"{pct(r['nothing_added']):>6s} {pct(r['spurious']):>6s} {r['median_s']:6.1f}")
    v = verdict(table)
    state = "MET" if v["met"] else "NOT MET"
    lines.append(f"criterion (each hidden family first, nothing added when nothing hidden, "
                 f">= {TARGET:.0%} per group, >= {MIN_SEEDS} seeds): {state}; pooled "
                 f"{pct(v['pooled'])}; below target: {', '.join(v['below_target']) or 'none'}; "
                 f"too few seeds: {', '.join(v['too_few_seeds']) or 'none'}")
    return lines


# --------------------------------------------------------------------------- running


def run_cases(cases: list[tuple[str, int]], workers: int = 1, progress: bool = False, **overrides) -> list[dict]:
    """Run ``(group, seed)`` cases, in processes when ``workers > 1``; rows in case order."""
    def failed(g, s, error):
        return {"group": g, "seed": s, "hidden": list(GROUPS[g]), "added": [], "ranking": [], "scores": [],
                "baseline_rmse_Nm": None, "final_rmse_Nm": None, "outcome": None, "draws": None,
                "seconds": None, "error": error}

    return run_in_processes(functools.partial(_case, **overrides), cases, workers, "running-torque battery",
                            failed, progress)


def _case(group, seed, **overrides):
    return run_case(group, seed, **overrides)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=6, help="seeds per group (default 6)")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--only", default="", help="comma-separated group prefixes (nothing, two, ...)")
    parser.add_argument("--max-rows", type=int, default=None, help="cap the rows of every record")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args(argv)
    prefixes = [p for p in args.only.split(",") if p]
    groups = [g for g in GROUPS if not prefixes or any(g.startswith(p) for p in prefixes)]
    if not groups:
        parser.error(f"--only {args.only!r} matches no group of {', '.join(GROUPS)}")
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    overrides = {} if args.max_rows is None else {"max_rows": args.max_rows}
    cases = [(g, s) for g in groups for s in seeds]
    start = time.perf_counter()
    rows = run_cases(cases, args.workers, progress=True, **overrides)
    lines = summarise(rows)
    print("\n".join(lines))
    for r in rows:
        if r["error"]:
            print(f"  {r['group']} seed {r['seed']}: {r['error'].splitlines()[0]}")
    table = rates(rows)
    write_json_atomic(args.out, {
        "settings": {"seeds": list(seeds), "groups": groups, "overrides": overrides,
                     "workers": args.workers, "seconds": round(time.perf_counter() - start, 1)},
        "table": lines, "rates": table, "verdict": verdict(table), "cases": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
