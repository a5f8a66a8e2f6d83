"""The truth-zoo battery: how ``diagnose`` generalises to forms and profiles it was not tuned on.

    python validation/zoo_battery.py [--seeds 8] [--first-seed 0] [--workers 2]
                                     [--only single:friction,nothing,two] [--max-rows N]
                                     [--leave-one-form-out [--tuning-forms friction:bouc_wen,...]]
                                     [--from earlier.json ...] [--list]

Data come from ``tests/truth_zoo.py`` (laws in ``tests/truth_zoo_forms.py``, no
``hdsim`` code): several forms per family (friction: generalised Maxwell-slip, LuGre,
Bouc–Wen, Preisach, Coulomb + viscous; hardening: cubic, sinh, piecewise-linear,
exponential; backlash: hard, smooth, asymmetric and closing gaps; damping:
Kelvin–Voigt, load- and frequency-dependent; kinematic error plain, with friction
windup, under a varying load) and eight profile kinds (one and several rates, unequal
cycle counts, sine, up to 20 cycles, 20 Hz to 2 kHz, drift).

Groups (every group runs ``--seeds`` seeds; the profile kind rotates with the seed, so
eight seeds show every group every kind, and each form and kind is in >= 5 cases
from five seeds on)
    ``single:<family>:<form>``  the form hidden alone, a baseline of other families
                                (each with probability 1/2, form drawn);
    ``nothing:<baseline>``      nothing hidden, several baselines (forms drawn);
    ``two:<a>+<b>``             two hidden (forms drawn), a fixed baseline.

Every case writes the contract's CSV to a temporary folder, reads it with
``load_measurement``, runs ``diagnose(meas, baseline)`` and grades it with
``examine``/``assess`` (the outcome ``hdsim diagnose`` prints). A case that raises is a
failed case (its text kept), never a crash. The tables give, as shares of runs:
``first`` (single: the hidden family ranked first and added first), ``first|dec`` (the
same among the runs that were decided: an honest ``cannot_decide`` with nothing added,
e.g. damping vs friction from one loading rate, is not a wrong pick), ``both`` (two
hidden both added), ``both|dec`` (the same among the runs without a *flagged pair*: a
missed family the run reported as ambiguous with its partner, damping vs friction from
one loading rate, with the separating measurement), ``none+`` (nothing hidden, nothing
added that is not in the truth), ``spur.`` (a family added that is not in the truth at
all), ``strict`` (a family added that is not hidden, counting a minor part of a truth
form as spurious: the viscous part of Coulomb + viscous friction *is* a damping, and a
model given only "friction" misses it, so its addition is graded right, and the strict
share is printed beside it), and the counts ``cd`` (outcome ``cannot_decide``) and
``amb`` (an ambiguity reported).

Targets of the issue, checked at the end: first pick right >= 90 % in every single
group (over decided runs), both added in >= 90 % of the two-hidden runs, nothing added
in >= 95 % of the nothing-hidden runs, spurious additions in <= 5 % of all runs, >= 5
seeds per group. Results go to ``validation/results/zoo_battery.json`` (atomically).
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
import tempfile
import time
import traceback
import zlib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
# this checkout's hdsim, whatever an editable install elsewhere points at; the zoo lives with the tests
sys.path[:0] = [str(HERE.parent), str(HERE.parent / "tests"), str(HERE)]

import truth_zoo as tz  # noqa: E402
from battery_common import run_in_processes, write_json_atomic  # noqa: E402

OUT = HERE / "results" / "zoo_battery.json"
TARGET_FIRST, TARGET_BOTH, TARGET_NOTHING, TARGET_SPURIOUS, MIN_SEEDS = 0.90, 0.90, 0.95, 0.05, 5
KINDS = tuple(tz.PROFILES)
RATE_PAIR = {"damping", "friction"}
BODY = tz.BODY_FAMILIES

#: group -> (hidden families, fixed baseline families or None for "drawn from the others")
GROUPS: dict[str, tuple[tuple, tuple | None]] = {}
for _fam, _forms in tz.FORMS.items():
    for _form in _forms:
        GROUPS[f"single:{_fam}:{_form}"] = (((_fam, _form),), None)
for _name, _base in (("linear", ()), ("hardening+friction", ("hardening", "friction")),
                     ("friction+damping", ("friction", "damping")), ("hardening+backlash", ("hardening", "backlash")),
                     ("all_four", BODY), ("ke+friction", ("kinematic_error", "friction"))):
    GROUPS[f"nothing:{_name}"] = ((), _base)
for _pair, _base in ((("hardening", "backlash"), ()), (("friction", "damping"), ("hardening", "backlash")),
                     (("backlash", "friction"), ("hardening",)), (("hardening", "damping"), ("friction",))):
    GROUPS[f"two:{'+'.join(_pair)}"] = (tuple((f, None) for f in _pair), _base)


def design(group: str, seed: int) -> dict:
    """The case of ``(group, seed)``: hidden and baseline ``{family: form}`` and the profile kind.

    Deterministic: the profile kind rotates with the seed (offset by the group's place),
    forms and the drawn baseline come from a stream seeded by ``(seed, crc32(group))``.
    """
    spec_hidden, spec_base = GROUPS[group]
    rng = np.random.default_rng([int(seed), zlib.crc32(group.encode())])
    pick = lambda fam: tz.FORMS[fam][int(rng.integers(len(tz.FORMS[fam])))]  # noqa: E731
    hidden = {fam: form or pick(fam) for fam, form in spec_hidden}
    if spec_base is None:  # single: others each with probability 1/2
        others = [f for f in BODY if f not in hidden]
        base = {f: pick(f) for f in others if rng.random() < 0.5}
    else:
        base = {f: pick(f) for f in spec_base}
        if base.get("kinematic_error") == "with_windup":
            base["kinematic_error"] = "plain"  # friction is already in this baseline
    kind = KINDS[(int(seed) + list(GROUPS).index(group)) % len(KINDS)]
    return {"hidden": hidden, "baseline": base, "profile": kind}


def run_case(group: str, seed: int, max_rows: int | None = None) -> dict:
    """One case: generate, write, read, examine, diagnose, assess; never raises."""
    d = design(group, seed)
    row = {"group": group, "seed": int(seed), "profile": d["profile"], "hidden": d["hidden"],
           "baseline": d["baseline"], "test": None, "rows": None, "added": [], "reshaped": [], "ranking": [],
           "scores": [],
           "ambiguous": [], "outcome": None, "next_measurement": None, "wrong_test": "",
           "baseline_rmse_rad": None, "final_rmse_rad": None, "success": None, "visibility": None,
           "secondary": {}, "noise_arcsec": None, "gen_seconds": None, "seconds": None, "error": None}
    start = time.perf_counter()
    try:
        over = {} if max_rows is None else {"max_rows": int(max_rows)}
        cols, meta, truth = tz.make_case(d["hidden"], d["baseline"], d["profile"], seed, **over)
        row.update(test=truth["test"], rows=int(truth["profile"]["rows"]), baseline=truth["baseline"],
                   visibility={k: round(v, 2) for k, v in truth["visibility"].items()},
                   secondary=truth["secondary"], noise_arcsec=round(truth["measurement"]["noise_rad"] / tz.ARCSEC, 3),
                   gen_seconds=round(time.perf_counter() - start, 2))
        from hdsim.identification.diagnosis import diagnose
        from hdsim.identification.outcome import assess
        from hdsim.identification.workflow import examine
        from hdsim.io.data_checks import DriveScale
        from hdsim.io.measurement import load_measurement
        from hdsim.model.catalog import load_unit

        with tempfile.TemporaryDirectory(prefix="zoo_battery_") as folder:
            path = Path(folder) / f"{group.replace(':', '_').replace('+', '_')}_{seed}.csv"
            tz.write_csv(path, cols, meta)
            meas = load_measurement(path)
        checks, data, wrong = examine(meas, DriveScale.of(load_unit()))
        if wrong:  # not the test it claims: what `hdsim diagnose` does, fit nothing
            row.update(outcome="wrong_test", wrong_test=wrong)
        else:
            report = diagnose(meas, list(truth["baseline"]))
            j = report.to_json()
            outcome, nxt = assess(j, data, report.kind)
            row.update(added=list(j["added"]), reshaped=[f"{r['family']}={r['to']}" for r in j["reshaped"]],
                       ranking=[r["family"] for r in j["ranking"]],
                       scores=[r.get("score") for r in j["ranking"]],
                       ambiguous=[a["families"] for a in j["ambiguous"]], outcome=outcome, next_measurement=nxt,
                       baseline_rmse_rad=j["baseline"]["rmse_rad"], final_rmse_rad=j["final"]["rmse_rad"],
                       success=bool(j["success"]), final_p_value=j["whiteness"]["p_value"],
                       **residual_floors(report.steps[-1].fit.residual))
    except Exception as exc:  # a failed case, not a failed battery
        tail = traceback.format_exc().strip().splitlines()[-6:]
        row["error"] = f"{type(exc).__name__}: {exc}\n" + "\n".join(tail)
    row["seconds"] = round(time.perf_counter() - start, 2)
    return row


def residual_floors(r) -> dict:
    """Three estimates of the final residual's white-noise rms [rad]: ``std(Δr)/√2``, the
    same from the median absolute first difference, and `hdsim.signals.noise_level` (a
    local cubic's median residual); the last two are robust to the few rows where a
    model's kink makes the residual jump."""
    from hdsim.signals import noise_level

    r = np.asarray(r, dtype=float)
    d = np.diff(r)
    return {"floor_std_rad": float(np.std(d) / np.sqrt(2.0)),
            "floor_mad_rad": float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0)),
            "floor_local_rad": noise_level(r)}


