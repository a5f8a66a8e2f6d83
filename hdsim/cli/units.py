"""``hdsim units``: the built-in units and their catalog data; a drive-file template."""

from __future__ import annotations

from hdsim.model.datasheet import catalog_entry, default_unit, unit_names


def register(subparsers) -> None:
    p = subparsers.add_parser("units", help="list the built-in units and their catalog data",
                              description="List the built-in units and their catalog data, or print "
                                          "a drive-file template (any drive from its datasheet).")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--template", action="store_true",
                   help="print a commented drive-file template (TOML) on stdout; save it, edit it "
                        "and give its path wherever a unit is accepted (--unit my_drive.toml); with --json, "
                        "one JSON object whose 'template' holds that text")
    p.set_defaults(func=main)


def main(args) -> int:
    from hdsim.cli import emit_json

    if args.template:
        from hdsim.model.drive_file import template

        if args.json:  # --json always prints one JSON object: the template's text is its value
            emit_json({"format": "toml", "template": template()})
        else:
            print(template(), end="")
        return 0
    entries = {name: catalog_entry(name) for name in unit_names()}
    if args.json:
        emit_json({"default": default_unit(), "units": entries})
        return 0
    header = f"{'unit':<12} {'T_N':>6} {'T1':>6} {'T2':>6} {'K1':>9} {'K2':>9} {'K3':>9}  status"
    print(header)
    print(f"{'':<12} {'[N·m]':>6} {'[N·m]':>6} {'[N·m]':>6} {'[N·m/rad]':>9} {'[N·m/rad]':>9} {'[N·m/rad]':>9}")
    for name, e in entries.items():
        mark = " (default)" if name == default_unit() else ""
        print(f"{name:<12} {e['rated_torque']:>6g} {e['T1']:>6g} {e['T2']:>6g} {e['K1']:>9.3g} "
              f"{e['K2']:>9.3g} {e['K3']:>9.3g}  {e['status']}{mark}")
    return 0
