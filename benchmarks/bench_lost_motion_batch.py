"""Benchmark: one 128-row batch of the lost-motion study (the unit of work of a Sobol study).

The five flexspline dimensions within ±10 %, the study's solver settings, best of three.
Run it in two checkouts in one sitting to compare them (timings on a shared machine are
noisy; compare ratios):

    python benchmarks/bench_lost_motion_batch.py
"""

from __future__ import annotations

import time

import numpy as np

from hdsim.sensitivity.scenario_outputs import model_function, nominal_values

NAMES = ["h_pz", "h_c", "R_v", "R_k", "h_p"]


def main() -> None:
    f = model_function("CSG-25-100", NAMES, "lost_motion_arcmin")
    nominal = np.array(list(nominal_values("CSG-25-100", NAMES).values()))
    X = nominal * (1 + 0.1 * (2 * np.random.default_rng(0).random((128, 5)) - 1))
    f(X[:4])  # warm-up: imports and caches
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        f(X)
        times.append(time.perf_counter() - t0)
    print(f"lost-motion batch: {min(times):.2f} s per 128 rows ({1e3 * min(times) / 128:.1f} ms per row)")


if __name__ == "__main__":
    main()
