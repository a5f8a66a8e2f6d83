"""``hdsim units``: the built-in units and their catalog data."""

from __future__ import annotations

from hdsim.model.catalog import catalog_entry, default_unit, unit_names


def register(subparsers) -> None:
    p = subparsers.add_parser("units", help="list the built-in units and their catalog data")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=main)


def main(args) -> int:
    entries = {name: catalog_entry(name) for name in unit_names()}
    if args.json:
        from hdsim.cli import emit_json

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
