"""A friction sweep as a servo logs it: one leg at a steady commanded speed whose measured
speed ripples with the torque ripple it fights (±15 % at 1× and ±5 % at 2× the WG angle),
torque estimated on the output, a rotor encoder, an idle leg after. The running torque has
one definition — the torque over whole WG turns, per unit of angle — and it is the same
number in the checks, the fit and the diagnosis, and the truth's level.

The log is written here from its physics (numpy only): the level ``L`` times the direction,
plus a ripple ``r1 cos(φ + 0.4) + r2 cos(2φ − 1.1)`` that reverses with it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hdsim import diagnose, fit
from hdsim.io.measurement import make_measurement

LEVEL, R1, R2, RATIO = 4.2, 1.5, 1.1, 50.0


def servo_log(seed=0, fs=200.0, noise=0.35):
    rng = np.random.default_rng(seed)
    w_run = 144.0 * 2 * math.pi / 60.0  # WG speed [rad/s]: 0.05 output rev/s at N = 50
    leg = math.radians(80.0) * RATIO / w_run  # the 0 -> 80° output leg [s]
    t = np.arange(0.0, 1.0 + 0.15 + leg + 0.15 + 20.0, 1.0 / fs)
    x = np.clip((t - 1.0) / 0.15, 0.0, 1.0)
    y = np.clip((t - 1.15 - leg) / 0.15, 0.0, 1.0)
    w = w_run * (0.5 * (1 - np.cos(math.pi * x)) - 0.5 * (1 - np.cos(math.pi * y)))
    phi = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))]) + 0.7
    steady = np.abs(w) > 0.5 * w_run
    phi = phi + (0.15 * np.sin(phi) + 0.05 * np.sin(2 * phi + 0.3)) * steady  # the servo's speed ripple
    moving = np.abs(w) > 1e-9
    torque = np.where(moving, LEVEL * np.tanh(w / 0.3) + (R1 * np.cos(phi + 0.4) + R2 * np.cos(2 * phi - 1.1)) *
                      np.tanh(w / 0.3), 0.0) + rng.normal(0.0, noise, t.size)
    rotor = np.round(phi / (2 * math.pi) * 2 ** 14) / 2 ** 14 * 2 * math.pi  # 14-bit rotor encoder
    return make_measurement("running_torque", t, torque, None, wg_angle=rotor, ratio=RATIO,
                            meta={"torque_side": "output"})


@pytest.fixture(scope="module")
def log():
    return servo_log()


def test_the_leg_is_one_plateau_of_whole_turns(log):
    result = fit(log)
    assert len(result.record.segments) == 1  # not fragments a fraction of a turn long
    assert result.running_torque_basis()["forward"].startswith("measured over 10 whole WG turn")


def test_one_running_torque_in_checks_fit_and_diagnosis(log):
    base = fit(log).metrics()["running_torque_forward_Nm"]
    result = diagnose(log, "friction")
    checks = {c["check"]: c for c in result.checks}
    assert f"{base:.4g} N·m forward" in checks["running_torque"]["message"]
    assert result.to_json()["metrics"]["running_torque_forward_Nm"] == base
    # the truth's level within the noise over ten turns, though a time average would keep part of
    # the ripple (the servo runs slower where the ripple holds it back)
    assert base == pytest.approx(LEVEL, rel=0.02)
    told_only_friction = result.added
    assert told_only_friction[:1] == ["ripple"]
    # one direction: the checks say what it cannot tell
    assert "not seen" in checks["torque_opposes_motion"]["message"]
    assert checks["reversals"]["status"] == "warn"
