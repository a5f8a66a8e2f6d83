"""Where the model fails: residual views, whiteness, and plain sentences that point at it.

Residual ``r = measured − model`` (angle, [rad]) after a fit. The views (figures of
docs/tutorial-find-missing-effect.md) and what each one shows:

| view | signature → candidate |
|---|---|
| r vs torque, coloured by loading direction | loop → friction/damping; step at T = 0 → backlash; slope changing with abs(T) → hardening |
| r vs time | drift, creep, a bad segment |
| r vs wave-generator angle, order spectrum | 1×, 2×, 4× WG, 1× output → kinematic error |
| r vs loading rate | loop width growing with rate → damping |

Whiteness: the Ljung–Box statistic ``Q = N(N+2) Σ_{k≤h} ρ_k²/(N−k)`` (χ² with ``h``
degrees of freedom for a white residual; Ljung & Box, Biometrika 65 (1978) 297–303)
and the noise floor ``σ_n``: the white part of the residual, estimated as the record's
noise is (`hdsim.signals.noise_level`: the residual minus its local cubic over seven
rows, whose median absolute value is robust to the few rows where the model's kinks make
the residual jump; Savitzky & Golay, Anal. Chem. 36 (1964) 1627). The residual's, not the
record's: it holds every white noise the model passes on (a measured torque's, through
the compliance). A residual counts as *explained* when it is white or when its rms is
within 25 % of the noise floor (the structure left is below ~75 % of the noise rms);
otherwise the model still misses something, whatever was added.
"""

from __future__ import annotations

import math

import numpy as np
# the χ² tail from scipy.special: scipy.stats would add 0.8 s to every `hdsim diagnose`
from scipy.special import chdtrc

from hdsim.signals import leg_loading, loading_direction, noise_level, rate_groups
from hdsim.units import ARCMIN_PER_RAD, ARCSEC_PER_RAD

__all__ = ["ljung_box", "noise_floor", "whiteness", "views", "findings", "order_spectrum",
           "EXPLAINED_RATIO"]

#: rms / noise-floor below which the residual counts as explained
EXPLAINED_RATIO = 1.25


def ljung_box(r, lags: int = 20) -> tuple[float, float]:
    """Ljung–Box test of ``r`` for autocorrelation up to ``lags``.

    Parameters
    ----------
    r : array_like
        Residual (any unit).
    lags : int
        Number of lags h.

    Returns
    -------
    tuple of float
        ``(Q, p)``: the statistic and its p-value against χ² with ``lags`` degrees of
        freedom; ``(0.0, 1.0)`` for a constant or too short residual.
    """
    r = np.asarray(r, dtype=float)
    r = r - r.mean()
    n = r.size
    den = float(r @ r)
    if den <= 0 or n <= lags + 1:
        return 0.0, 1.0
    acf = np.array([float(r[k:] @ r[:-k]) / den for k in range(1, lags + 1)])
    q = n * (n + 2) * float(np.sum(acf**2 / (n - np.arange(1, lags + 1))))
    return q, float(chdtrc(lags, q))  # χ²(lags) survival function


def noise_floor(r) -> float:
    """Rms of the white part of ``r`` (`hdsim.signals.noise_level`).

    Not ``std(diff(r))/√2``: a model's kinks (a friction's reversal, a gap's edge) make the
    residual jump on a few rows, and the standard deviation of the differences counts those
    jumps as noise. On the truth zoo's tuning seeds it read up to 3.2× the generator's noise
    (1.7× at the 90th percentile) and so called residuals at twice the noise explained;
    the local cubic's median reads at most 1.35× (docs/tutorial-find-missing-effect.md, "Explained").

    Parameters
    ----------
    r : array_like
        Residual (any unit).

    Returns
    -------
    float
        Noise floor, in the unit of ``r``; 0 for fewer than `hdsim.signals.NOISE_WINDOW`
        samples.
    """
    return noise_level(r)


