"""``hdsim fit``: fit the model with the named effect families to a measurement file.

Examples::

    hdsim fit bench.csv --effects hardening,friction --json
    hdsim fit other_bench.csv --columns time_s=t,torque_Nm=T_out,angle_deg=pos --out fitted.toml

The fitted parameter set is written as TOML (``--out``, default ``<data stem>.fit.toml`` in
the current folder); `hdsim.identification.fit.load_fitted` turns it back into a model.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from hdsim.cli._guards import path_argument

HELP = "fit the model with the named effect families to a measurement file"


def register(subparsers) -> None:
    from hdsim.cli._import_arguments import add_record_parser

    p = add_record_parser(subparsers, "fit", HELP, "families or effect ids, e.g. hardening,friction or dahl; "
                                                   "absent: the base model (linear compliance and angle offset)")
    p.add_argument("--out", type=path_argument, default=None, metavar="FILE",
                   help="where to write the fitted parameter set (default: DATA stem + .fit.toml)")
    p.add_argument("--report", type=path_argument, default=None, metavar="DIR",
                   help="write a self-contained page of the fit (index.html, index.md, figures) into DIR")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=run)


def load_inputs(args):
    """(measurement, effects) with every input checked before anything runs."""
    from hdsim.cli._import_arguments import cli_words, import_options
    from hdsim.errors import InputError
    from hdsim.identification import workflow  # registers the built-in test kinds
    from hdsim.identification.test_kinds import test_kind, test_kinds
    from hdsim.io.measurement import load_measurement, parse_column_map
    from hdsim.model.catalog import load_unit

    del workflow  # imported for the kinds it registers, not used by name

    columns = parse_column_map(args.columns) if args.columns else None
    # a misspelt family: one line, exit 2, before reading anything big. With --test the kind
    # is known and says it in its own words (another kind's had named a valid family of this
    # one); without, which kind's family it must be only the file says, so any kind's will do
    errors = []
    for kind in [test_kind(args.test)] if args.test else test_kinds().values():
        try:
            kind.parse_effects(args.effects)
            break
        except InputError as error:
            errors.append((kind, error))
    else:  # the words of a kind that knows the family named ('ripple=positon_torque': the sweep's)
        named = {part.partition("=")[0].strip() for part in str(args.effects).split(",")}
        raise next((e for k, e in errors if named & set(k.families())), errors[-1][1])
    try:  # the library names its keywords (drop_nan=True); the command line says its flags
        options = import_options(args)
        load_unit(args.unit)  # unknown unit: one line, exit 2, before reading anything big
        meas = load_measurement(args.data, columns, **vars(options))
    except InputError as error:
        raise InputError(cli_words(str(error))) from None
    return meas, test_kind(meas.test).parse_effects(args.effects)


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


#: what to look at when a fit gives a non-finite value (`hdsim.cli._guards.require_finite`)
NONFINITE_FIT_HINT = ("a cell of the record is probably far out of range (a mistyped or overflowed value): "
                      "correct it, or cut it out with --window")


def run(args) -> int:
    from hdsim.cli._guards import check_output_file, check_output_folder, require_finite
    from hdsim.identification.test_kinds import test_kind
    from hdsim.identification.workflow import drive_scale, fit

    meas, effects = load_inputs(args)
    kind = test_kind(meas.test)
    out = Path(args.out) if args.out else Path(Path(args.data).name).with_suffix(".fit.toml")
    # where the results go is checked before the fit, not after it
    check_output_file(out, "--out", args.data)  # the default path too: --out is how to change it
    if args.report:
        check_output_folder(args.report, "--report", data=args.data)
    result = fit(meas, effects, unit=args.unit)  # checked, thinned, refused if not its test
    require_finite(result.summary(), f"the fit of {meas.source}", NONFINITE_FIT_HINT)
    result.save(out)
    scale = drive_scale(args.unit)
    summary = kind.fit_summary(result, out.with_suffix(""), scale)
    summary["parameters_file"] = str(out)
    if args.report:
        from hdsim.identification.report_page import fit_page

        page = fit_page(result, args.report, {**summary, "checks": result.checks}, kind, scale)
        summary["report"] = str(page)
    if _emitted(args, summary, list(result.checks), dict(result.data)):
        return 0
    _PRINTERS[kind.error_key](meas, result, summary)
    sys.stdout.flush()
    return 0


def _print_twist(meas, result, summary) -> None:
    print(f"{meas.source}: {meas.test} test, {result.data['rows']} rows, effects "
          f"{', '.join(result.families) or '(base model)'}")
    print(f"  rms error {summary['rmse_rad']:.3g} rad, max {summary['max_abs_error_rad']:.3g} rad, "
          f"BIC {summary['bic']:.1f} ({summary['n_params']} parameters)")
    print(f"  angle offset {result.offset:.6g} rad ± {result.uncertainty.get('offset_rad', 0):.2g} "
          "(fitted, not counted as error)")
    for name, value in result.internal.items():
        sigma = result.uncertainty.get(name, float("nan"))
        print(f"  {name:<28} {value:.6g} " + (f"± {sigma:.2g}" if not math.isinf(sigma) else "(not determined)"))
    _print_harmonics(result)
    for line in summary["findings"]:
        print(f"  - {line}")
    print(f"  fitted parameter set: {summary['parameters_file']}")


def _print_harmonics(result) -> None:
    """The kinematic error's amplitudes [arcsec] and phases [rad], each with its uncertainty
    (solved linearly, so not among the fitted coordinates)."""
    from hdsim.units import ARCSEC_PER_RAD

    for name, value in result.params.items():
        family, _, field = name.partition(".")
        sigma = result.uncertainty.get(name)
        if family != "kinematic_error" or sigma is None:
            continue
        amplitude = field.startswith("a")
        scale, unit = (ARCSEC_PER_RAD, "arcsec") if amplitude else (1.0, "rad")
        told = f"± {sigma * scale:.2g} {unit}" if math.isfinite(sigma) else f"{unit} (not determined)"
        print(f"  {name:<28} {value * scale:.4g} {told}")


def starting_torque_lines(derived: dict, shaft: str) -> list[str]:
    """A torque fit's starting torque as console lines: each way where the law is asymmetric
    (`hdsim.identification.sweep_start`), else its one level, and what it rests on."""
    lines = []
    # a way the record never runs is null: "not run"; no level at all, no lines of levels
    has_level = derived.get("starting_torque_Nm") is not None
    ways = [w for w in ("forward", "reverse") if f"starting_torque_{w}_Nm" in derived] or [""]
    for way in ways if has_level else []:
        key = f"starting_torque_{way}_" if way else "starting_torque_"
        value, sigma = derived[key + "Nm"], derived.get(key + "uncertainty_Nm")
        label = f"starting torque {way} (the law at rest)" if way else "starting torque (the law at rest)"
        shown = ("not run (not determined by the record)" if value is None
                 else f"{value:.4g} N·m (not determined by the record)" if sigma is None
                 else f"{value:.4g} ± {sigma:.2g} N·m")
        lines.append(f"  {label:<42} {shown}" + ("" if value is None else f" on {shaft}"))
    if derived.get("starting_torque_basis"):
        lines.append(f"  starting torque: {derived['starting_torque_basis']}")
    return lines


def _print_torque(meas, result, summary) -> None:
    side = meas.torque_side
    print(f"{meas.source}: {meas.test} test, {result.data['rows']} rows, torque on the {side} shaft, effects "
          f"{', '.join(result.families) or '(base model)'}")
    print(f"  rms error {summary['rmse_Nm']:.3g} N·m (noise floor {summary['noise_floor_Nm']:.3g} N·m)")
    for name, value in summary["metrics"].items():
        shown = "not run" if value is None else f"{value:.4g}"
        print(f"  {name:<40} {shown}")
    for line in starting_torque_lines(summary.get("derived", {}), f"the {side} shaft"):
        print(line)
    for way, basis in summary.get("running_torque_basis", {}).items():
        print(f"  running torque {way}: {basis}")
    for ripple in summary.get("ripple_Nm", []):
        print(f"  ripple at order {ripple['order']:.4g} of the WG angle: {ripple['amplitude_Nm']:.3g} N·m on the "
              f"{side} shaft")
    if "law" in summary:
        print("  fitted law (wave-generator shaft; pastes into a scenario's [input_friction]):")
    for name, value in summary.get("law", summary.get("fitted", {})).items():
        shown = (", ".join(f"{v:.4g}" for v in value) if isinstance(value, list)
                 else f"{value:.4g}" if isinstance(value, float) else str(value))
        print(f"  {name:<28} {shown}")
    figures = f"; figures: {', '.join(summary['figures'])}" if summary.get("figures") else ""
    print(f"  fitted parameters: {summary['parameters_file']}{figures}")


#: console formats by the error a test kind fits (an angle, or a torque)
_PRINTERS = {"rmse_rad": _print_twist, "rmse_Nm": _print_torque}
