"""Long records: keep every k-th row where the statistics allow it.

A bench logs at kilohertz what a stiffness or running-torque test changes over seconds: a
100 s torque cycle logged at 10 kHz is a million rows, two thousand times more than
the cycle's shape needs. Fitting every row costs time and memory in proportion, and it
changes the answer: the diagnosis's statistics (its information criterion with the
effective sample size, the hold-out folds, the whiteness test) read a record of a
million nearly identical neighbours differently from the same test logged at 200 Hz.

So a record longer than `MAX_ROWS` is thinned to every k-th row, ``k`` the largest
factor that both

- leaves at least `MAX_ROWS` rows, and
- leaves the noise of every logged signal as it is: `hdsim.signals.noise_level` (the rms
  about a local cubic through a few neighbours, estimated without a model) of the thinned
  signal is within `NOISE_TOLERANCE` of the full one's. Where the thinned samples are
  too far apart for the signal to be locally cubic (a ripple, a ringing, a fast
  reversal), its "noise" grows, and the factor is halved until it does not.

Thinning, not averaging: the noise on each kept row is the sensor's, so the noise floor,
the rms at the end of a diagnosis and every threshold read against them are the same
at 200 Hz, 2 kHz and 10 kHz. The rows left out carry nothing the test's shape needs; they
would narrow the fitted parameters' uncertainty, which the thinned record reports
honestly for what it uses.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from hdsim.io.data_checks import Check
from hdsim.signals import noise_level

#: a record with more rows than this is thinned (a diagnosis of 20,000 rows takes seconds)
MAX_ROWS = 20_000
#: the thinned signal's noise level may differ from the full one's by this share at most
NOISE_TOLERANCE = 0.1
#: ... or by this share of the signal's range, for a signal logged without noise
RESOLUTION = 1e-6


def thinning_factor(signals, max_rows: int = MAX_ROWS, tolerance: float = NOISE_TOLERANCE) -> int:
    """The largest factor k, from ``rows // max_rows`` down by halving, that keeps the noise.

    Parameters
    ----------
    signals : sequence of array_like
        The logged signals, one row per sample (time excluded).
    max_rows : int
        Rows the thinned record keeps at least.
    tolerance : float
        Largest relative change of a signal's noise level.

    Returns
    -------
    int
        1 for a record of at most ``max_rows`` rows, or when no factor keeps the noise.
    """
    arrays = [np.asarray(s, dtype=float) for s in signals if s is not None]
    n = arrays[0].size if arrays else 0
    k = n // max_rows
    while k > 1:
        if all(_keeps_noise(x, k, tolerance) for x in arrays):
            return k
        k //= 2
    return 1


def _keeps_noise(x: np.ndarray, k: int, tolerance: float) -> bool:
    full = noise_level(x)
    thinned = noise_level(x[::k])
    # a signal logged without noise (a commanded torque, a value printed to 9 digits) has
    # only its rounding as "noise": its thinned form may err by a millionth of its range,
    # below what any sensor resolves (a 20-bit encoder: a millionth of a turn)
    floor = RESOLUTION * float(np.ptp(x)) if x.size else 0.0
    return abs(thinned - full) <= tolerance * full + floor


def thin_record(meas, max_rows: int = MAX_ROWS):
    """``(record, checks)``: ``meas`` with every k-th row (`thinning_factor` over its torque,
    angles and temperature) and a check that says so, or ``meas`` itself and no check."""
    signals = [meas.torque, meas.angle, meas.wg_angle, meas.temperature]
    k = thinning_factor(signals, max_rows)
    if k == 1:
        return meas, []
    take = {name: (None if value is None else value[::k]) for name, value in
            (("time", meas.time), ("torque", meas.torque), ("angle", meas.angle), ("wg_angle", meas.wg_angle),
             ("temperature", meas.temperature))}
    thinned = dataclasses.replace(meas, **take)
    rate = (len(meas) - 1) / max(float(meas.time[-1] - meas.time[0]), 1e-300)
    return thinned, [Check("thinned", "ok", f"{len(meas)} rows logged at {rate:.4g} Hz: one row in {k} is used "
                                          f"({len(thinned)} rows, {rate / k:.4g} Hz); the noise of every signal "
                                          f"is the same at that rate, so the test's shape needs no more")]
