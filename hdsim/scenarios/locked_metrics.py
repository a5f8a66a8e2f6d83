"""Test metrics: pure functions over the time series of a locked-WG torque cycle.

Conventions (see docs/physics.md, "Test definitions"):

- **Lost motion, full span** (catalog, seed paper): twist at the last +A turning
  point minus twist at the last −A turning point, each reached while loading
  towards it; A = 4 % T_N.
- **Lost motion, centre line** (Spinea's convention): span of the mid-line of the
  ±T_N loop between ±A, with the loop's odd symmetry: ``2 (mid(0) − mid(−A))``.
- **Hysteresis loss**: twist difference between the two zero-torque crossings of a
  ±T_N loop (B and B′, HD LLC catalog p. 49).
- **K1, K2, K3**: three-segment law (knots at the unit's T1, T2) fitted with a free
  offset to the loading branch from zero torque to −T_N after the reversal at +T_N,
  mirrored; samples below T1/2 are left out: the backlash step and the micro-slip
  sit there, and they are what lost motion and hysteresis loss measure. A segment the
  cycle does not load into gives NaN for its K; a cycle that never reaches T1/2 is refused.
  **Torsion at rated** is the fitted law's twist at T_N; **at the tips**, half the span
  between the measured twists at ±T_N while loading towards them (NaN for a cycle short of T_N).

Every function takes arrays with a leading batch axis ``(M, nt)`` and returns ``(M,)``.
"""

from __future__ import annotations

import numpy as np

from hdsim.errors import InputError

from hdsim.physics.stiffness import fit_three_segment, three_segment_twist
from hdsim.units import rad_to_arcmin


def _segments(levels):
    return list(zip(levels[:-1], levels[1:]))


def _segment_slice(index, n):
    return slice(index * n, (index + 1) * n + 1)


def _last_segment(levels, start, end):
    """Index of the last ramp from level ``start`` to ``end`` (or None)."""
    found = [i for i, (a, b) in enumerate(_segments(levels)) if np.isclose(a, start) and np.isclose(b, end)]
    return found[-1] if found else None


def _interp_rows(x_rows, y_rows, x0, clamp: bool = False):
    """Per row, y at x = x0 (a scalar or one value per row) by linear interpolation
    (x monotonic along a ramp); beyond the ramp NaN, or its end value with ``clamp``."""
    x0 = np.broadcast_to(x0, (x_rows.shape[0],))
    out = np.empty(x_rows.shape[0])
    outside = None if clamp else np.nan
    for m, (x, y) in enumerate(zip(x_rows, y_rows)):
        order = np.argsort(x)
        out[m] = np.interp(x0[m], x[order], y[order], left=outside, right=outside)
    return out


def lost_motion_full_span(twist, levels, n):
    """Lost motion, full span: θ(+A) − θ(−A) at the last turning points of a cycle.

    Parameters
    ----------
    twist : numpy.ndarray, shape (M, nt)
        Twist [rad], ``n`` samples per ramp.
    levels : numpy.ndarray
        The cycle's torque levels (fractions of T_N).
    n : int
        Samples per ramp.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Lost motion [rad].
    """
    plus, minus = _last_turning_points(levels)
    return twist[:, plus * n] - twist[:, minus * n]


def _last_turning_points(levels) -> tuple[int, int]:
    """The indices of the cycle's last +A and last −A turning points in ``levels``."""
    amplitude = np.max(levels)
    plus = [k for k, level in enumerate(levels) if np.isclose(level, amplitude)]
    minus = [k for k, level in enumerate(levels) if np.isclose(level, -amplitude)]
    return plus[-1], minus[-1]


def _branches(torque, twist, levels, n):
    """(descending ramp +A→−A, following ascending ramp from −A) as (torque, twist) pairs."""
    amplitude = np.max(levels)
    down = _last_segment(levels, amplitude, -amplitude)
    if down is None or down + 1 >= len(levels) - 1:
        raise ValueError("the cycle needs a ramp +A → −A followed by a rising ramp")
    up = down + 1
    sd, su = _segment_slice(down, n), _segment_slice(up, n)
    return (torque[:, sd], twist[:, sd]), (torque[:, su], twist[:, su])


def hysteresis_loss(torque, twist, levels, n):
    """Hysteresis loss: twist difference at zero torque between unloading from +A and from −A.

    Parameters
    ----------
    torque, twist : numpy.ndarray, shape (M, nt)
        Output torque [N·m] and twist [rad], ``n`` samples per ramp.
    levels : numpy.ndarray
        The cycle's torque levels (fractions of T_N).
    n : int
        Samples per ramp.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Hysteresis loss [rad].
    """
    (td, pd), (tu, pu) = _branches(torque, twist, levels, n)
    return _interp_rows(td, pd, 0.0) - _interp_rows(tu, pu, 0.0)


