"""``hdsim simulate SCENARIO``: run one scenario (a file or a built-in name) on one unit."""

from __future__ import annotations

import sys
from pathlib import Path

from hdsim.cli import _common, emit_json
from hdsim.cli._guards import check_output_folder, path_argument
from hdsim.model.catalog import load_unit
from hdsim.scenarios.evaluator import EVALUATORS
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import builtin_scenario_names, load_scenario


def register(subparsers) -> None:
    """Add the ``simulate`` verb."""
    p = subparsers.add_parser("simulate", help="run a scenario on a unit",
                              description="Run a scenario (a TOML file or a built-in scenario) on a "
                                          "built-in unit or a drive file; write an HDF5 result and figures to --out.")
    p.add_argument("scenario", help="scenario file (e.g. my_test.toml) or built-in scenario name: "
                                    + ", ".join(builtin_scenario_names()))
    p.add_argument("--unit", default=None,
                   help="built-in unit (default CSG-25-100; see 'hdsim units') or a drive file "
                        "(a TOML file of datasheet figures; 'hdsim units --template')")
    _common.add_set_argument(p)
    p.add_argument("--out", type=path_argument, default="hdsim-out", help="output folder (default ./hdsim-out)")
    p.add_argument("--no-figures", action="store_true", help="write the HDF5 result only")
    p.add_argument("--evaluator", choices=EVALUATORS, default="dynamic",
                   help="'dynamic' (default): solve_ivp on the full model, the reference; "
                        "'quasistatic': the twist's inertia dropped; 'auto': the latter where the "
                        "bench's criterion holds (the ±4 %% lost-motion test, kinematic-error runs at "
                        "constant speed)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=main)


def main(args) -> int:
    """Run the scenario, write the run file and figures, print the metrics; exit status."""
    # everything that can be wrong with the input is checked before anything is written
    scenario = load_scenario(args.scenario)
    model, scenario = _common.apply_sets(load_unit(args.unit), scenario, _common.parse_sets(args.sets))
    # an unwritable folder (or a folder where a result file goes) is said before the run, not after it
    check_output_folder(args.out, "--out", names=_common.output_names(scenario, figures=not args.no_figures))
    run = run_scenario(model, scenario, evaluator=args.evaluator)
    # a run that overflowed is refused here, before any file is written, not reported as a result
    paths = _common.write_outputs(run, Path(args.out), figures=not args.no_figures)
    metrics = _common.metrics_as_floats(run.metrics)
    if args.json:
        emit_json({"scenario": scenario.name, "unit": model.name, "metrics": metrics,
                   "result": paths["result"], "files": paths,
                   "evaluator": run.result.metadata["evaluator"]["chosen"]})
    else:
        _common.print_metrics(f"{scenario.name} on {model.name}:", metrics)
        print(f"result: {paths['result']}")
    print(f"wrote {', '.join(paths.values())}", file=sys.stderr)
    return 0
