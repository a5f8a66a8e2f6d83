"""hdsim's own simulations, read back as bench records, are diagnosed without an internal error.

On a nearly noise-free record the quasi-static evaluator's own error (~1e-6 rad with the
micro-slip friction) exceeds the noise: a candidate's structure then gives the model it
contains another cost than it was fitted at (a zero gap takes another path), and the
nested-fit check stopped the diagnosis as an internal error (exit 1). Such a candidate is
now not judged, with the reason.
"""

from __future__ import annotations

import hdsim
from hdsim.io.measurement import make_measurement


def test_a_noise_free_simulated_stiffness_test_is_diagnosed_and_says_what_it_could_not_judge(default_stiffness_run):
    # the default unit through solve_ivp, as `hdsim simulate` runs it, read back without noise and
    # with an encoder's offset (0.3 rad, as the tester's file had: the fits' paths depend on it)
    plain = hdsim.measurement_from_run(default_stiffness_run)
    record = make_measurement("stiffness", plain.time, plain.torque, plain.angle + 0.3,
                              rated_torque=plain.rated_torque)
    result = hdsim.diagnose(record)  # raised RuntimeError: "… above the … of the model it contains"
    # the default unit holds hardening, backlash, friction and damping: the diagnosis adds from
    # those families only, hardening (its largest effect on a ±T_N test) among them, and says so
    added = set(result.to_json()["added"])
    assert "hardening" in added and added <= {"hardening", "backlash", "friction", "damping"}
    assert result.outcome in ("found", "improved")
    reasons = [c.reason for step in result.steps for c in step.candidates]
    assert all(r for r in reasons)
    not_judged = [r for r in reasons if r.startswith("not judged")]
    assert not_judged  # the path that had raised is the one this record takes
    assert all("the evaluator's resolution on this record is coarser than its noise" in r for r in not_judged)