def lost_motion_centre_line(torque, twist, levels, n, level_torque):
    """Lost motion, centre line: span of the loop mid-line between ±``level_torque`` (odd symmetry assumed).

    Parameters
    ----------
    torque, twist : numpy.ndarray, shape (M, nt)
        Output torque [N·m] and twist [rad], ``n`` samples per ramp.
    levels : numpy.ndarray
        The cycle's torque levels (fractions of T_N).
    n : int
        Samples per ramp.
    level_torque : float or numpy.ndarray
        The torque A of the span [N·m], per sample.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Lost motion [rad].
    """
    (td, pd), (tu, pu) = _branches(torque, twist, levels, n)
    level_torque = np.asarray(level_torque, dtype=float)
    mid0 = 0.5 * (_interp_rows(td, pd, 0.0) + _interp_rows(tu, pu, 0.0))
    mid_minus = 0.5 * (_interp_rows(td, pd, -level_torque) + _interp_rows(tu, pu, -level_torque))
    return 2.0 * (mid0 - mid_minus)


def reaches_rated(levels) -> bool:
    """Whether the cycle of ``levels`` (fractions of T_N) loads the drive to ±T_N."""
    return bool(np.max(levels) >= 1.0 - 1e-9)


def torsion_at_rated_tips(torque, twist, levels, n, rated_torque):
    """Half the span between the twists measured at +T_N and at −T_N, each on the last ramp
    loading towards that side's turning point.

    The catalog reads it at the tips of its ±T_N cycle, which this is at an amplitude of
    T_N. A cycle beyond T_N passes T_N on its way to the tip, where the twist is read. One
    short of T_N never loads the drive to it: the twist at rated torque is not measured and
    the result is NaN, not the tips' twist, a smaller figure that the name would pass off
    as the rated one (4.6 arcmin at ±0.6 T_N on CSG-25-100, 6.7 at ±T_N).

    Parameters
    ----------
    torque, twist : numpy.ndarray, shape (M, nt)
        Output torque [N·m] and twist [rad], ``n`` samples per ramp.
    levels : numpy.ndarray
        The cycle's torque levels (fractions of T_N).
    n : int
        Samples per ramp.
    rated_torque : float or numpy.ndarray
        T_N [N·m], per sample.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Torsion [rad]; NaN when the cycle's amplitude is below T_N.
    """
    M = torque.shape[0]
    if not reaches_rated(levels):
        return np.full(M, np.nan)
    TN = np.broadcast_to(np.asarray(rated_torque, dtype=float), (M,))
    # the ramp that ends on the last +A (−A) turning point: a cycle of 1 reaches +A only
    # from zero, on the virgin loading, as the catalog's test does
    plus, minus = _last_turning_points(levels)
    sp, sm = _segment_slice(plus - 1, n), _segment_slice(minus - 1, n)
    # np.interp holds the end value beyond the ramp: at an amplitude of exactly T_N the
    # tip's torque may round a hair below T_N, and the tip is then what is read
    at_plus = _interp_rows(torque[:, sp], twist[:, sp], TN, clamp=True)
    at_minus = _interp_rows(torque[:, sm], twist[:, sm], -TN, clamp=True)
    return 0.5 * (at_plus - at_minus)


def stiffness_fit_unreachable(amplitude, T1, T2, rated_torque) -> str:
    """Why a cycle to ±``amplitude`` T_N gives the three-segment fit no sample ('' when it
    gives some), with the amplitude that gives all three segments."""
    peak = amplitude * rated_torque
    if peak > 0.5 * T1:
        return ""
    return (f"the stiffness metrics fit the loading branch above T1/2 = {0.5 * T1:g} N·m, which a cycle to "
            f"±{amplitude:g} T_N ({peak:.4g} N·m) never reaches; K1, K2 and K3 need load.amplitude above "
            f"T2/T_N = {T2 / rated_torque:.3g} (T2 = {T2:g} N·m; the stiffness scenario loads to ±T_N)")


