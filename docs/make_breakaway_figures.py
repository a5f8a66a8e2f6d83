"""Regenerate the breakaway figures of docs/tutorial-find-missing-effect.md and docs/measurements.md.

Run from the repository root::

    python docs/make_breakaway_figures.py

It writes ``docs/figures/breakaway_log.csv``: a breakaway ramp made by the independent
generator ``tests/truth_breakaway.py`` (a Stribeck drop hidden, the reverse level 20-50 %
off the forward one, torque from motor current), reads it as the tutorial does, fits it,
runs the diagnosis and writes ``docs/figures/breakaway_record.png`` (torque and angle
against time with each start marked), ``docs/figures/breakaway_diagnosis.json`` and
``docs/figures/breakaway_fit.json`` (the numbers the docs quote).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FIG = ROOT / "docs" / "figures"


def main() -> None:
    import truth_breakaway as tb
    from matplotlib.figure import Figure

    import hdsim
    from hdsim.identification.breakaway import BreakawayRecord
    from hdsim.io.measurement import load_measurement

    FIG.mkdir(parents=True, exist_ok=True)
    cols, meta, truth = tb.make_breakaway_data(("friction", "asymmetry"), seed=1)
    log = FIG / "breakaway_log.csv"
    tb.write_csv(log, cols, meta)
    meas = load_measurement(log)
    fitted = hdsim.fit(meas)
    result = hdsim.diagnose(meas)
    rec = BreakawayRecord.of(meas)
    fig = Figure(figsize=(9, 5))
    top, bottom = fig.subplots(2, 1, sharex=True)
    t = np.asarray(meas.time)
    top.plot(t, meas.torque, lw=0.6, color="0.3", label="measured torque")
    for s in rec.starts:
        top.plot(t[s.onset], s.torque, "o", color="C3", ms=5)
    top.plot([], [], "o", color="C3", label="starting torque (each start)")
    top.set(ylabel="torque [N·m, input]", title="breakaway ramps: the torque at which the shaft left its rest")
    top.legend(fontsize=8)
    bottom.plot(t, np.degrees(meas.wg_angle), lw=0.8)
    bottom.set(xlabel="time [s]", ylabel="wave-generator angle [deg]")
    fig.savefig(FIG / "breakaway_record.png", dpi=110, bbox_inches="tight")
    (FIG / "breakaway_fit.json").write_text(json.dumps(
        {"metrics": fitted.metrics(), "truth": {k: truth[k] for k in ("starting_torque_forward_Nm",
                                                                   "starting_torque_reverse_Nm")}},
        indent=1) + "\n")
    (FIG / "breakaway_diagnosis.json").write_text(json.dumps(
        {k: v for k, v in result.to_json().items() if k in ("added", "outcome", "verdict", "table")},
        indent=1, default=float) + "\n")
    print("wrote", log.name, "breakaway_record.png and the JSON")


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "tests"))
    main()
