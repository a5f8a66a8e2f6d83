"""``hdsim fit``: fit the model with the named effect families to a measurement file.

Examples::

    hdsim fit bench.csv --effects hardening,friction --json
    hdsim fit other_bench.csv --columns time_s=t,torque_Nm=T_out,angle_deg=pos --out fitted.toml

The fitted parameter set is written as TOML (``--out``, default ``<data stem>.fit.toml`` in
the current folder); `hdsim.identification.fit.load_fitted` turns it back into a model.
"""

from __future__ import annotations

import sys
from pathlib import Path

HELP = "fit the model with the named effect families to a measurement file"


def register(subparsers) -> None:
    import argparse

    from hdsim.cli._import_arguments import IMPORT_EPILOG, add_import_arguments

    p = subparsers.add_parser("fit", help=HELP, description=HELP + ".", epilog=IMPORT_EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("data", metavar="DATA", help="measurement file (CSV or HDF5; see docs/measurements.md)")
    p.add_argument("--effects", default="",
                   help="families or effect ids, e.g. hardening,friction or dahl; "
                        "absent: the base model (linear compliance and angle offset)")
    p.add_argument("--unit", default=None,
                   help="built-in unit or drive file (TOML, see 'hdsim units --template') to start from "
                        "(default CSG-25-100)")
    add_import_arguments(p)
    p.add_argument("--out", default=None, metavar="FILE",
                   help="where to write the fitted parameter set (default: DATA stem + .fit.toml)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=run)


def load_inputs(args):
    """(measurement, effects) with every input checked before anything runs."""
    from hdsim.model.catalog import load_unit
    from hdsim.identification.fit import parse_effects
    from hdsim.cli._import_arguments import import_options
    from hdsim.io.measurement import load_measurement, parse_column_map

    columns = parse_column_map(args.columns) if args.columns else None
    effects = parse_effects(args.effects)
    options = import_options(args)
    load_unit(args.unit)  # unknown unit: one line, exit 2, before reading anything big
    meas = load_measurement(args.data, columns, **vars(options))
    return meas, effects


def examine_inputs(meas, args):
    """(checks as JSON objects, data summary, wrong-test sentence, the drive's
    `hdsim.io.data_checks.DriveScale`) of a record against the named drive."""
    from hdsim.io.data_checks import DriveScale, examine
    from hdsim.model.catalog import load_unit

    scale = DriveScale.of(load_unit(args.unit))
    checks, data, wrong = examine(meas, scale)
    return [c.to_json() for c in checks], data, wrong, scale


def say_checks(verb: str, checks) -> None:
    """Every check that is not ok, one line each on stderr (after the work is done, so a
    refusal stays one line)."""
    for check in checks:
        if check["status"] != "ok":
            print(f"hdsim {verb}: {check['status']}: {check['message']}", file=sys.stderr, flush=True)


def run(args) -> int:
    from hdsim.identification.fit import fit
    from hdsim.identification.outcome import plausibility
    from hdsim.identification.residuals import findings, whiteness

    from hdsim.errors import InputError

    meas, effects = load_inputs(args)
    checks, data, wrong, scale = examine_inputs(meas, args)
    if wrong:
        raise InputError(f"{meas.source}: this is not a {meas.test} test: {wrong}")
    result = fit(meas, effects, unit=args.unit)
    out = Path(args.out) if args.out else Path(Path(args.data).name).with_suffix(".fit.toml")
    result.save(out)
    summary = result.summary()
    summary["parameters_file"] = str(out)
    summary["whiteness"] = whiteness(result.residual)
    summary["findings"] = findings(meas, result.residual)
    summary["checks"] = checks + plausibility(summary, scale)
    summary["data"] = data
    say_checks("fit", summary["checks"])
    if args.json:
        from hdsim.cli import emit_json

        emit_json(summary)
        return 0
    print(f"{meas.source}: {meas.test} test, {len(meas)} rows, effects "
          f"{', '.join(result.families) or '(base model)'}")
    print(f"  rms error {summary['rmse_rad']:.3g} rad, max {summary['max_abs_error_rad']:.3g} rad, "
          f"BIC {summary['bic']:.1f} ({summary['n_params']} parameters)")
    print(f"  angle offset {result.offset:.6g} rad ± {result.uncertainty.get('offset_rad', 0):.2g} "
          "(fitted, not counted as error)")
    for name, value in result.internal.items():
        print(f"  {name:<28} {value:.6g} ± {result.uncertainty.get(name, float('nan')):.2g}")
    for line in summary["findings"]:
        print(f"  - {line}")
    print(f"  fitted parameter set: {out}")
    sys.stdout.flush()
    return 0
