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
    p = subparsers.add_parser("fit", help=HELP, description=HELP + ".")
    p.add_argument("data", metavar="DATA", help="measurement file (CSV or HDF5; see docs/measurements.md)")
    p.add_argument("--effects", default="",
                   help="families or effect ids, e.g. hardening,friction or dahl; "
                        "absent: the base model (linear compliance and angle offset)")
    p.add_argument("--unit", default=None, help="built-in unit to start from (default CSG-25-100)")
    p.add_argument("--columns", default=None, metavar="MAP",
                   help="column map for another bench, e.g. time_s=t,torque_Nm=T_out,angle_deg=pos")
    p.add_argument("--out", default=None, metavar="FILE",
                   help="where to write the fitted parameter set (default: DATA stem + .fit.toml)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=run)


def load_inputs(args):
    """(measurement, effects) with every input checked before anything runs."""
    from hdsim.model.catalog import load_unit
    from hdsim.identification.fit import parse_effects
    from hdsim.io.measurement import load_measurement, parse_column_map

    columns = parse_column_map(args.columns) if args.columns else None
    effects = parse_effects(args.effects)
    load_unit(args.unit)  # unknown unit: one line, exit 2, before reading anything big
    meas = load_measurement(args.data, columns)
    return meas, effects


def run(args) -> int:
    from hdsim.identification.fit import fit
    from hdsim.identification.residuals import findings, whiteness

    meas, effects = load_inputs(args)
    result = fit(meas, effects, unit=args.unit)
    out = Path(args.out) if args.out else Path(Path(args.data).name).with_suffix(".fit.toml")
    result.save(out)
    summary = result.summary()
    summary["parameters_file"] = str(out)
    summary["whiteness"] = whiteness(result.residual)
    summary["findings"] = findings(meas, result.residual)
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