# --------------------------------------------------------------------------- grading


def kind_of(group: str) -> str:
    return group.split(":")[0]


def first_right(r: dict) -> bool:
    fam = next(iter(r["hidden"]))
    return not r["error"] and bool(r["ranking"]) and r["ranking"][0] == fam and r["added"][:1] == [fam]


def honest_cannot_decide(r: dict) -> bool:
    """``cannot_decide`` with nothing added: the record was judged undecidable, no pick made."""
    return not r["error"] and r["outcome"] == "cannot_decide" and not r["added"]


def spurious(r: dict) -> set:
    """Families added that are not in the truth at all (the targets' spurious additions)."""
    return strictly_spurious(r) - set(r["secondary"])


def strictly_spurious(r: dict) -> set:
    """Families added that are not hidden, counting a minor part of a truth form (the viscous
    part of Coulomb + viscous friction, which is a damping) as spurious too."""
    return set() if r["error"] else set(r["added"]) - set(r["hidden"])


def flagged_pair(r: dict) -> bool:
    """Two hidden, not both added, and every missed family is in a pair the run reported as
    ambiguous (damping vs friction from one loading rate, with the separating measurement):
    the behaviour the issue asks for instead of a guess, graded like an honest cannot_decide."""
    missed = set(r["hidden"]) - set(r["added"])
    return (not r["error"] and bool(missed)
            and any(set(pair) == RATE_PAIR and missed <= RATE_PAIR for pair in r["ambiguous"]))


