"""``hdsim demo``: the ±4 % lost-motion test and the ±T_N stiffness test on the default unit."""

from __future__ import annotations

import sys
import time

from hdsim.cli import _common, emit_json
from hdsim.cli._guards import check_output_folder, path_argument
from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import catalog_entry, default_unit
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import load_scenario
from hdsim.units import rad_to_arcmin


def register(subparsers) -> None:
    """Add the ``demo`` verb."""
    p = subparsers.add_parser("demo", help="lost-motion and stiffness tests on the default unit",
                              description="Run the catalog ±4 % T_N lost-motion test and the ±T_N "
                                          "stiffness test; write figures and HDF5 results to --out.")
    p.add_argument("--unit", default=None,
                   help=f"built-in unit (default {default_unit()}) or a drive file (.toml)")
    p.add_argument("--out", type=path_argument, default="hdsim-demo", help="output folder (default ./hdsim-demo)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=main)


def main(args) -> int:
    """Run both tests, write their files, print the summary; exit status."""
    start = time.perf_counter()
    model = load_unit(args.unit)
    catalog = dict(model.provenance.get("catalog") or catalog_entry(model.name))
    scenarios = [load_scenario(name) for name in ("lost_motion", "stiffness")]
    names = [name for scenario in scenarios for name in _common.output_names(scenario)]
    out = check_output_folder(args.out, "--out", names=names)  # before the runs, not after them
    runs, summary, files = [], {}, {}
    for scenario in scenarios:
        print(f"running {scenario.name} on {model.name} ...", file=sys.stderr)
        run = run_scenario(model, scenario)
        runs.append(run)
        summary.update(_common.finite_metrics(run))
    for run in runs:  # both runs checked first: a failed second run leaves no files of the first
        files[run.scenario.name] = _common.write_outputs(run, out)
    elastic = rad_to_arcmin(0.08 * catalog["rated_torque"] / catalog["K1"])
    seconds = time.perf_counter() - start
    if args.json:
        emit_json({"unit": model.name, "metrics": summary, "catalog": catalog,
                   "elastic_lost_motion_arcmin": elastic, "files": files, "seconds": seconds})
        return 0
    print(f"hdsim demo: {model.name} (default effects: "
          f"{', '.join(f'{k}={e.id}' for k, e in model.effects().items())})")
    rows = [("lost motion, ±4 % T_N, full span", summary["lost_motion_arcmin"], "arcmin",
             f"elastic only 0.08·T_N/K1 = {elastic:.3f}"),
            ("lost motion, centre line of ±T_N loop", summary["lost_motion_centre_line_arcmin"], "arcmin", ""),
            ("hysteresis loss after ±T_N", summary["hysteresis_loss_arcmin"], "arcmin", "catalog class ~1"),
            ("torsion at T_N (fitted law)", summary["torsion_at_rated_arcmin"], "arcmin", ""),
            ("K1", summary["K1_Nm_per_rad"], "N·m/rad", f"catalog {catalog['K1']:.3g}"),
            ("K2", summary.get("K2_Nm_per_rad"), "N·m/rad", f"catalog {catalog['K2']:.3g}"),
            ("K3", summary.get("K3_Nm_per_rad"), "N·m/rad", f"catalog {catalog['K3']:.3g}")]
    for label, value, unit, note in rows:
        if value is None:  # a segment above the ±T_N cycle (a breakpoint above the rated torque)
            print(f"  {label:<40} {'not reached':>10} {unit:<8} {note}: the ±T_N cycle stays below its breakpoint")
            continue
        print(f"  {label:<40} {value:>10.4g} {unit:<8} {note}")
    print(f"figures and results in {out}/ ({seconds:.1f} s)")
    return 0
