"""Regenerate the running-torque figures of docs/tutorial-find-missing-effect.md and docs/physics.md.

Run from the repository root::

    python docs/make_running_figures.py

It writes ``docs/figures/friction_sweep_log.csv``: a motor drive's log of a friction sweep
(time, motor current, motor encoder in revolutions, one failed read), made by the
independent generator ``tests/truth_running.py`` with a Stribeck rise and a ripple hidden.
It reads it as the tutorial does, fits the base model and runs the diagnosis, and writes
``docs/figures/running_*.png`` and ``docs/figures/running_diagnosis.json``; then it
simulates ``scenarios/running_torque.toml`` on the default unit for the catalog figure.
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FIG = ROOT / "docs" / "figures"
#: motor torque constant of the made-up drive [N·m/A]
KT = 0.05


def write_log(path: Path) -> None:
    sys.path.insert(0, str(ROOT / "tests"))
    import truth_running

    cols, meta, _ = truth_running.make_running_data({"friction", "ripple"}, 11, max_rows=12000)
    current = cols["torque_Nm"] / KT
    rows = ["t,iq_A,motor_rev,fet_C"]
    temperature = cols.get("temperature_C", np.full(current.size, 31.5))
    for i, (t, iq, rev, temp) in enumerate(zip(cols["time_s"], current, cols["wg_angle_rad"] / (2 * np.pi),
                                                temperature)):
        cell = "NaN" if i == 4321 else f"{iq:.5f}"  # a failed read
        rows.append(f"{t:.6f},{cell},{rev:.7f},{temp:.2f}")
    path.write_text("\n".join(rows) + "\n")


def main() -> None:
    from hdsim import load_unit, run_scenario
    from hdsim.identification.running_diagnosis import diagnose_running
    from hdsim.identification.running_fit import fit_running
    from hdsim.identification.running_report import fit_figures
    from hdsim.io.data_checks import DriveScale
    from hdsim.io.measurement import load_measurement

    FIG.mkdir(parents=True, exist_ok=True)
    log = FIG / "friction_sweep_log.csv"
    write_log(log)
    meas = load_measurement(log, {"time_s": "t", "torque_Nm": f"{KT}*iq_A", "wg_angle_rev": "motor_rev",
                                  "temperature_C": "fet_C"},
                            test="running_torque", ratio=100, drop_nan=True)
    scale = DriveScale.of(load_unit())
    catalog = scale.running_torque
    base = fit_running(meas, [])
    fit_figures(base, FIG / "running_base", catalog)
    result = diagnose_running(meas, [])
    with tempfile.TemporaryDirectory() as tmp:
        result.report(tmp, scale=scale)
        for png in sorted(Path(tmp).glob("*.png")):
            shutil.copy(png, FIG / f"running_diagnosis_{png.name}")
    (FIG / "running_diagnosis.json").write_text(json.dumps(result.to_json(), indent=1, default=float) + "\n")
    run = run_scenario(load_unit(), "running_torque")
    (FIG / "running_torque_scenario.json").write_text(
        json.dumps({k: float(run.metric(k)) for k in run.metrics}, indent=1) + "\n")
    print("wrote", log.name, "and the running_* figures")


if __name__ == "__main__":
    main()
