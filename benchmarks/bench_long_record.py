"""Benchmark: ``hdsim diagnose`` on one stiffness record logged at three sampling rates.

A plain linear spring (K = 31,000 N·m/rad, nothing else) under a ±T_N cosine cycle of
100 s, angle plus white noise of 2e-6 rad, logged at 200 Hz, 2 kHz and 10 kHz: 20,000,
200,000 and 1,000,000 rows (``--rows`` changes the list). Nothing is missing from a
linear model, so the right answer is ``nothing_missing`` with the rms at the noise, at
every rate. Each run is ``hdsim diagnose FILE --json`` in a subprocess, as a user runs
it; the line printed per rate gives the wall time, the peak resident memory of that
process (``ru_maxrss`` of the child), the outcome and the final rms against the noise.

    python benchmarks/bench_long_record.py [--rows 20000 200000 1000000] [--hdf5]
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

import numpy as np

K = 31_000.0  # N·m/rad
RATED = 87.0  # N·m
NOISE = 2e-6  # rad
DURATION = 100.0  # s


def record(rows: int, seed: int = 0) -> dict[str, np.ndarray]:
    """The same ±T_N cycle (two cycles, cosine ramps) sampled with ``rows`` rows."""
    t = np.linspace(0.0, DURATION, rows)
    waypoints = np.array([0.0, 1.0, -1.0, 1.0, -1.0, 0.0]) * RATED
    edges = np.linspace(0.0, DURATION, waypoints.size)
    segment = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, waypoints.size - 2)
    phase = (t - edges[segment]) / (edges[segment + 1] - edges[segment])
    torque = waypoints[segment] + (waypoints[segment + 1] - waypoints[segment]) * 0.5 * (1 - np.cos(np.pi * phase))
    angle = torque / K + np.random.default_rng(seed).normal(0.0, NOISE, rows)
    return {"time_s": t, "torque_Nm": torque, "angle_rad": angle}


def write(path: Path, columns: dict[str, np.ndarray], hdf5: bool) -> Path:
    if hdf5:
        import h5py

        path = path.with_suffix(".h5")
        with h5py.File(path, "w") as f:
            f.attrs["test"] = "stiffness"
            for name, values in columns.items():
                f.create_dataset(name, data=values)
        return path
    path = path.with_suffix(".csv")
    with open(path, "w") as f:
        f.write("# test: stiffness\n" + ",".join(columns) + "\n")
        np.savetxt(f, np.column_stack(list(columns.values())), delimiter=",", fmt="%.9g")
    return path


def diagnose(path: Path) -> tuple[float, float, dict]:
    """(wall time [s], peak RSS of the child [GB], the JSON it printed)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "hdsim", "diagnose", str(path), "--json"],
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    if done.returncode != 0:
        raise SystemExit(f"hdsim diagnose failed ({done.returncode}): {done.stderr.strip()}")
    # ru_maxrss of the children is the largest so far: runs go from small to large
    return wall, max(peak, before) / 1024**2, json.loads(done.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, nargs="+", default=[20_000, 200_000, 1_000_000])
    parser.add_argument("--hdf5", action="store_true", help="write HDF5 instead of CSV")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for rows in sorted(args.rows):
            path = write(Path(tmp) / f"spring_{rows}", record(rows), args.hdf5)
            wall, peak_gb, out = diagnose(path)
            print(f"{rows:>9} rows ({rows / DURATION:,.0f} Hz): {wall:6.1f} s, peak {peak_gb:.2f} GB, "
                  f"outcome {out['outcome']}, rms {out['final']['rmse_rad']:.3g} rad, noise floor "
                  f"{out['data']['noise_floor_rad']:.3g} (added noise {NOISE:g})")


if __name__ == "__main__":
    main()
