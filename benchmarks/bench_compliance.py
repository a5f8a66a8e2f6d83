"""Benchmark: the compliance chain and its finite-element checks.

    python benchmarks/bench_compliance.py      # prints one JSON line

- ``chain_per_geometry_us``: the closed-form chain for a batch of 12,288 geometries (the
  seed study's design), per geometry — what a Sobol study pays on top of the simulation.
- ``fe_cup_s``: one converged finite-element cup (`hdsim compliance --fe`), after the
  first call has imported scikit-fem; ``fe_cup_import_s``: the first call's extra.
- ``fe_rim_s``: the rim on the balls as ``hdsim compliance --fe`` checks it (two
  plane-stress solves, balls on the zone centre and straddling it, refinement 2).
"""

from __future__ import annotations

import json
import time

import numpy as np

from hdsim.model.catalog import load_unit
from hdsim.model.fe_check import fe_cup_compliance, fe_rim_stiffness


def main() -> int:
    model = load_unit()
    g = model.geometry
    rng = np.random.default_rng(0)
    n = 12288
    batch = model.with_updates({f"flexspline.{k}": getattr(g, k) * rng.uniform(0.9, 1.1, n)
                                for k in ("h_pz", "h_c", "R_v", "R_k", "h_p")})
    t0 = time.perf_counter()
    for _ in range(5):
        batch.compliance()
    chain_us = (time.perf_counter() - t0) / 5 / n * 1e6
    t0 = time.perf_counter()
    fe_cup_compliance(g)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    for _ in range(5):
        fe_cup_compliance(g)
    cup_s = (time.perf_counter() - t0) / 5
    t0 = time.perf_counter()
    fe_rim_stiffness(model)
    rim_s = time.perf_counter() - t0
    print(json.dumps({"chain_per_geometry_us": round(chain_us, 3), "fe_cup_s": round(cup_s, 3),
                      "fe_cup_import_s": round(first - cup_s, 3), "fe_rim_s": round(rim_s, 3)}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
