"""Time-resolved Sobol' indices of the twist over the ±4 % lost-motion cycle.

Which parameter decides the twist *where* in the cycle: the flexspline walls set
the slope, the micro-slip and the backlash decide what happens around zero torque.

    python docs/make_resolved_figures.py        # writes docs/figures/sobol_resolved_lost_motion.png
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hdsim.sensitivity.scenario_outputs import series_function  # noqa: E402
from hdsim.model.catalog import load_unit  # noqa: E402
from hdsim.sensitivity.problem import uniform  # noqa: E402
from hdsim.sensitivity.resolved import resolved_indices  # noqa: E402

NAMES = ["flexspline.h_pz", "flexspline.h_c", "friction.slip_torque", "friction.slip_max", "backlash.gap"]
LABELS = ["h_pz", "h_c", "slip torque", "slip range", "backlash gap"]
RANGE = {"flexspline.h_pz": 0.1, "flexspline.h_c": 0.1, "friction.slip_torque": 0.3,
         "friction.slip_max": 0.3, "backlash.gap": 0.3}


def main():
    unit = load_unit()
    nominal = unit.params()
    bounds = {n: (nominal[n] * (1 - r), nominal[n] * (1 + r)) for n, r in RANGE.items()}
    problem = uniform(NAMES, [bounds[n] for n in NAMES])
    func = series_function(unit.name, NAMES, "twist_rad", "lost_motion")
    res = resolved_indices(func, problem, 256, seed=0)
    t = func.times()
    torque = func._scenario().torque_profile(unit.drive.rated_torque)(t)

    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7.5, 5.2), layout="constrained")
    top.plot(t, torque, color="k")
    top.set_ylabel("torque [N·m]")
    top.set_title("CSG-25-100, ±4 % T_N cycle: first-order index of the twist at each instant", fontsize=9)
    bottom.stackplot(t, np.clip(res["S1"], 0, None).T, labels=LABELS, alpha=0.85)
    bottom.set_ylabel("S1 of twist [-]")
    bottom.set_xlabel("time [s]")
    bottom.set_ylim(0, 1.05)
    bottom.legend(fontsize=8, ncol=5, loc="lower center", frameon=False)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    out = Path(__file__).resolve().parent / "figures" / "sobol_resolved_lost_motion.png"
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
