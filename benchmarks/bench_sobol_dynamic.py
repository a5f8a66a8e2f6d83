"""Benchmark: a Sobol study of a dynamic output, the driven bench's transmission accuracy.

Three flexspline dimensions within ±10 %, N = 64 (320 runs of the contract kinematic-error
scenario ``kinematic_error.toml``, 1 output revolution each way at 500 rpm under a
quarter of T_N) on 2 local workers, as ``hdsim sobol --output
transmission_accuracy_arcsec`` runs it (``evaluator="auto"``: the driven bench's quasi-static
evaluator where its criterion holds, as it does here): wall time per run. Then, in the same
run, the reference: the same study through ``solve_ivp`` (``evaluator="dynamic"``), and one
driven run on its own (the same scenario and solver options, one ``solve_ivp`` per
parameter set), for the ratios.

    python benchmarks/bench_sobol_dynamic.py [--n 64] [--workers 2] [--single 2] [--no-reference]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import hdsim
from hdsim.model.catalog import load_unit
from hdsim.scenarios.run import run_scenario
from hdsim.sensitivity.scenario_outputs import STUDY_SOLVER

NAMES = ["h_pz", "h_c", "R_v"]
OUTPUT = "transmission_accuracy_arcsec"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=64)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--single", type=int, default=2, help="single runs timed for the ratio")
    parser.add_argument("--no-reference", action="store_true", help="skip the solve_ivp study (~30 s)")
    args = parser.parse_args()

    walls = {}
    for evaluator in ("auto",) if args.no_reference else ("auto", "dynamic"):
        t0 = time.perf_counter()
        study = hdsim.sobol("CSG-25-100", NAMES, OUTPUT, n=args.n, workers=args.workers, progress=False,
                            evaluator=evaluator)
        walls[evaluator] = wall = time.perf_counter() - t0
        per_run = wall / study.evaluations
        print(f"study: {OUTPUT}, {len(NAMES)} parameters, N={args.n}, {study.evaluations} runs, "
              f"{args.workers} workers: {wall:.1f} s, {per_run * 1e3:.0f} ms of wall time per run "
              f"(evaluator: {study.extra['evaluator']['chosen']})")
        print("  ST", {n: round(float(v), 3) for n, v in zip(NAMES, study.analysis["ST"])})
    if "dynamic" in walls:
        print(f"the solve_ivp study takes {walls['dynamic'] / walls['auto']:.1f}x the wall time")
    per_run = walls["auto"] / study.evaluations

    unit = load_unit("CSG-25-100")
    nominal = unit.params()
    rng = np.random.default_rng(0)
    times = []
    for _ in range(args.single):
        row = {f"flexspline.{n}": nominal[f"flexspline.{n}"] * (1 + 0.1 * (2 * rng.random() - 1)) for n in NAMES}
        t0 = time.perf_counter()
        run_scenario(unit.with_updates(row), "kinematic_error", options=STUDY_SOLVER)
        times.append(time.perf_counter() - t0)
    single = float(np.median(times))
    print(f"one driven run on its own (solve_ivp, one process): {single:.2f} s; the batched study costs "
          f"{per_run * args.workers / single:.3f} of that per run and core ({single / per_run:.0f}x less wall time "
          f"per run on {args.workers} workers)")


if __name__ == "__main__":
    main()
