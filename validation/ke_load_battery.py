"""The kinematic-error-under-load battery: is the twist under a measured load identified?

    python validation/ke_load_battery.py [--seeds 5] [--first-seed 0] [--workers 2] [--only windup] [--out NAME]

Data come from ``tests/truth.py`` (``make_ke_data``: a body ODE of its own, a von-Mises
2x kinematic-error bump, encoder steps and noise), under three load profiles: ``sine``
(a load that does not follow the motion, ±50 % about its mean), ``ramp`` (a load ramping
one way across zero), ``opposing`` (the load flips with the motion) and ``windup`` (a
constant load whose transmitted torque steps by ±10-30 % with the direction: the friction
of an output bearing the torque sensor sees), each logged in
the contract's sign (``+``) and in the other (``-``: the torque the drive delivers).
Every case runs ``hdsim.diagnose`` with no family given. Per group: how often the
kinematic error was added first, how often something else was added (spurious), the
worst stiffness error against the truth's K1 and the worst final rms over the model-free noise floor.
The issue's criteria: >= 90 % first pick, <= 5 % spurious.

Seeds 0-2 were used while building the torque-sign rule (tuning); the frozen seeds
300-309 were run once, at the end (validation/README.md).
"""

from __future__ import annotations

import sys
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from battery_common import added_rates, battery_main  # noqa: E402

GROUPS = {f"{profile}{sign}": (profile, 1.0 if sign == "+" else -1.0)
          for profile in ("sine", "ramp", "opposing", "windup") for sign in "+-"}


def run_case(group: str, seed: int) -> dict:
    import hdsim
    import truth
    from hdsim.io.measurement import make_measurement

    profile, sign = GROUPS[group]
    cols, tr = truth.make_ke_data(hidden=("kinematic_error",), seed=seed, load_profile=profile, n_rows=6000)
    meas = make_measurement("kinematic_error", cols["time_s"], sign * cols["torque_Nm"], cols["output_angle_rad"],
                            wg_angle=cols["wg_angle_rad"], ratio=100, rated_torque=87.0)
    result = hdsim.diagnose(meas)
    stiffness = result.final.fit.summary()["derived"]["K0_Nm_per_rad"]
    return {"group": group, "seed": seed, "added": list(result.added), "outcome": result.outcome,
            "stiffness_error": abs(stiffness / tr["params"]["k1"] - 1.0),
            "rms_over_noise": result.whiteness["rms_over_noise"]}


def failed_row(group: str, seed: int, exc: BaseException) -> dict:
    return {"group": group, "seed": seed, "added": None, "outcome": "error", "stiffness_error": 1.0,
            "rms_over_noise": float("inf"),
            "error": "".join(traceback.format_exception_only(type(exc), exc)).strip()}


def table(rows: list) -> dict:
    out = {}
    for group in GROUPS:
        mine = [r for r in rows if r["group"] == group]
        if mine:
            rates = added_rates(mine, {"kinematic_error"})
            out[group] = {**{k: rates[k] for k in ("runs", "errors", "first_pick", "spurious")},
                          "worst_stiffness_error": max(r["stiffness_error"] for r in mine),
                          "worst_rms_over_noise": max(r["rms_over_noise"] for r in mine)}
    return out


def main(argv=None) -> int:
    return battery_main(__doc__, GROUPS, run_case, failed_row, table, seeds=5, out="ke_load_battery.json",
                        label="KE under load", argv=argv)


if __name__ == "__main__":
    sys.exit(main())
