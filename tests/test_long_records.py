"""Long records: a log is thinned to every k-th row where the noise of every signal allows,
so the diagnosis's answer and its rms at the noise do not depend on the sampling rate.

The record is one ±T_N cycle of a plain linear spring plus white angle noise (nothing is
missing from a linear model), logged at several rates; `benchmarks/bench_long_record.py`
runs the same at 1,000,000 and 10,000,000 rows.
"""

from __future__ import annotations

import numpy as np
import pytest

import hdsim
from hdsim.io.decimation import MAX_ROWS, thinning_factor
from hdsim.io.measurement import make_measurement
from hdsim.signals import noise_level

K, RATED, NOISE, DURATION = 31_000.0, 87.0, 2e-6, 40.0


def _spring(rows, seed=0):
    t = np.linspace(0.0, DURATION, rows)
    torque = RATED * np.sin(2 * np.pi * t / 20.0) * np.minimum(1.0, t / 5.0)
    angle = torque / K + np.random.default_rng(seed).normal(0.0, NOISE, rows)
    return t, torque, angle


def test_a_record_short_enough_is_kept_whole():
    t, torque, angle = _spring(MAX_ROWS)
    assert thinning_factor([torque, angle]) == 1


def test_a_long_log_is_thinned_to_about_max_rows_and_keeps_its_noise():
    t, torque, angle = _spring(16 * MAX_ROWS)
    k = thinning_factor([torque, angle])
    assert k == 16
    assert noise_level(angle[::k]) == pytest.approx(noise_level(angle), rel=0.1)


def test_a_ripple_the_thinned_rows_cannot_follow_keeps_the_rows_it_needs():
    # a 10 Hz ripple of 20 µrad on the angle, logged at 4 kHz: every 160th row (25 Hz) would
    # alias it; the factor stops where the thinned angle still follows it
    t, torque, angle = _spring(160_000)
    rippled = angle + 2e-5 * np.sin(2 * np.pi * 10.0 * t)
    assert thinning_factor([torque, angle]) == 8
    k = thinning_factor([torque, rippled], max_rows=1_000)
    assert 1 < k < 160
    assert noise_level(rippled[::k]) == pytest.approx(noise_level(rippled), rel=0.1)


@pytest.mark.parametrize("rows", [MAX_ROWS, 16 * MAX_ROWS])
def test_the_same_test_at_two_sampling_rates_gives_one_answer_at_the_noise(rows):
    t, torque, angle = _spring(rows)
    meas = make_measurement("stiffness", t, torque, angle)
    result = hdsim.diagnose(meas)
    assert result.outcome == "nothing_missing" and result.added == []
    rms = result.to_json()["final"]["rmse_rad"]
    assert rms == pytest.approx(NOISE, rel=0.05)
    assert result.data["rows"] <= 2 * MAX_ROWS
    thinned = [c for c in result.checks if c["check"] == "thinned"]
    assert bool(thinned) == (rows > MAX_ROWS)
    if thinned:
        assert result.data["logged_rows"] == rows and "one row in 16 is used" in thinned[0]["message"]
