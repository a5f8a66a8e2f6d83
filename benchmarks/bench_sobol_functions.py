"""Estimator accuracy and interval honesty on the closed forms, by N.

For Ishigami, the Sobol G-function and the linear model: largest error of S1 and
ST against the analytic values, and the median 95 % half-width of both interval
kinds (R = 4 replicates vs SALib's bootstrap), plus wall time (in-process).

    python benchmarks/bench_sobol_functions.py [--n 1024 4096 8192] [--seed 0]
    python benchmarks/bench_sobol_functions.py --coverage     # 40 seeds, N = 1024
    python benchmarks/bench_sobol_functions.py --replicates   # R = 1, 2, 4, 8 at N = 4096

``--coverage`` counts how often each 95 % interval (around the reported estimate)
holds the exact value; ``--replicates`` shows why the default is R = 4.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hdsim.sensitivity import FUNCTIONS, GFunction, Ishigami, Linear, run_study
from hdsim.sensitivity.analysis import analyse, estimates
from hdsim.sensitivity.design import replicate_seed, sample_replicate


def _design(f, n, R, seed):
    return np.concatenate([sample_replicate(f.problem(), n // R, replicate_seed(seed, r), False)
                           for r in range(R)])


def coverage(n=1024, R=4, seeds=40) -> None:
    print(f"coverage of 95 % intervals, N = {n}, R = {R}, {seeds} seeds (S1 and ST pooled)")
    for f in (Linear(), Ishigami(), GFunction()):
        exact, hits, widths = f.analytic(), {"rep": [], "boot": []}, {"rep": [], "boot": []}
        for seed in range(seeds):
            X = _design(f, n, R, seed)
            a = analyse(f.problem(), X, f(X), second_order=False, replicates=R, seed=seed)
            for key in ("S1", "ST"):
                err = np.abs(a[key] - exact[key])
                for kind, suffix in (("rep", "_conf_replicates"), ("boot", "_conf")):
                    hits[kind].append(err <= a[key + suffix])
                    widths[kind].append(a[key + suffix])
        print(f"{type(f).__name__:>10}: replicates {np.mean(hits['rep']):.3f} "
              f"(median half-width {np.median(widths['rep']):.4f}), bootstrap "
              f"{np.mean(hits['boot']):.3f} ({np.median(widths['boot']):.4f})")


def replicate_choice(n=4096, seeds=20) -> None:
    print(f"largest |error| of S1/ST over {seeds} seeds at N = {n}, by replicates R")
    for f in (Ishigami(), GFunction()):
        D, exact = f.problem().num_vars, f.analytic()
        for R in (1, 2, 4, 8):
            errs = []
            for seed in range(seeds):
                X = _design(f, n, R, seed)
                e = estimates(f(X).reshape(-1, D + 2), D, False)
                errs.append(max(np.abs(e[k] - exact[k]).max() for k in ("S1", "ST")))
            print(f"{type(f).__name__:>10} R = {R}: max {max(errs):.4f}, "
                  f"median {np.median(errs):.4f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[1024, 4096, 8192])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--coverage", action="store_true")
    ap.add_argument("--replicates", action="store_true")
    args = ap.parse_args()
    if args.coverage:
        coverage()
    if args.replicates:
        replicate_choice()
    if args.coverage or args.replicates:
        return
    print(f"{'function':>10} {'N':>6} {'|dS1|max':>9} {'|dST|max':>9} "
          f"{'hw rep':>8} {'hw boot':>8} {'seconds':>8}")
    for name, cls in FUNCTIONS.items():
        f = cls()
        exact = f.analytic()
        for n in args.n:
            t0 = time.perf_counter()
            a = run_study(f, f.problem(), n, seed=args.seed, workers=1, progress=False).analysis
            dt = time.perf_counter() - t0
            d1 = np.abs(a["S1"] - exact["S1"]).max()
            dT = np.abs(a["ST"] - exact["ST"]).max()
            hw_rep = np.median(np.r_[a["S1_conf_replicates"], a["ST_conf_replicates"]])
            hw_boot = np.median(np.r_[a["S1_conf"], a["ST_conf"]])
            print(f"{name:>10} {n:>6} {d1:>9.4f} {dT:>9.4f} {hw_rep:>8.4f} {hw_boot:>8.4f} "
                  f"{dt:>8.2f}")


if __name__ == "__main__":
    main()