def stiffness_fit(torque, twist, levels, n, T1, T2, rated_torque):
    """Three-segment stiffness fitted to the loading branch to −A.

    Parameters
    ----------
    torque, twist : numpy.ndarray, shape (M, nt)
        Output torque [N·m] and twist [rad], ``n`` samples per ramp.
    levels : numpy.ndarray
        The cycle's torque levels (fractions of T_N).
    n : int
        Samples per ramp.
    T1, T2 : float or numpy.ndarray
        Breakpoints of the law [N·m], per sample.
    rated_torque : float or numpy.ndarray
        T_N [N·m], per sample.

    Returns
    -------
    numpy.ndarray, shape (4, M)
        K1, K2, K3 [N·m/rad] and the torsion at T_N [rad]. A segment the branch does not
        load into gives NaN for its K and for the torsion (a sample of a batch may stop
        short of its own T2 while the others reach theirs).

    Raises
    ------
    InputError
        If the branch of a sample never reaches T1/2, where the fit starts: there is
        nothing to fit (the ±4 % lost-motion cycle on any catalog unit).
    """
    (td, pd), _ = _branches(torque, twist, levels, n)
    M = torque.shape[0]
    T1, T2, TN = (np.broadcast_to(v, (M,)) for v in (T1, T2, rated_torque))
    out = np.empty((4, M))
    for m in range(M):
        load, phi = -td[m], -pd[m]
        reason = stiffness_fit_unreachable(float(np.max(levels)), T1[m], T2[m], TN[m])
        if reason:
            raise InputError(reason + (f" (sample {m} of the batch)" if M > 1 else ""))
        keep = load >= 0.5 * T1[m]
        K1, K2, K3, _ = fit_three_segment(load[keep], phi[keep], T1[m], T2[m])
        # the twist at T_N needs only the segments below T_N: one T_N does not reach (a
        # datasheet's T2 above its rated torque, as at a low ratio) is not read, not NaN
        K2_used = K2 if TN[m] > T1[m] else np.inf
        K3_used = K3 if TN[m] > T2[m] else np.inf
        out[:, m] = K1, K2, K3, three_segment_twist(TN[m], T1[m], T2[m], K1, K2_used, K3_used)
    return out


def locked_metrics(names, torque, twist, levels, n, T1, T2, rated_torque) -> dict:
    """The requested metric groups of a locked-WG run, in the units their names carry.

    Parameters
    ----------
    names : list of str
        Metric groups (`METRIC_GROUPS`).
    torque, twist : numpy.ndarray, shape (M, nt)
        Output torque [N·m] and twist [rad], sampled ``n`` per ramp.
    levels : numpy.ndarray
        The cycle's torque levels (fractions of T_N).
    n : int
        Samples per ramp.
    T1, T2 : float or numpy.ndarray
        Breakpoints of the three-segment fit [N·m] (``stiffness`` only).
    rated_torque : float or numpy.ndarray
        T_N [N·m].

    Returns
    -------
    dict
        ``{name: array of shape (M,)}``: arcmin for angles, N·m/rad for stiffnesses.
    """
    out: dict[str, np.ndarray] = {}
    amplitude = float(np.max(levels))
    for name in names:
        if name == "lost_motion":
            out["lost_motion_arcmin"] = rad_to_arcmin(lost_motion_full_span(twist, levels, n))
        elif name == "hysteresis_loss":
            out["hysteresis_loss_arcmin"] = rad_to_arcmin(hysteresis_loss(torque, twist, levels, n))
        elif name == "lost_motion_centre_line":
            if amplitude <= 0.04:  # the scenario check refuses this before any simulation
                raise InputError("lost_motion_centre_line needs a cycle beyond ±4 % T_N")
            level = 0.04 * np.asarray(rated_torque)
            out["lost_motion_centre_line_arcmin"] = rad_to_arcmin(
                lost_motion_centre_line(torque, twist, levels, n, level))
        elif name == "stiffness":
            K1, K2, K3, phi_rated = stiffness_fit(torque, twist, levels, n, T1, T2, rated_torque)
            # a segment no sample's cycle loads into is absent (one NaN figure made the command
            # refuse the run: `hdsim demo` on a ratio-30 drive file, whose T2 lies above T_N); a
            # batch whose samples differ keeps NaN where one sample stops short
            peak = amplitude * np.asarray(rated_torque, dtype=float)
            figures = {"K1_Nm_per_rad": K1, "K2_Nm_per_rad": K2 if np.any(np.asarray(T1) < peak) else None,
                       "K3_Nm_per_rad": K3 if np.any(np.asarray(T2) < peak) else None,
                       "torsion_at_rated_arcmin": rad_to_arcmin(phi_rated)}
            out.update({name: value for name, value in figures.items() if value is not None})
            if reaches_rated(levels):  # a cycle short of T_N has no twist at T_N to report: the figure is absent
                out["torsion_at_rated_tip_arcmin"] = rad_to_arcmin(
                    torsion_at_rated_tips(torque, twist, levels, n, rated_torque))
        else:
            raise ValueError(f"unknown metric group {name}")
    return out


METRIC_GROUPS = ("lost_motion", "hysteresis_loss", "lost_motion_centre_line", "stiffness")
