"""Benchmark: one solve_ivp run of each built-in catalog scenario on the default unit
(a single model: Python floats through the laws, `DenseRadau`), wall time each, and the
cost of one right-hand-side call of the driven bench.

    python benchmarks/bench_single_runs.py [--repeat 2]
"""

from __future__ import annotations

import argparse
import time
import timeit

from hdsim.model.catalog import load_unit
from hdsim.scenarios.driven import bench_from_scenario
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import load_scenario

SCENARIOS = ("lost_motion", "stiffness", "kinematic_error", "running_torque")
DRIVEN = ("kinematic_error", "running_torque")


def rhs_microseconds(unit, name: str, calls: int = 20000) -> float:
    """One right-hand-side call of the driven bench of scenario ``name`` near its start
    state [µs], best of five rounds of ``calls``."""
    system = bench_from_scenario(unit, load_scenario(name)).system(unit)
    y = system.y0 + 1e-6
    return min(timeit.repeat(lambda: system.rhs(0.7, y), number=calls, repeat=5)) / calls * 1e6


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
    for name in DRIVEN:
        print(f"{name:16s} {rhs_microseconds(unit, name):6.1f} µs a right-hand-side call")


if __name__ == "__main__":
    main()