def whiteness(r, lags: int = 20) -> dict:
    """Ljung–Box, noise floor and the verdict for a residual.

    Parameters
    ----------
    r : array_like
        Residual [rad].
    lags : int
        Number of lags of the Ljung–Box test.

    Returns
    -------
    dict
        ``ljung_box_q``, ``lags``, ``p_value``, ``white`` (p > 0.01),
        ``noise_floor_rad`` [rad], ``rmse_rad`` [rad], ``rms_over_noise`` [-],
        ``structured_fraction`` [-] and ``explained`` (white, or rms within
        `EXPLAINED_RATIO` of the noise floor).
    """
    r = np.asarray(r, dtype=float)
    q, p = ljung_box(r, lags)
    floor = noise_floor(r)
    rms = float(np.sqrt(np.mean((r - r.mean()) ** 2)))
    ratio = rms / floor if floor > 0 else math.inf
    structured = max(0.0, 1.0 - (floor / rms) ** 2) if rms > 0 else 0.0
    white = p > 0.01
    return {"ljung_box_q": q, "lags": lags, "p_value": p, "white": bool(white),
            "noise_floor_rad": floor, "rmse_rad": rms, "rms_over_noise": ratio,
            "structured_fraction": structured,
            "explained": bool(white or ratio <= EXPLAINED_RATIO)}


def order_spectrum(angle, r, max_order: float = 8.0, n_orders: int = 800):
    """Amplitude of ``r`` at orders of ``angle`` (least-squares sine fit per order).

    Works for any sampling of the angle (uneven, reversing): the amplitude at order ``k``
    is that of the best fit ``a sin(kθ) + b cos(kθ)``.

    Parameters
    ----------
    angle : array_like
        Angle θ the orders refer to [rad], e.g. the wave-generator angle.
    r : array_like
        Residual [rad].
    max_order : float
        Highest order [-].
    n_orders : int
        Number of orders, evenly spaced from ``max_order / n_orders`` to ``max_order``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(orders, amplitude)``: orders [-] and amplitudes [rad].
    """
    angle = np.asarray(angle, dtype=float)
    r = np.asarray(r, dtype=float) - np.mean(r)
    orders = np.linspace(max_order / n_orders, max_order, n_orders)
    return orders, np.array([math.hypot(*_sine_fit(angle, r, k)) for k in orders])


def _sine_fit(angle, r, k):
    """``(a, b)`` of the least-squares fit ``a sin(kθ) + b cos(kθ)`` of ``r``."""
    return np.linalg.lstsq(np.column_stack([np.sin(k * angle), np.cos(k * angle)]), r, rcond=None)[0]


def views(meas, residual) -> dict:
    """The arrays behind the figures: residual vs torque/direction, time, rate, WG angle.

    Parameters
    ----------
    meas : hdsim.io.measurement.Measurement
        The measurement the residual belongs to.
    residual : array_like
        Residual [rad], one value per row of ``meas``.

    Returns
    -------
    dict of str to numpy.ndarray
        ``time`` [s], ``torque`` [N·m], ``residual`` [rad], ``direction`` (sign of the
        smoothed dT/dt), ``rate`` (its magnitude [N·m/s]) and, for a kinematic-error test,
        ``wg_angle`` [rad].
    """
    direction, rate = loading_direction(meas.time, meas.torque)
    out = {"time": np.asarray(meas.time), "torque": np.asarray(meas.torque),
           "residual": np.asarray(residual), "direction": direction, "rate": rate}
    if meas.wg_driven:
        out["wg_angle"] = np.asarray(meas.wg_angle)
    return out


def _band_mean(mask, r):
    return float(np.mean(r[mask])) if np.count_nonzero(mask) >= 3 else float("nan")


def _loop_width(rows, direction, r):
    """Mean residual of the unloading rows of ``rows`` less that of their loading rows."""
    return _band_mean(rows & (direction < 0), r) - _band_mean(rows & (direction > 0), r)


