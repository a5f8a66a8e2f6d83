"""Failures that used to pass silently now raise a clear error, or are reported.

Each test names the silent behaviour it guards against; each fails on the code that
had it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from hdsim.errors import InputError, SolverError
from hdsim.identification.diagnosis import diagnose
from hdsim.identification.fit import fit
from hdsim.io.measurement import make_measurement
from hdsim.model import effects as fx
from hdsim.model.catalog import load_unit
from hdsim.model.parameters import param
from hdsim.scenarios.locked import breakpoints
from hdsim.scenarios.scenario import Scenario
from hdsim.simulation.quasistatic import locked_twist
from hdsim.simulation.solver import SolverOptions

UNIT = load_unit()
K0 = float(UNIT.base_stiffness)


def _ramp(n=200):
    t = np.linspace(0.0, 2.0, n)
    return t, 40.0 * np.sin(np.pi * t)


def test_unsolved_torque_balance_raises_instead_of_returning_the_last_iterate():
    model = UNIT.with_effects(hardening=fx.TanhHardening(e_inf=20.0, T_s=2.0),
                              friction=fx.DahlFriction(torque_max=5.0, sigma=50 * K0))
    t, T = _ramp()
    with pytest.raises(SolverError, match="not solved"):
        locked_twist(model, t, T, max_iter=1, x_tol=0.0)
    x = locked_twist(model, t, T, max_iter=1, x_tol=0.0, on_failure="nan")
    assert np.isnan(x).any()


def test_time_axis_that_is_not_increasing_is_refused_not_turned_into_nan():
    with pytest.raises(InputError, match="strictly increasing"):
        locked_twist(UNIT, [0.0, 1.0, 1.0, 2.0], [0.0, 1.0, 2.0, 3.0])


def test_centre_line_lost_motion_below_four_percent_is_refused_not_dropped():
    data = {"name": "small", "setup": "locked_wave_generator", "metrics": ["lost_motion_centre_line"],
            "load": {"amplitude": 0.04, "cycles": 1, "rate": 0.04}}
    with pytest.raises(InputError, match="above 0.04"):
        Scenario(data, "small.toml")


def test_stiffness_metrics_follow_a_changed_breakpoint():
    changed = UNIT.with_updates({"hardening.T1": 20.0})
    assert breakpoints(changed)[0] == 20.0
    assert breakpoints(UNIT)[0] == UNIT.provenance["catalog"]["T1"]


def test_constant_torque_record_is_refused():
    t = np.linspace(0.0, 1.0, 50)
    meas = make_measurement("stiffness", t, np.zeros_like(t), 1e-5 * np.sin(t))
    with pytest.raises(InputError, match="never changes"):
        fit(meas)


def test_fit_reports_whether_it_converged():
    t, T = _ramp()
    meas = make_measurement("stiffness", t, T, T / K0)
    result = fit(meas)
    assert result.converged and result.message.startswith("converged")
    assert result.summary()["converged"] is True


def test_kinematic_error_beyond_its_bound_is_refused_not_clamped():
    t = np.linspace(0.0, 10.0, 2000)
    wg = 2.0 * np.pi * t
    out = wg / 100.0 + 0.05 * np.sin(2.0 * wg)  # 0.05 rad: 170 arcmin, not a kinematic error
    meas = make_measurement("kinematic_error", t, 5.0 + 0.0 * t + 0.1 * np.sin(t), out, wg_angle=wg, ratio=100)
    with pytest.raises(InputError, match="exceeds"):
        fit(meas, ["kinematic_error"])


def test_negative_load_gain_never_flips_the_kinematic_error():
    effect = fx.FourierKinematicError(a1=0.0, a2=1e-5, a4=0.0, p1=0.0, p2=0.0, p4=0.0, a_out=0.0,
                                      p_out=0.0, load_gain=-0.5)
    wg = np.pi / 4.0  # sin(2·wg) = 1
    assert effect.displacement(wg, 0.0, 1.0) == pytest.approx(0.5e-5)
    assert effect.displacement(wg, 0.0, 3.0) == 0.0  # 1 − 0.5·3 < 0: clipped at zero, not −0.5
    e, _, _, d_f = effect.displacement_and_partials(wg, 0.0, 3.0)
    assert e == 0.0 and d_f == 0.0


@pytest.mark.parametrize("updates, match", [
    ({"flexspline.h_c": "abc"}, "must be a number"),
    ({"friction.slip_torque": "x"}, "must be a number"),
    ({"flexspline.h_c": np.array([4e-4, 5e-4]), "flexspline.h_pz": np.array([5e-4, 6e-4, 7e-4])}, "lengths"),
    ({"flexspline.h_c": np.array([4e-4, 5e-4]), "friction.slip_torque": np.array([1.0, 2.0, 3.0])}, "lengths"),
])
def test_bad_parameter_values_are_named(updates, match):
    with pytest.raises(InputError, match=match):
        UNIT.with_updates(updates)


def test_explicit_solver_is_refused_with_the_reason():
    with pytest.raises(InputError, match="stiff"):
        SolverOptions(method="RK45")


@dataclass(frozen=True, eq=False)
class _NoStartFriction(fx.Friction):
    """A law that declares no placeholder values: a fit cannot start it from a family name."""

    id: ClassVar[str] = "no_start_test"
    level: float = param("level", "N·m", positive=True)


def test_candidate_that_cannot_be_fitted_is_rejected_with_its_reason():
    fx.register(_NoStartFriction)
    try:
        t, T = _ramp(300)
        meas = make_measurement("stiffness", t, T, T / K0 + 1e-7 * np.sin(37 * t))
        d = diagnose(meas, families=["friction", "backlash"], candidates={"friction": "no_start_test"},
                     max_rounds=1)
    finally:
        fx.unregister(_NoStartFriction)
    entry = next(c for c in d.to_json()["ranking"] if c["family"] == "friction")
    assert entry["passes"] is False and "could not be fitted" in entry["why"]
