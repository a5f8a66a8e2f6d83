"""Benchmark: one output revolution at 2000 rpm input on CSG-25-100 (issue 3: < 20 s on 2 cores).

    python benchmarks/bench_kinematic_error.py [--repeat 3] [--unit CSG-25-100]

Runs the shipped ``constant_speed`` scenario (ramp to 2000 rpm in 0.2 s, 0.05 output
revolution to settle, one output revolution measured = 100 wave-generator turns, every
effect of the unit on, kinematic error, WG-shaft friction) through ``run_scenario`` and
prints the wall time of the simulation, of the metrics that need extra runs (starting
torque), and the transmission accuracy as a sanity check. Also times the contract
scenario ``kinematic_error.toml`` (one revolution each way at 500 rpm under load).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from hdsim.model.catalog import load_unit
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import Scenario, load_scenario

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--unit", default="CSG-25-100")
    args = parser.parse_args()
    model = load_unit(args.unit)
    base = load_scenario(ROOT / "scenarios" / "constant_speed.toml")
    one_rev = Scenario({**base.data, "metrics": ["transmission_accuracy", "order_spectrum"]}, base.source)
    contract = load_scenario(ROOT / "scenarios" / "kinematic_error.toml")
    for label, scenario in (("1 output rev at 2000 rpm input (constant_speed.toml)", one_rev),
                            ("full constant_speed.toml incl. starting-torque run", base),
                            ("kinematic_error.toml (1 rev each way, 500 rpm, 1/4 T_N)", contract)):
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            run = run_scenario(model, scenario)
            times.append(time.perf_counter() - t0)
        solver = run.result.solver
        print(f"{label}: best {min(times):.2f} s, median {sorted(times)[len(times) // 2]:.2f} s "
              f"(nfev {solver['nfev']}, LU {solver['nlu']}); "
              f"transmission accuracy {run.metric('transmission_accuracy_arcsec'):.2f} arcsec")


if __name__ == "__main__":
    main()
