"""Benchmark: one solve_ivp run of each built-in catalog scenario on the default unit
(a single model: Python floats through the laws, `DenseRadau`), wall time each.

    python benchmarks/bench_single_runs.py [--repeat 2]
"""

from __future__ import annotations

import argparse
import time

from hdsim.model.catalog import load_unit
from hdsim.scenarios.run import run_scenario

SCENARIOS = ("lost_motion", "stiffness", "kinematic_error", "running_torque")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2, help="runs of each scenario; the fastest counts")
    args = parser.parse_args()
    unit = load_unit("CSG-25-100")
    for name in SCENARIOS:
        best = float("inf")
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            run = run_scenario(unit, name)
            best = min(best, time.perf_counter() - t0)
        print(f"{name:16s} {best:6.2f} s  ({run.result.solver['nfev']} right-hand-side calls)")


if __name__ == "__main__":
    main()
