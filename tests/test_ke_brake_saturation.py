"""A kinematic-error record under a brake holds the brake's set torque for each pass: that
plateau is the load the test applies ("against a load that opposes the motion",
scenarios/kinematic_error.toml), not a clipped channel, and is not warned as saturation in
either sign convention of the file; a plateau the motion does not explain still is.
Hand-built records (docs/measurements.md, data checks)."""

from __future__ import annotations

import numpy as np
import pytest

from hdsim.identification.workflow import examine_record
from hdsim.io.measurement import make_measurement

RATIO, K, LOAD = 100.0, 3.0e4, 21.75  # CSG-25-100's 1/4 T_N


def _record(torque_of_direction, sign=1.0, rows=1600):
    """One output revolution forward and back at constant speed; the output lags by T/K."""
    half = rows // 2
    wg = 2 * np.pi * RATIO * np.r_[np.linspace(0.0, 1.0, half), np.linspace(1.0, 0.0, rows - half)]
    direction = np.sign(np.gradient(wg))
    torque = torque_of_direction(direction)
    noise = np.random.default_rng(0).normal(0.0, 2e-7, rows)
    out = wg / RATIO + torque / K + 3e-5 * np.sin(2 * wg) + noise
    return make_measurement("kinematic_error", np.linspace(0.0, 30.0, rows), sign * torque, out,
                            wg_angle=wg, ratio=RATIO, rated_torque=87.0)


def _checks(meas) -> dict:
    return {c["check"]: c for c in examine_record(meas, "CSG-25-100")[0]}


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["load_convention", "logged_the_other_way"])
def test_a_brake_holding_its_torque_is_not_saturation(sign):
    checks = _checks(_record(lambda direction: -LOAD * direction, sign))
    assert "saturation" not in checks
    assert checks["torque_sign"]["status"] == ("ok" if sign > 0 else "warn")  # the other way is turned first


def test_a_torque_that_sits_at_its_extreme_with_the_motion_is_still_warned():
    """The load pulls the output along on the return pass and the channel, noisy elsewhere,
    stays at one value: no brake explains the plateau, a clipped reading might."""
    wander = np.random.default_rng(1).normal(0.0, 0.05, 1600)
    checks = _checks(_record(lambda direction: np.where(direction > 0, -LOAD * np.linspace(0.5, 0.9, direction.size)
                                                        + wander, -LOAD)))
    assert checks["saturation"]["status"] == "warn" and "minimum -21.75" in checks["saturation"]["message"]


def test_a_set_load_logged_without_noise_is_no_clipped_channel():
    """hdsim's own run under a constant load (`measurement_from_run`) holds its set torque
    exactly, with the motion on one pass: a channel without noise repeats what it holds."""
    checks = _checks(_record(lambda direction: np.where(direction > 0, -LOAD * np.linspace(0.5, 0.9, direction.size),
                                                        -LOAD)))
    assert "saturation" not in checks
