"""`auto` keeps the dynamic model where the micro-slip slider slides within the lost-motion cycle.

With the default unit's micro-slip friction (``dahl_slip``) given a slip torque below
the ±4 % test's peak (3.48 N·m), the quasi-static evaluator gave 0.843 arcmin of lost
motion where ``solve_ivp`` gives 1.62 (the slider's travel from stop to stop), or found
no torque balance, and ``auto`` chose it. The law now says so
(`Friction.locked_quasistatic_limit`) and the criterion reads it.
"""

from __future__ import annotations

import numpy as np

from hdsim.model.catalog import load_unit
from hdsim.scenarios.locked import quasistatic_criterion
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario

LOST_MOTION = load_scenario(builtin_scenario_path("lost_motion"))
DRIVE = load_unit("CSG-25-100")
PEAK = 0.04 * float(DRIVE.drive.rated_torque)


def test_a_slider_that_slides_within_the_cycle_keeps_the_dynamic_model():
    holds, reason, _ = quasistatic_criterion(DRIVE.with_updates({"friction.slip_torque": 0.6 * PEAK}), LOST_MOTION)
    assert not holds and "micro-slip friction slides" in reason


def test_a_slider_that_sticks_through_the_cycle_is_left_to_the_quasi_static_evaluator():
    assert float(DRIVE.params()["friction.slip_torque"]) > PEAK  # the default unit's: it sticks
    holds, reason, _ = quasistatic_criterion(DRIVE, LOST_MOTION)
    assert holds, reason
    assert DRIVE.friction.locked_quasistatic_limit(PEAK) is None


def test_one_sample_of_a_batch_that_slides_keeps_the_batch_dynamic():
    batch = DRIVE.with_updates({"friction.slip_torque": np.array([2.0, 1.5]) * PEAK})
    assert quasistatic_criterion(batch, LOST_MOTION)[0]
    batch = DRIVE.with_updates({"friction.slip_torque": np.array([2.0, 0.9]) * PEAK})
    assert not quasistatic_criterion(batch, LOST_MOTION)[0]


def test_a_study_whose_range_reaches_below_the_peak_keeps_the_dynamic_model():
    """The criterion had been judged on the nominal drive alone (5.22 N·m, which sticks), so a
    study of the slip torque over 1.5-6 N·m ran quasi-statically and found S1 = ST = 0 for it
    where solve_ivp gives nearly 1; it is judged at the ends of the ranges too."""
    from hdsim.sensitivity.models import from_unit

    func, *_ = from_unit("CSG-25-100", ["friction.slip_torque"], "lost_motion_arcmin",
                         bounds={"friction.slip_torque": (1.5, 6.0)})
    assert func.evaluator == "dynamic" and "friction.slip_torque = 1.5, an end of its range" in func.choice["reason"]
    func, *_ = from_unit("CSG-25-100", ["friction.slip_torque", "h_c"], "lost_motion_arcmin",
                         bounds={"friction.slip_torque": (4.0, 6.0)}, range_frac=0.1)
    assert func.evaluator == "quasistatic"
