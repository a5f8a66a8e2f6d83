"""``hdsim diagnose``: rank the effect families the model misses, add the best, repeat.

Examples::

    hdsim diagnose bench.csv --effects friction --json
    hdsim diagnose bench.csv --report diagnosis/      # figures + index.html / index.md

See `hdsim.identification.diagnosis` for the procedure and the acceptance rule.
"""

from __future__ import annotations

import sys

HELP = "find the effect families a measurement needs: rank, add the best, refit, repeat"


def register(subparsers) -> None:
    p = subparsers.add_parser("diagnose", help=HELP, description=HELP + ".")
    p.add_argument("data", metavar="DATA", help="measurement file (CSV or HDF5; see docs/measurements.md)")
    p.add_argument("--effects", default="",
                   help="families or effect ids already in the model (the baseline)")
    p.add_argument("--unit", default=None, help="built-in unit to start from (default CSG-25-100)")
    p.add_argument("--columns", default=None, metavar="MAP",
                   help="column map for another bench, e.g. time_s=t,torque_Nm=T_out,angle_deg=pos")
    p.add_argument("--report", default=None, metavar="DIR",
                   help="write figures and an HTML/Markdown page of every step here")
    p.add_argument("--max-rounds", default=None, type=int, metavar="N",
                   help="add at most N families")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=run)


def run(args) -> int:
    from hdsim.cli.fit import load_inputs
    from hdsim.identification.diagnosis import diagnose
    from hdsim.errors import InputError

    if args.max_rounds is not None and args.max_rounds < 0:
        raise InputError("--max-rounds must be 0 or more")
    meas, effects = load_inputs(args)

    def log(message):
        print(f"hdsim diagnose: {message}", file=sys.stderr, flush=True)

    result = diagnose(meas, effects, unit=args.unit, max_rounds=args.max_rounds, log=log)
    summary = result.to_json()
    if args.report:
        from hdsim.identification.report import write_report

        page = write_report(result, args.report)
        summary["report"] = str(page)
    if args.json:
        from hdsim.cli import emit_json

        emit_json(summary)
        return 0
    _print(summary)
    return 0


def _print(s) -> None:
    print(f"{s['test']} test: baseline {', '.join(s['baseline']['effects']) or '(base model)'}, "
          f"rms {s['baseline']['rmse_rad']:.3g} rad")
    print("ranking (first round, lower score is better):")
    for c in s["ranking"]:
        print(f"  {c['family']:<16} {c['effect']:<10} score {c['score']:10.1f}  rms {c['rmse_rad']:.3g} rad"
              f"  {c['why']}")
    print(f"added: {', '.join(s['added']) or 'nothing'}")
    for a in s["ambiguous"]:
        print(f"ambiguous: {a['families'][0]} vs {a['families'][1]}; to separate them: {a['measurement']}")
    print(f"final: {', '.join(s['final']['effects']) or '(base model)'}, rms {s['final']['rmse_rad']:.3g} rad")
    print(s["verdict"])
    for line in s["findings"]["final"]:
        print(f"  - {line}")
    if "report" in s:
        print(f"report: {s['report']}")
