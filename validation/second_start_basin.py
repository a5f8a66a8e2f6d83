"""Where the friction's second start is needed: truth records that trap a single start.

Each record is the zoo's reversing kinematic-error run (LuGre friction holding the body's
windup, a hard gap, a brake load reversing with the output; ``tests/truth_zoo.py``). It
is fitted with backlash + friction + kinematic error twice: with the Dahl friction's
second start (`Effect.other_starts`) and without it. A ratio well above 1 is a basin the
single start stays in; the slow test
``tests/test_fit.py::test_a_second_friction_start_escapes_the_basin_of_a_reversing_ke_run``
holds the record of this table that shows it most.

    python validation/second_start_basin.py --profiles one_rate,two_rates_equal,sine --seeds 12

prints, per record, the rms error [arcsec] with and without the second start and their
ratio, and writes them to ``validation/results/second_start_basin.json``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

EFFECTS = ["backlash", "friction", "kinematic_error"]
ARCSEC = np.degrees(1.0) * 3600.0


def with_and_without(case: tuple[str, int]) -> tuple[str, int, float, float]:
    """rms error [arcsec] of the fit with and without the friction's second start."""
    import truth_zoo as tz

    from hdsim.identification.fit import fit
    from hdsim.io.measurement import load_measurement
    from hdsim.model import effects as fx

    profile, seed = case
    cols, meta, _ = tz.make_case({"kinematic_error": "with_windup"}, {"backlash": "hard_gap"}, profile, seed,
                                 max_rows=6000)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "ke.csv")
        tz.write_csv(path, cols, meta)
        meas = load_measurement(path)
    both = fit(meas, EFFECTS)
    second = fx.DahlFriction.other_starts
    fx.DahlFriction.other_starts = lambda self, context: ()
    try:
        single = fit(meas, EFFECTS)
    finally:
        fx.DahlFriction.other_starts = second
    return profile, seed, both.rmse_rad * ARCSEC, single.rmse_rad * ARCSEC


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profiles", default="one_rate,two_rates_equal,sine", help="zoo profiles, comma-separated")
    parser.add_argument("--seeds", type=int, default=12, help="seeds 0 .. N-1 of each profile")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    cases = list(itertools.product(args.profiles.split(","), range(args.seeds)))
    print(f"{'profile':18s} {'seed':>4s} {'both [arcsec]':>14s} {'single':>8s} {'ratio':>6s}")
    rows = []
    with ProcessPoolExecutor(args.workers) as pool:
        for profile, seed, both, single in pool.map(with_and_without, cases):
            print(f"{profile:18s} {seed:4d} {both:14.2f} {single:8.2f} {single / both:6.2f}", flush=True)
            rows.append({"profile": profile, "seed": seed, "rmse_arcsec": both, "single_start_rmse_arcsec": single})
    from hdsim.atomic import write_text_atomic

    out = Path(__file__).resolve().parent / "results" / "second_start_basin.json"
    write_text_atomic(out, json.dumps(rows, indent=1) + "\n")
    print(f"written: {out}")


if __name__ == "__main__":
    main()
