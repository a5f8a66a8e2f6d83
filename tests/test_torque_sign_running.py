"""A friction sweep or breakaway ramp logged with the other torque sign is negated, as a
twist test's is, with a ``torque_sign`` warning; where the sign cannot be told it is refused.

A free drive's friction opposes its motion, so the torque that turns it has the motion's sign
(docs/measurements.md, contract §3 and §7: running and starting torques are positive
magnitudes). The sweeps are the library's own law (`test_running_torque.law_record`), the
ramps the breakaway truth's (`truth_breakaway`).
"""

from __future__ import annotations

import numpy as np
import pytest

import truth_breakaway as tb
from hdsim import fit
from hdsim.errors import InputError
from hdsim.io.measurement import make_measurement
from hdsim.io.running_checks import sweep_torque_sign
from hdsim.identification.breakaway import breakaway_torque_sign
from hdsim.model.input_friction import InputFriction
from test_breakaway import _measurement
from test_running_torque import law_record

LAW = InputFriction(starting_torque=0.07, coulomb_torque=0.05, viscous=2e-4, stribeck_speed=8.0, velocity_scale=0.05)


def flipped(meas):
    return make_measurement(meas.test, meas.time, -np.asarray(meas.torque), None, wg_angle=meas.wg_angle,
                            ratio=meas.ratio, meta={"torque_side": meas.torque_side})


def test_a_sweep_logged_with_the_other_sign_is_negated_and_its_running_torque_is_a_magnitude():
    # it had been fitted with a Coulomb level of 0 and a running torque of -0.08 N·m, exit 0
    meas = law_record(LAW, noise=1e-3, speeds=(20.0, 100.0), dwell_turns=4.0)
    turned, checks = sweep_torque_sign(flipped(meas))
    assert [c.check for c in checks] == ["torque_sign"] and checks[0].status == "warn"
    assert np.array_equal(turned.torque, meas.torque)
    assert sweep_torque_sign(meas)[1] == []  # the contract's sign: left as it is
    one_way = law_record(LAW, noise=1e-3, speeds=(20.0, 100.0), dwell_turns=4.0, signs=(1.0,))
    assert "grows with speed" in sweep_torque_sign(flipped(one_way))[1][0].message
    result = fit(flipped(meas))
    metrics = result.metrics()
    assert metrics["running_torque_forward_Nm"] > 0 and metrics["running_torque_reverse_Nm"] > 0


def test_a_one_way_one_speed_sweep_against_its_motion_is_refused():
    meas = law_record(LAW, noise=1e-3, speeds=(30.0,), dwell_turns=4.0, signs=(1.0,))
    with pytest.raises(InputError, match="one direction at one speed"):
        sweep_torque_sign(flipped(meas))


def test_a_breakaway_logged_with_the_other_sign_gives_positive_starting_torques():
    cols, meta, truth = tb.make_breakaway_data(("asymmetry",), seed=3)
    meas = _measurement({**cols, "torque_Nm": -cols["torque_Nm"]}, meta)
    _, checks = breakaway_torque_sign(meas)
    assert [c.check for c in checks] == ["torque_sign"]
    metrics = fit(meas).metrics()
    for way in ("forward", "reverse"):
        assert metrics[f"starting_torque_{way}_Nm"] == pytest.approx(truth[f"starting_torque_{way}_Nm"], rel=0.1)


def test_a_sweep_against_its_motion_one_way_only_carries_a_load_and_is_left_as_it_is():
    """A load larger than the friction, the same way throughout, puts the torque against the
    motion in one direction only; on a sweep with more plateaus that way it had made up the
    share of plateaus against the motion and was negated as "always against it"."""
    meas = law_record(LAW, speeds=(20.0, 60.0, 100.0), dwell_turns=4.0, signs=(1.0, 1.0, 1.0, -1.0))
    loaded = make_measurement(meas.test, meas.time, np.asarray(meas.torque) - 0.2, None, wg_angle=meas.wg_angle,
                              ratio=meas.ratio, meta={"torque_side": meas.torque_side})
    turned, checks = sweep_torque_sign(loaded)
    assert checks == [] and turned is loaded
