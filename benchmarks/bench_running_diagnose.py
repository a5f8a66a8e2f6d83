"""Benchmark: ``hdsim diagnose`` on a 25,000-row friction sweep (running-torque test).

Run::

    python benchmarks/bench_running_diagnose.py     # prints one JSON line

The sweep comes from ``tests/truth_running.py`` (independent truth: a Stribeck rise and
a ripple hidden, six speeds, current noise, encoder steps), capped at 25,000 rows.
``hdsim diagnose`` runs as a user would run it (a subprocess of the console entry point);
the line gives the wall time, the time inside the diagnosis (``seconds`` of its JSON, no
start-up or reading) and what was added. Every fit is a bounded linear least-squares
problem per Stribeck speed of a 16-point grid, so a diagnosis of three families with
hold-out halves and the proxy test is a few hundred of them.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(rows: int = 25000) -> int:
    sys.path.insert(0, str(HERE.parent / "tests"))
    import truth_running

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sweep.csv"
        cols, meta, _ = truth_running.make_running_data({"friction", "ripple"}, 3, max_rows=rows,
                                                        speeds_rpm=[20, 60, 200, 600, 1500, 3000])
        truth_running.write_csv(path, cols, meta)
        t0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-m", "hdsim", "diagnose", str(path), "--json"],
                             capture_output=True, text=True, check=True)
        wall = time.perf_counter() - t0
    result = json.loads(out.stdout)
    print(json.dumps({"rows": len(cols["time_s"]), "wall_s": round(wall, 2), "diagnose_s": result["seconds"],
                      "added": result["added"], "outcome": result["outcome"]}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
