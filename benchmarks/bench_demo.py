"""Benchmark: wall time of `hdsim demo` (issue 2 asks for < 30 s on 2 cores).

    python benchmarks/bench_demo.py
"""

import subprocess
import sys
import tempfile
import time

with tempfile.TemporaryDirectory() as folder:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "hdsim", "demo"], cwd=folder, check=True, capture_output=True)
    print(f"hdsim demo: {time.perf_counter() - t0:.1f} s")
