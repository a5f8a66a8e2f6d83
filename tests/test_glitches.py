"""One-row glitches of a log (a failed read that wrote a number) are refused, or dropped with
--drop-nan, before anything is fitted; the drive's own sharp features are never taken for one.

A glitch of 1000 N·m in the torque of an 87 N·m stiffness test made the residual's noise
floor as large as its rms, and the diagnosis called the record explained (``found``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.io.measurement import load_measurement
from hdsim.signals import glitches

EXAMPLE = Path(__file__).parent / "data" / "stiffness_example.csv"


def _with_torque_cell(tmp_path, row: int, value: str) -> Path:
    lines = EXAMPLE.read_text().splitlines()
    cells = lines[3 + row].split(",")
    cells[1] = value
    lines[3 + row] = ",".join(cells)
    path = tmp_path / "spike.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_glitch_is_found_in_noise_and_nothing_else_is():
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 8.0, 4000)
    triangle = 87.0 * np.abs((t % 2.0) - 1.0)  # sharp corners every second, sampled on them
    noisy = triangle + rng.normal(0.0, 0.05, t.size)
    assert glitches(triangle).size == 0 and glitches(noisy).size == 0
    spiked = noisy.copy()
    spiked[1234] += 30.0
    assert glitches(spiked).tolist() == [1234]
    step = np.where(t < 4.0, 0.0, 1e-3) + rng.normal(0.0, 1e-7, t.size)  # a backlash jump
    assert glitches(step).size == 0
    counts = np.round(3.0 * np.sin(t)) + (np.arange(t.size) == 500)  # a coarse encoder, one count off once
    assert glitches(1e-6 * counts).size == 0
    assert glitches(rng.normal(0.0, 1.0, 200_000)).size == 0  # 20 σ: white noise never gets there


def test_a_glitch_next_to_a_nan_is_not_judged():
    x = np.linspace(0.0, 1.0, 50)
    x[20], x[21] = 50.0, np.nan
    assert glitches(x).size == 0


def test_a_log_with_a_glitch_is_refused_naming_its_line(tmp_path):
    path = _with_torque_cell(tmp_path, 5, "1e3")
    with pytest.raises(InputError, match=r"line 9, column 'torque_Nm': 1000\.0 jumps away from both neighbours"
                                         r".*drop_nan=True drops them"):
        load_measurement(path)


def test_drop_nan_drops_the_glitch_row_and_counts_it(tmp_path):
    clean = load_measurement(EXAMPLE)
    meas = load_measurement(_with_torque_cell(tmp_path, 5, "1e3"), drop_nan=True)
    assert len(meas) == len(clean) - 1 and meas.rows.dropped_rows == 1
    assert np.array_equal(meas.torque, np.delete(clean.torque, 5))



def test_the_dip_into_the_gap_at_a_reversal_is_no_glitch():
    """A twist falling steeply into the backlash gap as the torque nears zero, then caught on
    the other flank (a record of the truth zoo, rows around its reversal, in µrad): the row
    at the bottom is 128.8 from its neighbours' mean, 1.65 times their spread, and 20 times
    the noise; it is the drive, not a failed read."""
    rng = np.random.default_rng(0)
    around = np.array([359460.83, 359445.85, 359412.90, 359355.97, 359266.09, 359433.87, 359451.85,
                       359451.85, 359454.84])
    before = 359460.83 + np.cumsum(rng.normal(-4.0, 1.8, 40))[::-1] * -1.0
    after = 359454.84 + rng.normal(0.0, 1.8, 40)
    assert glitches(1e-6 * np.concatenate([before, around, after])).size == 0
