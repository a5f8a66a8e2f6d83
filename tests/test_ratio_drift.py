"""A kinematic-error record read with the wrong ratio is caught by the drift it leaves, which
no kinematic error has: N for N+1 (100 for 101) is 1 % of the slope but degrees of drift."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hdsim.identification.workflow import examine
from hdsim.io.data_checks import DriveScale
from hdsim.io.measurement import make_measurement
from hdsim.model.catalog import load_unit

DRIVE = DriveScale.of(load_unit("CSG-25-100"))
ARCMIN = math.radians(1.0 / 60.0)


def _record(ratio, output_turns=1.0):
    """One pass of ``output_turns`` output revolutions at ratio 100 with a kinematic error of a
    few arcmin (twice per WG turn and once per output turn) and a load reversing halfway."""
    t = np.linspace(0.0, 20.0, 4000)
    out_nominal = 2 * np.pi * output_turns * t / t[-1]
    wg = 100.0 * out_nominal
    torque = np.where(t < 10.0, 40.0, -40.0) + np.random.default_rng(0).normal(0.0, 0.3, t.size)
    ke = 1.5 * ARCMIN * np.sin(2 * wg) + 3.0 * ARCMIN * np.sin(out_nominal + 0.4) + torque / DRIVE.K_soft
    return make_measurement("kinematic_error", t, torque, 0.3 + out_nominal + ke, wg, ratio=ratio)


@pytest.mark.parametrize("turns", [0.25, 1.0, 3.0])
def test_a_genuine_record_passes(turns):
    checks, _, wrong = examine(_record(100.0, turns), DRIVE)
    assert wrong == "" and {c.check: c for c in checks}["ratio_consistent"].status == "ok"


@pytest.mark.parametrize("ratio", [101.0, 99.0, 100.2])
def test_a_ratio_a_little_off_is_named(ratio):
    _, _, wrong = examine(_record(ratio), DRIVE)
    assert f"the slope says 100, the file says {ratio:g}" in wrong


@pytest.mark.parametrize("ratio, wrong_test", [(100.0, False), (101.0, True)])
def test_a_load_that_ramps_with_the_angle_leaves_the_slope_to_the_angle(ratio, wrong_test):
    """A load growing with the output angle (0 → 40 N·m over the pass, a quiet sensor) is
    collinear with it: fitted beside it, the torque's column took up the slope, and a
    genuine record was called a wrong ratio (slope 0.976, 8.5°)."""
    t = np.linspace(0.0, 20.0, 4000)
    out_nominal = 2 * np.pi * t / t[-1]
    torque = 40.0 * t / t[-1]
    angle = out_nominal + torque / 31_000 + 2e-5 * np.sin(200 * out_nominal)
    angle = angle + np.random.default_rng(1).normal(0.0, 1e-6, t.size)
    record = make_measurement("kinematic_error", t, torque, angle, 100.0 * out_nominal, ratio=ratio)
    _, _, wrong = examine(record, DRIVE)
    assert bool(wrong) == wrong_test, wrong
