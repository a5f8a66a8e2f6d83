"""Benchmark: the seed paper's five-dimension lost-motion study through the simulator.

N = 1024 with second order (12,288 simulations) on 2 local processes, through the
quasi-static evaluator (what ``evaluator="auto"`` picks for this test) and through the
batched ``solve_ivp`` reference, in the same run: the wall time of each, their ratio and
the largest difference of the indices. Then the same scenario evaluated sample by sample
with a plain ``solve_ivp`` call per row (same solver options) on a subset, for the
batching's own speed-up.

    python benchmarks/bench_sobol_lost_motion.py [--n 1024] [--subset 6]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hdsim.sensitivity.scenario_outputs import STUDY_SAMPLES, STUDY_SOLVER, model_function, nominal_values
from hdsim.model.catalog import load_unit
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario
from hdsim.sensitivity.problem import build_problem
from hdsim.sensitivity.study import run_study

NAMES = ["h_pz", "h_c", "R_v", "R_k", "h_p"]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--n", type=int, default=1024)
    parser.add_argument("--subset", type=int, default=6)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()

    problem = build_problem(NAMES, nominal_values("CSG-25-100", NAMES), 0.10, None, None)
    seconds, studies = {}, {}
    for evaluator in ("quasistatic", "dynamic"):
        func = model_function("CSG-25-100", NAMES, "lost_motion_arcmin", evaluator=evaluator)
        t0 = time.perf_counter()
        study = run_study(func, problem, args.n, second_order=True, workers=args.workers, progress=False,
                          log=lambda *a, **k: None)
        seconds[evaluator], studies[evaluator] = time.perf_counter() - t0, study
        print(f"study ({evaluator}): N={args.n}, second order, {study.evaluations} simulations, "
              f"{args.workers} workers: {seconds[evaluator]:.2f} s "
              f"({seconds[evaluator] / study.evaluations * 1e3:.3f} ms/simulation)")
        print("  S1", np.round(study.analysis["S1"], 4), "ST", np.round(study.analysis["ST"], 4))
    gap = np.max(np.abs(studies["quasistatic"].analysis["ST"] - studies["dynamic"].analysis["ST"]))
    print(f"quasi-static study {seconds['dynamic'] / seconds['quasistatic']:.1f}x faster than the solve_ivp "
          f"study; largest |ΔST| {gap:.4f}")
    batched, study = seconds["dynamic"], studies["dynamic"]

    # plain loop: one solve_ivp per parameter set, same scenario and solver options
    scenario = load_scenario(builtin_scenario_path("lost_motion"))
    base = load_unit("CSG-25-100")
    rng = np.random.default_rng(0)
    nominal = base.params()
    t0 = time.perf_counter()
    for _ in range(args.subset):
        row = {f"flexspline.{n}": nominal[f"flexspline.{n}"] * (1 + 0.1 * (2 * rng.random() - 1)) for n in NAMES}
        run_scenario(base.with_updates(row), scenario, options=STUDY_SOLVER,
                     samples_per_segment=STUDY_SAMPLES["lost_motion"])
    per_sample = (time.perf_counter() - t0) / args.subset
    loop_estimate = per_sample * study.evaluations
    print(f"plain per-sample solve_ivp loop: {per_sample:.3f} s/simulation -> "
          f"{loop_estimate:.0f} s for {study.evaluations} on one process "
          f"({loop_estimate / args.workers:.0f} s on {args.workers})")
    print(f"speed-up of the batched study over the plain loop on the same workers: "
          f"{loop_estimate / args.workers / batched:.0f}x")


if __name__ == "__main__":
    main()
