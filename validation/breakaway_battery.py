"""The breakaway battery: starting torque and the hidden family of a breakaway ramp.

    python validation/breakaway_battery.py [--seeds 10] [--first-seed 0] [--workers 2] [--out NAME]

Data come from ``tests/truth_breakaway.py`` (written from the file contract alone: its own
integrator, a stick/slip logic, a decay ``1/(1 + x^1.5)`` after breakaway that is not
hdsim's, ramps or staircases of torque, current noise and quantisation, encoder steps,
torque on the input or on the output shaft). Every case writes the contract's CSV,
reads it with ``load_measurement`` and runs ``hdsim.fit`` and ``hdsim.diagnose`` with no
family given. Per group the table gives how often the hidden family was added first,
both were added (two hidden), nothing was added (nothing hidden), how often a family not
hidden was added (spurious), and the worst error of the starting torque of either
direction against the truth. The issue's criteria: >= 90 % first pick, <= 5 % spurious,
starting torque within 10 %. A case that raises is a failed case (its text is kept).

Seeds 0-9 were used to build the kind (tuning); the frozen seeds 200-219 were run once, at
the end (validation/README.md).
"""

from __future__ import annotations

import sys
import tempfile
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))  # truth_breakaway lives with the tests
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from battery_common import added_rates, battery_main  # noqa: E402

GROUPS = {"nothing": (), "asymmetry": ("asymmetry",), "friction": ("friction",),
          "two:asymmetry+friction": ("asymmetry", "friction")}


def run_case(group: str, seed: int) -> dict:
    import hdsim
    import truth_breakaway as tb
    from hdsim.io.measurement import load_measurement

    side = "output" if seed % 3 == 2 else "input"  # a third of the logs on the output shaft
    cols, meta, truth = tb.make_breakaway_data(GROUPS[group], seed=seed, torque_side=side)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "breakaway.csv"
        tb.write_csv(path, cols, meta)
        meas = load_measurement(path)
    metrics = hdsim.fit(meas).metrics()
    result = hdsim.diagnose(meas)
    errors = []
    for way in ("forward", "reverse"):
        want, got = truth[f"starting_torque_{way}_Nm"], metrics[f"starting_torque_{way}_Nm"]
        if want is not None:
            errors.append(abs(got - want) / want if got is not None else 1.0)
    return {"group": group, "seed": seed, "shape": truth["shape"], "torque_side": side, "rows": len(meas),
            "added": list(result.added), "outcome": result.outcome, "starting_torque_error": max(errors)}


def failed_row(group: str, seed: int, exc: BaseException) -> dict:
    return {"group": group, "seed": seed, "added": None, "outcome": "error",
            "error": "".join(traceback.format_exception_only(type(exc), exc)).strip(), "starting_torque_error": 1.0}


def table(rows: list) -> dict:
    out = {}
    for group, hidden in GROUPS.items():
        mine = [r for r in rows if r["group"] == group]
        if not mine:
            continue
        out[group] = {**added_rates(mine, hidden),
                      "worst_starting_torque_error": max(r["starting_torque_error"] for r in mine)}
    return out


def main(argv=None) -> int:
    return battery_main(__doc__, GROUPS, run_case, failed_row, table, seeds=10, out="breakaway_battery.json",
                        label="breakaway battery", argv=argv)


if __name__ == "__main__":
    sys.exit(main())
