"""Regenerate the kinematic-error-under-load figure and numbers of docs/tutorial-find-missing-effect.md.

Run from the repository root::

    python docs/make_ke_load_figures.py

A kinematic-error run forward then back under a constant load whose transmitted torque
steps with the direction (the friction of an output bearing the torque sensor sees), made
by the independent generator ``tests/truth.py`` and logged with the torque the drive
delivers (the other sign from the contract's). It is diagnosed as it is; the figure shows
the kinematic error against time with the twist under load the fit identified, and
``docs/figures/ke_load.json`` holds the numbers the docs quote.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FIG = ROOT / "docs" / "figures"
ARCSEC = 180 * 3600 / np.pi


def main() -> None:
    import truth
    from matplotlib.figure import Figure

    import hdsim
    from hdsim.io.measurement import make_measurement

    FIG.mkdir(parents=True, exist_ok=True)
    cols, tr = truth.make_ke_data(hidden=("kinematic_error",), seed=2, load_profile="windup", n_rows=6000)
    meas = make_measurement("kinematic_error", cols["time_s"], -cols["torque_Nm"], cols["output_angle_rad"],
                            wg_angle=cols["wg_angle_rad"], ratio=100, rated_torque=87.0)
    result = hdsim.diagnose(meas)
    checks = {c["check"]: c for c in result.checks}
    stiffness = result.final.fit.summary()["derived"]["K0_Nm_per_rad"]
    fig = Figure(figsize=(9, 4.5))
    top, bottom = fig.subplots(2, 1, sharex=True)
    t = np.asarray(meas.time)
    top.plot(t, -np.asarray(meas.torque), lw=0.8, color="0.3")
    top.set(ylabel="load torque [N·m]", title="a kinematic-error run under a load that steps with the direction")
    ke = np.asarray(meas.kinematic_error)
    bottom.plot(t, (ke - np.mean(ke)) * ARCSEC, lw=0.5, color="0.6", label="measured kinematic error")
    twist = -np.asarray(meas.torque) / stiffness
    bottom.plot(t, (twist - np.mean(twist)) * ARCSEC, lw=1.2, color="C3", label="twist under load T/K (fitted K)")
    bottom.set(xlabel="time [s]", ylabel="angle [arcsec]")
    bottom.legend(fontsize=8)
    fig.savefig(FIG / "ke_load.png", dpi=110, bbox_inches="tight")
    numbers = {"outcome": result.outcome, "added": list(result.added),
               "torque_sign": checks["torque_sign"]["message"], "fitted_K_Nm_per_rad": stiffness,
               "truth_K1_Nm_per_rad": tr["params"]["k1"],
               "rms_over_noise": result.whiteness["rms_over_noise"],
               "baseline_rms_arcsec": result.to_json()["baseline"]["rmse_rad"] * ARCSEC,
               "final_rms_arcsec": result.to_json()["final"]["rmse_rad"] * ARCSEC}
    (FIG / "ke_load.json").write_text(json.dumps(numbers, indent=1) + "\n")
    print(json.dumps(numbers, indent=1))


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "tests"))
    main()