def findings(meas, residual, max_items: int = 5, floor: float | None = None) -> list[str]:
    """Plain sentences that say where the model misses, largest first.

    Parameters
    ----------
    meas : hdsim.io.measurement.Measurement
        The measurement the residual belongs to.
    residual : array_like
        Residual [rad], one value per row of ``meas``.
    max_items : int
        Most findings after the opening sentence.
    floor : float, optional
        The noise floor to read the residual against [rad]; default the residual's own
        (`noise_floor`).

    Returns
    -------
    list of str
        The rms against the noise floor first, then each finding larger than twice the
        noise floor and a tenth of the rms (backlash step, hysteresis loop, rate
        dependence, hardening, kinematic-error orders).
    """
    r = np.asarray(residual, dtype=float)
    T = np.asarray(meas.torque, dtype=float)
    direction, leg_rate = leg_loading(meas.time, T)
    Tmax = max(float(np.max(np.abs(T))), 1e-12)
    rms = float(np.sqrt(np.mean(r * r)))
    out: list[tuple[float, str]] = []
    # the page's one noise floor when the caller gives it (a diagnosis: its final model's),
    # so that the baseline's and the final model's findings are read against one number
    floor = noise_floor(r) if floor is None else float(floor)

    def arcmin(x):
        return f"{abs(x) * ARCMIN_PER_RAD:.2f} arcmin"

    def arcsec(x):
        return f"{abs(x) * ARCSEC_PER_RAD:.1f} arcsec"

    # zero crossing: step of the residual between just below and just above zero torque
    near = np.abs(T) < 0.08 * Tmax
    step = _band_mean(near & (T > 0), r) - _band_mean(near & (T < 0), r)
    if np.isfinite(step):
        out.append((abs(step), f"the model misses {arcsec(step)} ({arcmin(step)}) where the torque "
                               f"crosses zero: a step in the residual there points at backlash"))
    # branches
    gap = _loop_width(np.abs(T) < 0.5 * Tmax, direction, r)
    if np.isfinite(gap):
        out.append((abs(gap), f"loading and unloading branches of the residual differ by "
                              f"{arcsec(gap)}: a hysteresis loop the model does not have "
                              f"(friction, or damping if it grows with the loading rate)"))
    # rate dependence of the loop: the rows of legs loaded faster and slower than midway
    # (geometric) between the record's slowest and fastest loading rates, when it has two or
    # more (`hdsim.signals.rate_groups`). Not the rows' median: when most rows load slowly it
    # is the slow rate itself, and a fast leg's turning points would count as slow rows.
    groups = rate_groups(leg_rate)
    if len(groups) >= 2:
        split = math.sqrt(groups[0] * groups[-1])
        fast, slow = leg_rate > split, (leg_rate > 0) & (leg_rate < split)
        if np.count_nonzero(fast) > 10 and np.count_nonzero(slow) > 10:
            diff = _loop_width(fast, direction, r) - _loop_width(slow, direction, r)
            if np.isfinite(diff):
                out.append((abs(diff), f"the residual loop is {arcsec(diff)} "
                                       f"{'wider' if diff > 0 else 'narrower'} at the fast loading "
                                       f"rate than at the slow one: rate-dependent loss (damping)"))
    # curvature with |T|
    hi = np.abs(T) > 0.7 * Tmax
    mid = (np.abs(T) > 0.3 * Tmax) & (np.abs(T) < 0.6 * Tmax)
    curve = _band_mean(hi, r * np.sign(T)) - _band_mean(mid, r * np.sign(T))
    if np.isfinite(curve):
        out.append((abs(curve), f"towards rated torque the residual bends by {arcsec(curve)} "
                                f"({'the drive is stiffer' if curve < 0 else 'the drive is softer'} "
                                f"than the model at high load): stiffness changing with load "
                                f"(hardening)"))
    if meas.wg_driven:
        ratio = float(meas.ratio)
        wg = np.asarray(meas.wg_angle, dtype=float)
        for k, label in ((1, "1× wave generator"), (2, "2× wave generator"),
                         (4, "4× wave generator"), (1.0 / ratio, "1× output")):
            amp = float(np.hypot(*_sine_fit(wg, r - r.mean(), k)))
            out.append((amp, f"the residual has {arcsec(amp)} at {label} order: periodic in the "
                             f"wave-generator angle (kinematic error)"))
    out.sort(key=lambda item: -item[0])
    sentences = [f"residual rms {arcsec(rms)} against a noise floor of {arcsec(floor)}"]
    threshold = max(2.0 * floor, 0.1 * rms)
    sentences += [text[0].upper() + text[1:] for size, text in out[:max_items] if size > threshold]
    return sentences
