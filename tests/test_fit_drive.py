"""`hdsim.fit(...).drive` of a torque test (a friction sweep, a breakaway) is the drive the fit
was made for (``unit``), carrying what was fitted that a drive has a slot for (docs/cli.md,
``hdsim fit``; contract: the input friction is part of the drive).

Before, both started from the default unit CSG-25-100 whatever ``unit`` said, while the
plausibility checks of the same fit used the unit given.
"""

from __future__ import annotations

import pytest

import hdsim
import truth_breakaway as tb
from hdsim.model.input_friction import InputFriction
from test_breakaway import _measurement
from test_running_torque import law_record

LAW = InputFriction(starting_torque=0.05, coulomb_torque=0.03, viscous=1e-4, stribeck_speed=8.0)


def _sweep() -> object:
    """A friction sweep made with the library's law: 10 and 100 rad/s, each forward and back."""
    return law_record(LAW, inertia=3e-5, noise=1e-4, speeds=(10.0, 100.0), fs=300.0, dwell_turns=1.5)


def _breakaway(hidden=("asymmetry", "friction"), seed=1, **overrides):
    cols, meta, truth = tb.make_breakaway_data(hidden, seed=seed, **overrides)
    return _measurement(cols, meta), truth


@pytest.mark.parametrize("record", [_sweep, lambda: _breakaway()[0]], ids=["running_torque", "breakaway"])
def test_the_drive_of_a_torque_fit_is_the_unit_given(record):
    unit = hdsim.load_unit("CSG-14-100")
    result = hdsim.fit(record(), unit="CSG-14-100")
    drive = result.drive
    assert drive.name == "CSG-14-100"
    assert drive.base_stiffness == unit.base_stiffness and drive.drive.J_out == unit.drive.J_out
    # what a torque record cannot see stays the unit's: its mesh-loss coefficient
    assert drive.input_friction.load_coefficient == unit.input_friction.load_coefficient
    assert hdsim.fit(record(), unit=unit).drive.name == "CSG-14-100"  # a drive object as well as a name
    assert hdsim.fit(record()).drive.name == hdsim.load_unit().name  # and the default without one


def test_a_breakaway_drive_carries_the_fitted_viscous_asymmetry_and_inertia():
    meas, _ = _breakaway()
    result = hdsim.fit(meas, "friction,asymmetry")
    f, drive, unit = result.fitted, result.drive, hdsim.load_unit()
    law = drive.input_friction
    assert law.viscous == f["viscous"] != unit.input_friction.viscous
    # the law starts forward at the fitted level, reverse at the level plus the fitted excess
    forward, reverse = law.starting_torque + law.coulomb_asymmetry, law.starting_torque - law.coulomb_asymmetry
    assert (forward, reverse) == pytest.approx((f["level"], f["level"] + f["asymmetry.reverse_excess"]), rel=1e-12)
    assert law.coulomb_asymmetry != 0.0
    assert forward - (law.coulomb_torque + law.coulomb_asymmetry) == pytest.approx(f["friction.stribeck_drop"])
    # the drive's rigid inertia on the WG shaft (J_in + J_out/N²) is the fitted one
    rigid = drive.drive.J_in + drive.drive.J_out / drive.drive.ratio ** 2
    assert rigid == pytest.approx(f["inertia"], rel=1e-12) and drive.drive.J_in != unit.drive.J_in


def test_a_fitted_inertia_is_carried_only_where_it_is_the_inputs():
    sweep = hdsim.fit(_sweep(), "friction")
    rigid = sweep.drive.drive.J_in + sweep.drive.drive.J_out / sweep.drive.drive.ratio ** 2
    assert rigid == pytest.approx(sweep.inertia, rel=1e-12) and sweep.inertia == pytest.approx(3e-5, rel=0.05)
    # torque on the output shaft: the motor turned the output, so the inertia is not the input's
    meas, _ = _breakaway(torque_side="output")
    assert hdsim.fit(meas).drive.drive.J_in == hdsim.load_unit().drive.J_in
