"""Benchmark: in-process diagnoses of small records, the kind a battery and the test
suite run by the thousand.

Run::

    python benchmarks/bench_small_diagnoses.py [--repeat 3]     # prints one JSON line

On a record of a few thousand rows the compiled evaluator's loop over the samples is a
small part of a fit's pass; the rest is building the trial models (parameter checks, the
stiffness split, stacking them into one batch), so this is where the per-pass overhead of
`hdsim.identification.optimizer.fit_many` shows. Three records: the shipped stiffness and
kinematic-error examples (``tests/data``) and a friction sweep from ``tests/truth_running.py``
(seed 0, a Stribeck rise and a ripple hidden). Each is diagnosed once to warm the caches,
then ``--repeat`` times; the fastest counts. No start-up or reading is timed.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def best_seconds(meas, repeat: int) -> tuple[float, list]:
    import hdsim

    added = hdsim.diagnose(meas).added
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        hdsim.diagnose(meas)
        best = min(best, time.perf_counter() - t0)
    return best, added


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="timed diagnoses of each record; the fastest counts")
    args = parser.parse_args()
    sys.path.insert(0, str(HERE.parent / "tests"))
    import truth
    import truth_running

    from hdsim.io.measurement import load_measurement

    records = {name: load_measurement(HERE.parent / "tests" / "data" / f"{name}.csv")
               for name in ("stiffness_example", "ke_example")}
    with tempfile.TemporaryDirectory() as tmp:
        cols, meta, _ = truth_running.make_running_data(("friction", "ripple"), seed=0)
        truth.write_csv(Path(tmp) / "sweep.csv", cols, meta)
        records["friction_sweep"] = load_measurement(Path(tmp) / "sweep.csv")
    out = {}
    for name, meas in records.items():
        seconds, added = best_seconds(meas, args.repeat)
        out[name] = {"rows": int(meas.time.size), "seconds": round(seconds, 3), "added": added}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
