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

    from hdsim.errors import InputError
    from hdsim.model.running_terms import parse_running_effects

    columns = parse_column_map(args.columns) if args.columns else None
    try:  # a misspelt family: one line, exit 2, before reading anything big
        parse_effects(args.effects)
    except InputError as error:
        try:  # ... unless it names a running-torque family (ripple), which only the file can confirm
            parse_running_effects(args.effects)
        except InputError:
            raise error from None
    options = import_options(args)
    load_unit(args.unit)  # unknown unit: one line, exit 2, before reading anything big
    meas = load_measurement(args.data, columns, **vars(options))
    if meas.test == "running_torque":  # its own families (friction, damping, ripple)
        return meas, parse_running_effects(args.effects)
    return meas, parse_effects(args.effects)


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


def _emitted(args, summary: dict, checks: list, data: dict) -> bool:
    """Put the checks and the data summary in ``summary``, say the checks that are not ok, and
    print the JSON object if asked (True: the caller prints nothing more)."""
    summary["checks"] = checks
    summary["data"] = data
    say_checks("fit", checks)
    if args.json:
        from hdsim.cli import emit_json

        emit_json(summary)
    return bool(args.json)


def run(args) -> int:
    from hdsim.identification.fit import fit
    from hdsim.identification.outcome import plausibility
    from hdsim.identification.residuals import findings, whiteness

    from hdsim.errors import InputError

    meas, effects = load_inputs(args)
    checks, data, wrong, scale = examine_inputs(meas, args)
    if wrong:
        raise InputError(f"{meas.source}: this is not a {meas.test} test: {wrong}")
    if meas.test == "running_torque":
        return _run_running(args, meas, effects, checks, data, scale)
    result = fit(meas, effects, unit=args.unit)
    out = Path(args.out) if args.out else Path(Path(args.data).name).with_suffix(".fit.toml")
    result.save(out)
    summary = result.summary()
    summary["parameters_file"] = str(out)
    summary["whiteness"] = whiteness(result.residual)
    summary["findings"] = findings(meas, result.residual)
    if _emitted(args, summary, checks + plausibility(summary, scale), data):
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


def _run_running(args, meas, effects, checks, data, scale) -> int:
    """``hdsim fit`` on a running-torque test: the law, its two figures and the fit file."""
    from hdsim.identification.running_fit import fit_running, running_plausibility
    from hdsim.identification.running_report import fit_figures

    result = fit_running(meas, effects)
    out = Path(args.out) if args.out else Path(Path(args.data).name).with_suffix(".fit.toml")
    result.save(out)
    figures = fit_figures(result, out.with_suffix(""), scale.running_torque or None)
    summary = result.summary()
    summary["parameters_file"] = str(out)
    summary["figures"] = [str(f) for f in figures]
    if _emitted(args, summary, checks + running_plausibility(result, scale), data):
        return 0
    m = summary["metrics"]
    print(f"{meas.source}: running_torque test, {len(meas)} rows, torque on the {meas.torque_side}, effects "
          f"{', '.join(result.families) or '(base: one Coulomb level)'}")
    print(f"  rms error {summary['rmse_Nm']:.3g} N·m (noise floor {summary['noise_floor_Nm']:.3g} N·m)")
    levels = {k: "not run" if v is None else f"{v:.4g} N·m" for k, v in m.items()}
    print(f"  running torque forward {levels['running_torque_forward_Nm']}, reverse "
          f"{levels['running_torque_reverse_Nm']}")
    for name, value in summary["law"].items():
        print(f"  {name:<24} {value}")
    print(f"  fitted law: {out}; figures: {', '.join(summary['figures'])}")
    sys.stdout.flush()
    return 0