def rates(rows: list[dict]) -> dict:
    """Shares over ``rows`` (any selection): see the module text for the columns."""
    n = len(rows)
    if not n:
        return {"n": 0}
    frac = lambda pred, sel=rows: (sum(bool(pred(r)) for r in sel) / len(sel)) if sel else None  # noqa: E731
    singles = [r for r in rows if kind_of(r["group"]) == "single"]
    decided = [r for r in singles if not honest_cannot_decide(r)]
    twos = [r for r in rows if kind_of(r["group"]) == "two"]
    nothing = [r for r in rows if kind_of(r["group"]) == "nothing"]
    times = sorted(r["seconds"] or 0.0 for r in rows)
    both = lambda r: not r["error"] and set(r["hidden"]) <= set(r["added"])  # noqa: E731
    return {
        "n": n, "errors": sum(bool(r["error"]) for r in rows),
        "first": frac(first_right, singles), "first_decided": frac(first_right, decided),
        "both": frac(both, twos), "both_decided": frac(both, [r for r in twos if not flagged_pair(r)]),
        "nothing_added": frac(lambda r: not r["error"] and not spurious(r), nothing),
        "nothing_added_strict": frac(lambda r: not r["error"] and not r["added"], nothing),
        "spurious": frac(spurious), "spurious_strict": frac(strictly_spurious),
        "secondary": frac(lambda r: strictly_spurious(r) and not spurious(r)),
        "cannot_decide": sum(r["outcome"] == "cannot_decide" for r in rows),
        "ambiguous": sum(bool(r["ambiguous"]) for r in rows),
        "median_s": times[n // 2],
    }


def _line(label: str, r: dict, width: int = 40) -> str:
    pct = lambda x: "—" if x is None else f"{x:.0%}"  # noqa: E731
    return (f"{label:{width}s} {r['n']:3d} {r['errors']:4d} {pct(r['first']):>6s} {pct(r['first_decided']):>9s} "
            f"{pct(r['both']):>5s} {pct(r['both_decided']):>8s} {pct(r['nothing_added']):>6s} "
            f"{pct(r['spurious']):>6s} {pct(r['spurious_strict']):>6s} "
            f"{r['cannot_decide']:3d} {r['ambiguous']:4d} {r['median_s']:7.1f}")


def _header(title: str, width: int = 40) -> str:
    return (f"{title:{width}s} {'n':>3s} {'err':>4s} {'first':>6s} {'first|dec':>9s} {'both':>5s} {'both|dec':>8s} "
            f"{'none+':>6s} {'spur.':>6s} {'strict':>6s} {'cd':>3s} {'amb':>4s} {'med s':>7s}")


def summarise(rows: list[dict], tuning: tuple = tz.TUNING_FORMS) -> list[str]:
    """The printed tables: per form, per family, per profile kind, two hidden, nothing hidden."""
    lines = [_header("single: family:form (* tuning form)")]
    for group in GROUPS:
        sel = [r for r in rows if r["group"] == group]
        if sel and kind_of(group) == "single":
            tag = group.split(":", 1)[1]
            lines.append(_line(tag + (" *" if tag in tuning else ""), rates(sel)))
    singles = [r for r in rows if kind_of(r["group"]) == "single"]
    if singles:
        lines.append(_header("single: per family"))
        for fam in tz.FORMS:
            sel = [r for r in singles if fam in r["hidden"]]
            if sel:
                lines.append(_line(fam, rates(sel)))
    lines.append(_header("per profile kind (all groups)"))
    for kind in KINDS:
        sel = [r for r in rows if r["profile"] == kind]
        if sel:
            lines.append(_line(kind, rates(sel)))
    for prefix, title in (("two", "two hidden"), ("nothing", "nothing hidden")):
        sel_groups = [g for g in GROUPS if kind_of(g) == prefix and any(r["group"] == g for r in rows)]
        if sel_groups:
            lines.append(_header(title))
            for g in sel_groups:
                lines.append(_line(g.split(":", 1)[1], rates([r for r in rows if r["group"] == g])))
    lines.append(_line("ALL", rates(rows)))
    return lines + verdict_lines(rows)


def verdict(rows: list[dict]) -> dict:
    """The issue's targets, each ``{value, target, met}``, and the groups with too few seeds."""
    per_group = {}
    for r in rows:
        per_group.setdefault(r["group"], []).append(r)
    singles = {g: rates(sel) for g, sel in per_group.items() if kind_of(g) == "single"}
    low = sorted(g for g, x in singles.items() if x["first_decided"] is None or x["first_decided"] < TARGET_FIRST)
    pooled = rates([r for g in singles for r in per_group[g]])
    all_r = rates(rows)
    two_r = rates([r for r in rows if kind_of(r["group"]) == "two"])
    none_r = rates([r for r in rows if kind_of(r["group"]) == "nothing"])
    out = {
        "first_pick": {"value": pooled["first_decided"] if singles else None,
                       "raw": pooled["first"] if singles else None,
                       "target": TARGET_FIRST, "below": low, "met": bool(singles) and not low},
        "both_added": {"value": two_r.get("both_decided"), "raw": two_r.get("both"), "target": TARGET_BOTH},
        "nothing_added": {"value": none_r.get("nothing_added"), "strict": none_r.get("nothing_added_strict"),
                          "target": TARGET_NOTHING},
        "spurious": {"value": all_r["spurious"], "strict": all_r["spurious_strict"], "target": TARGET_SPURIOUS},
        "seeds": {"too_few": sorted(g for g, sel in per_group.items() if len({r['seed'] for r in sel}) < MIN_SEEDS),
                  "target": MIN_SEEDS},
    }
    for key in ("both_added", "nothing_added"):
        v = out[key]["value"]
        out[key]["met"] = v is not None and v >= out[key]["target"]
    out["spurious"]["met"] = out["spurious"]["value"] is not None and out["spurious"]["value"] <= TARGET_SPURIOUS
    out["seeds"]["met"] = not out["seeds"]["too_few"]
    out["met"] = all(out[k]["met"] for k in ("first_pick", "both_added", "nothing_added", "spurious", "seeds"))
    return out


def verdict_lines(rows: list[dict]) -> list[str]:
    v = verdict(rows)
    pct = lambda x: "—" if x is None else f"{x:.0%}"  # noqa: E731
    state = lambda ok: "met" if ok else "NOT met"  # noqa: E731
    f, seeds = v["first_pick"], v["seeds"]
    return [
        "targets:",
        f"  first pick right >= {TARGET_FIRST:.0%} in every single group (decided runs): pooled {pct(f['value'])} "
        f"(all runs {pct(f['raw'])}); "
        f"{state(f['met'])}; below: {', '.join(g.split(':', 1)[1] for g in f['below']) or 'none'}",
        f"  two hidden both added >= {TARGET_BOTH:.0%} (runs without a flagged pair): "
        f"{pct(v['both_added']['value'])} (all runs {pct(v['both_added']['raw'])}); {state(v['both_added']['met'])}",
        f"  nothing hidden, nothing added >= {TARGET_NOTHING:.0%} (nothing outside the truth): "
        f"{pct(v['nothing_added']['value'])} (nothing at all {pct(v['nothing_added']['strict'])}); "
        f"{state(v['nothing_added']['met'])}",
        f"  spurious additions <= {TARGET_SPURIOUS:.0%} of runs (not in the truth): {pct(v['spurious']['value'])} "
        f"(not hidden {pct(v['spurious']['strict'])}); {state(v['spurious']['met'])}",
        f"  >= {MIN_SEEDS} seeds per group: {state(seeds['met'])}"
        + (f" (too few: {len(seeds['too_few'])} groups)" if seeds["too_few"] else ""),
        f"  all targets: {state(v['met'])}",
    ]


def leave_one_form_out(rows: list[dict], tuning: tuple) -> list[str]:
    """Single-hidden rates for the tuning forms and for the held-out forms, per family and pooled."""
    singles = [r for r in rows if kind_of(r["group"]) == "single"]
    tag = lambda r: r["group"].split(":", 1)[1]  # noqa: E731
    lines = [f"leave-one-form-out (tuning forms: {', '.join(tuning)})", _header("family / split")]
    for fam in list(tz.FORMS) + [None]:
        sel = [r for r in singles if fam is None or fam in r["hidden"]]
        for split, keep in (("tuning", True), ("held-out", False)):
            part = [r for r in sel if (tag(r) in tuning) == keep]
            if part:
                lines.append(_line(f"{fam or 'ALL'} / {split}", rates(part)))
    return lines


# --------------------------------------------------------------------------- running


def run_cases(cases: list[tuple[str, int]], workers: int = 1, max_rows: int | None = None) -> list[dict]:
    """Run ``(group, seed)`` cases, in processes when ``workers > 1``; rows in case order."""
    def failed(g, s, error):
        d = design(g, s)
        return {"group": g, "seed": s, "profile": d["profile"], "hidden": d["hidden"], "baseline": d["baseline"],
                "added": [], "ranking": [], "ambiguous": [], "outcome": None, "secondary": {}, "seconds": None,
                "error": error}

    return run_in_processes(functools.partial(run_case, max_rows=max_rows), cases, workers, "zoo battery", failed)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8, help="seeds per group (default 8: every kind once)")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--only", default="", help="comma-separated group prefixes (single:friction, two, ...)")
    parser.add_argument("--max-rows", type=int, default=None, help="cap the rows of every record")
    parser.add_argument("--leave-one-form-out", action="store_true",
                        help="also print the rates of the tuning forms and of the held-out forms apart")
    parser.add_argument("--tuning-forms", default=",".join(tz.TUNING_FORMS),
                        help="family:form list of the forms the diagnosis was tuned on")
    parser.add_argument("--from", dest="source", type=Path, nargs="+", default=None,
                        help="summarise the cases of earlier runs' JSON files (pooled) instead of running")
    parser.add_argument("--list", action="store_true", help="print the cases (group, seed, profile, forms) and exit")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args(argv)
    tuning = tuple(t for t in args.tuning_forms.split(",") if t)
    prefixes = [p for p in args.only.split(",") if p]
    groups = [g for g in GROUPS if not prefixes or any(g.startswith(p) for p in prefixes)]
    if not groups:
        parser.error(f"--only {args.only!r} matches no group of {', '.join(GROUPS)}")
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    cases = [(g, s) for g in groups for s in seeds]
    if args.list:
        for g, s in cases:
            d = design(g, s)
            print(f"{g:40s} seed {s:4d} {d['profile']:24s} hidden {d['hidden']} baseline {d['baseline']}")
        return 0
    start = time.perf_counter()
    if args.source:
        rows = [r for path in args.source for r in json.loads(path.read_text())["cases"]]
        rows = [r for r in rows if r["group"] in groups]
    else:
        rows = run_cases(cases, args.workers, args.max_rows)
    lines = summarise(rows, tuning)
    if args.leave_one_form_out:
        lines += leave_one_form_out(rows, tuning)
    print("\n".join(lines))
    for r in rows:
        if r.get("error"):
            print(f"  {r['group']} seed {r['seed']}: {r['error'].splitlines()[0]}")
    if not args.source:
        write_json_atomic(args.out, {
            "settings": {"seeds": list(seeds), "groups": groups, "max_rows": args.max_rows,
                         "workers": args.workers, "seconds": round(time.perf_counter() - start, 1),
                         "tuning_forms": list(tuning)},
            "table": lines, "rates": {g: rates([r for r in rows if r["group"] == g]) for g in groups},
            "verdict": verdict(rows), "cases": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
