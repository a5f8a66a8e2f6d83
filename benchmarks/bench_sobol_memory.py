"""Peak memory of a Sobol' study through the HDF5 store at N = 1024 and N = 8192.

Each N runs in a fresh interpreter (peak RSS only ever grows within a process):
the Sobol G-function (8 inputs) with second order, two local worker processes,
every chunk written to a study file. Prints peak RSS of the main process and of
the largest worker, in MiB.

    python benchmarks/bench_sobol_memory.py [--n 1024 8192]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def one(n: int) -> dict:
    from hdsim.sensitivity import GFunction, run_study

    g = GFunction()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        res = run_study(g, g.problem(), n, second_order=True, workers=2,
                        out=Path(tmp) / "study.h5", progress=False)
        seconds = time.perf_counter() - t0
    # ru_maxrss is in KiB on Linux.
    self_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    child_mib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return {"n": n, "evaluations": res.evaluations, "seconds": round(seconds, 2),
            "peak_rss_main_MiB": round(self_mib, 1), "peak_rss_worker_MiB": round(child_mib, 1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[1024, 8192])
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(one(args.one)))
        return
    print(f"{'N':>6} {'evaluations':>12} {'seconds':>8} {'main MiB':>9} {'worker MiB':>11}")
    for n in args.n:
        out = subprocess.run([sys.executable, __file__, "--one", str(n)], check=True,
                             capture_output=True, text=True).stdout
        r = json.loads(out)
        print(f"{r['n']:>6} {r['evaluations']:>12} {r['seconds']:>8} "
              f"{r['peak_rss_main_MiB']:>9} {r['peak_rss_worker_MiB']:>11}")


if __name__ == "__main__":
    main()
