"""Kinematic error under a measured load: the elastic twist T/K is identified from the
torque whatever the load's profile (varying, ramping, flipping with the motion) and
whatever sign convention the torque was logged in; a load that hardly varies is said not
to determine the stiffness.

Truth: ``tests/truth.py`` (``make_ke_data``, load profiles ``sine``, ``ramp``, ``opposing``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import truth
from hdsim import diagnose
from hdsim.io.data_checks import twist_slope
from hdsim.io.measurement import make_measurement


def _ke(cols, sign=1.0):
    return make_measurement("kinematic_error", cols["time_s"], sign * cols["torque_Nm"], cols["output_angle_rad"],
                            wg_angle=cols["wg_angle_rad"], ratio=100, rated_torque=87.0)


def test_the_twist_slope_of_a_hand_built_run_is_the_compliance():
    # y = T/K + KE orders 1, 2 and the output's + offset, exactly: the slope is 1/K to rounding
    t = np.linspace(0.0, 40.0, 8000)
    wg = 2 * math.pi * 5.0 * t
    torque = 20.0 * (1.0 + 0.5 * np.sin(2 * math.pi * t / 17.0))
    K = 3.1e4
    out = wg / 100 + torque / K + 3e-5 * np.sin(wg + 0.2) + 8e-5 * np.cos(2 * wg) + 5e-5 * np.sin(wg / 100) + 1e-3
    meas = make_measurement("kinematic_error", t, torque, out, wg_angle=wg, ratio=100)
    slope, t_stat = twist_slope(meas)
    assert slope == pytest.approx(1.0 / K, rel=1e-6)
    assert t_stat > 1e3


# one profile in the default run (the torque logged the other way, the case with a sign to
# find); the other two profiles behind -m slow, which validation/ke_load_battery.py extends
@pytest.mark.parametrize("profile, sign", [("sine", -1.0), pytest.param("ramp", 1.0, marks=pytest.mark.slow),
                                           pytest.param("opposing", -1.0, marks=pytest.mark.slow)])
def test_the_stiffness_under_load_is_identified_in_either_sign_convention(profile, sign):
    cols, tr = truth.make_ke_data(hidden=("kinematic_error",), seed=0, load_profile=profile, n_rows=2500)
    result = diagnose(_ke(cols, sign))
    assert result.added == ["kinematic_error"] and result.outcome == "found"
    stiffness = result.final.fit.summary()["derived"]["K0_Nm_per_rad"]
    assert stiffness == pytest.approx(tr["params"]["k1"], rel=0.05)
    # the diagnosis JSON carries the value beside its uncertainty, as `hdsim fit --json` does
    final = result.to_json()["final"]
    assert final["derived"]["K0_Nm_per_rad"] == stiffness
    assert "stiffness.K0" in final["fitted"] and "stiffness.K0" in final["uncertainty"]
    assert set(final["uncertainty"]) <= {*final["fitted"], *final["derived"], *final["params"], "offset_rad"}
    checks = {c["check"]: c for c in result.checks}
    assert checks["torque_sign"]["status"] == ("ok" if sign > 0 else "warn")
    # the rms falls to the measurement noise of the truth (0.55 arcsec rms, plus the encoder's steps)
    assert result.final.fit.rmse_rad < 1.5 * tr["measurement"]["noise_rad"]


def test_a_constant_load_in_one_direction_does_not_determine_the_stiffness():
    cols, _ = truth.make_ke_data(hidden=("kinematic_error",), seed=1, load_profile="sine", n_rows=2500)
    half = cols["time_s"].size // 2  # the forward pass only
    steady = {k: v[:half] for k, v in cols.items()}
    steady["torque_Nm"] = np.full(half, 20.0) + np.random.default_rng(0).normal(0.0, 0.05, half)
    result = diagnose(_ke(steady))
    checks = {c["check"]: c for c in result.checks}
    assert checks["twist_under_load"]["status"] == "warn"
    assert "not determined" in checks["twist_under_load"]["message"]
