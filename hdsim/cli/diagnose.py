"""``hdsim diagnose``: rank the effect families the model misses, add the best, repeat.

Examples::

    hdsim diagnose bench.csv --effects friction --json
    hdsim diagnose bench.csv --report diagnosis/      # figures + index.html / index.md

See `hdsim.identification.diagnosis` for the procedure and the acceptance rule.
"""

from __future__ import annotations

import importlib.util
import sys

from hdsim.cli._guards import path_argument

HELP = "find the effect families a measurement needs: rank, add the best, refit, repeat"


def register(subparsers) -> None:
    from hdsim.cli._import_arguments import add_record_parser

    p = add_record_parser(subparsers, "diagnose", HELP, "families or effect ids already in the model (the baseline)")
    p.add_argument("--report", type=path_argument, default=None, metavar="DIR",
                   help="write figures and an HTML/Markdown page of every step here")
    p.add_argument("--max-rounds", default=None, type=int, metavar="N",
                   help="add at most N families")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=run)


def run(args) -> int:
    from hdsim.cli.fit import load_inputs, say_checks
    from hdsim.errors import InputError
    from hdsim.identification.workflow import diagnose

    if args.max_rounds is not None and args.max_rounds < 0:
        raise InputError("--max-rounds must be 0 or more")
    meas, effects = load_inputs(args)
    if args.report:
        from hdsim.cli._guards import check_output_folder

        check_output_folder(args.report, "--report", data=args.data)  # before the work, not after it

    def log(message):
        print(f"hdsim diagnose: {message}", file=sys.stderr, flush=True)

    from hdsim.identification.test_kinds import test_kind

    if test_kind(meas.test).compiled_fits and importlib.util.find_spec("numba") is None:
        log("numba is not installed: the fits run in numpy, about 4x slower on a long record (pip install 'hdsim[fast]')")
    result = diagnose(meas, effects, unit=args.unit, max_rounds=args.max_rounds, log=log)
    if args.report:
        result.report(args.report)
    summary = result.to_json()
    say_checks("diagnose", summary["checks"])
    return _emit(args, summary)


def _emit(args, summary) -> int:
    if args.json:
        from hdsim.cli import emit_json

        emit_json(summary)
        return 0
    if summary["outcome"] == "wrong_test":
        print(f"outcome: wrong_test: {summary['verdict']}")
        if "report" in summary:
            print(f"report: {summary['report']}")
        return 0
    _print(summary)
    return 0


def _print(s) -> None:
    from hdsim.identification.test_kinds import test_kind

    kind = test_kind(s["test"])
    key = kind.error_key
    unit, scale = kind.report_unit  # the report's unit: the console and the page say the same numbers
    print(f"{s['test']} test: baseline {', '.join(s['baseline']['effects']) or '(base model)'}, "
          f"rms {s['baseline'][key] * scale:.3g} {unit}")
    settled = s.get("ranking_round", 1)
    print("ranking (first round, lower score is better):" if settled == 1 else
          f"ranking (round {settled}, the first after the change of form below; lower score is better):")
    for c in s["ranking"]:
        if c["score"] is None:
            print(f"  {c['family']:<16} {c['effect']:<16} {c['why']}")
            continue
        print(f"  {c['family']:<16} {c['effect']:<16} score {c['score']:10.1f}  rms {c[key] * scale:.3g} {unit}"
              f"  {c['why']}")
    print(f"added: {', '.join(s['added']) or 'nothing'}")
    for r in s.get("reshaped", []):
        why = ("no family passed, this form explained the residual" if r["instead_of"] is None
               else f"it explained the residual better than adding {r['instead_of']}")
        print(f"other form: {r['family']} as {r['to']} instead of {r['from']} (round {r['round']}: {why}, "
              f"score {r['score']:.1f})")
    inclusion = (s.get("confidence") or {}).get("inclusion")
    if inclusion:
        print("how sure (share of block-bootstrap resamples that add it): "
              + ", ".join(f"{f} {p:.2f}" for f, p in sorted(inclusion.items(), key=lambda kv: -kv[1])))
    for a in s["ambiguous"]:
        rival = a["families"][1] + "".join(f" as {e}" for e in a.get("other_form", {}).values())
        held = f" ({a['provisional']} stands in the model for the loss, not added)" if a.get("provisional") else ""
        print(f"ambiguous: {a['families'][0]} vs {rival}{held}; to separate them: {a['measurement']}")
    print(f"final: {', '.join(s['final']['effects']) or '(base model)'}, rms {s['final'][key] * scale:.3g} {unit}")
    if "derived" in s["final"]:  # a torque fit's starting torque, as `hdsim fit` prints it
        from hdsim.cli.fit import starting_torque_lines

        for line in starting_torque_lines(s["final"]["derived"], "the file's shaft"):
            print(line)
    print(s["verdict"])
    print(f"outcome: {s['outcome']}" + (f"; to decide, record {s['next_measurement']}" if s["next_measurement"]
                                         else ""))
    for line in s.get("findings", {}).get("final", []):
        print(f"  - {line}")
    if "report" in s:
        print(f"report: {s['report']}")
