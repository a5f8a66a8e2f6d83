"""Torsional stiffness laws: twist ↔ torque of the drive's elastic path.

All functions are pure, vectorised and odd in their argument (the drive is taken
as symmetric: the catalog gives one curve and applies it to |T|).
"""

from __future__ import annotations

import numpy as np

from hdsim.physics.smooth import magnitude_and_sign, softplus, softplus_slope


def three_segment_twist(torque, T1, T2, K1, K2, K3):
    """Catalog three-segment law: twist at output torque ``torque``.

    φ = T/K1 (|T| ≤ T1); T1/K1 + (|T|−T1)/K2 (T1 < |T| ≤ T2); and
    T1/K1 + (T2−T1)/K2 + (|T|−T2)/K3 beyond, with the sign of T restored.
    Harmonic Drive LLC CSF/CSG catalog p. 48; HD AG CSD-2A manual.

    Parameters
    ----------
    torque : float or array
        Output torque T [N·m].
    T1, T2 : float or array
        Breakpoint torques [N·m].
    K1, K2, K3 : float or array
        Stiffness of the three segments [N·m/rad].

    Returns
    -------
    float or array
        Twist [rad].
    """
    a = np.abs(torque)
    phi = (np.minimum(a, T1) / K1
           + np.clip(a - T1, 0.0, T2 - T1) / K2
           + np.maximum(a - T2, 0.0) / K3)
    return np.sign(torque) * phi


def three_segment_torque(twist, T1, T2, K1, K2, K3):
    """Inverse of `three_segment_twist`: torque at a twist.

    Parameters
    ----------
    twist : float or array
        Twist [rad].
    T1, T2 : float or array
        Breakpoint torques [N·m].
    K1, K2, K3 : float or array
        Stiffness of the three segments [N·m/rad].

    Returns
    -------
    float or array
        Torque [N·m].
    """
    a = np.abs(twist)
    phi1 = T1 / K1
    phi2 = phi1 + (T2 - T1) / K2
    torque = (K1 * np.minimum(a, phi1)
              + K2 * np.clip(a - phi1, 0.0, phi2 - phi1)
              + K3 * np.maximum(a - phi2, 0.0))
    return np.sign(twist) * torque


def smooth_three_segment_torque(twist, T1, T2, K1, K2, K3, width):
    """Three-segment law with its two knees rounded over ``width`` (softplus).

    Away from the knees it equals `three_segment_torque` to within
    ``(K_{i+1}−K_i)·width·e^{-|φ−φ_i|/width}``. The rounding keeps the right-hand side
    differentiable, which an implicit solver needs to take long steps.

    Parameters
    ----------
    twist : float or array
        Twist [rad].
    T1, T2 : float or array
        Breakpoint torques [N·m].
    K1, K2, K3 : float or array
        Stiffness of the three segments [N·m/rad].
    width : float or array
        Rounding width of the knees [rad], > 0.

    Returns
    -------
    float or array
        Torque [N·m].
    """
    a, sign = magnitude_and_sign(twist)
    phi1 = T1 / K1
    phi2 = phi1 + (T2 - T1) / K2
    torque = K1 * a + (K2 - K1) * softplus(a - phi1, width) + (K3 - K2) * softplus(a - phi2, width)
    return sign * torque


def smooth_three_segment_tangent(twist, T1, T2, K1, K2, K3, width):
    """Tangent stiffness of `smooth_three_segment_torque`.

    Parameters
    ----------
    twist : float or array
        Twist [rad].
    T1, T2 : float or array
        Breakpoint torques [N·m].
    K1, K2, K3 : float or array
        Stiffness of the three segments [N·m/rad].
    width : float or array
        Rounding width of the knees [rad], > 0.

    Returns
    -------
    float or array
        dT/dφ [N·m/rad].
    """
    a, _ = magnitude_and_sign(twist)
    phi1 = T1 / K1
    phi2 = phi1 + (T2 - T1) / K2
    return K1 + (K2 - K1) * softplus_slope(a - phi1, width) + (K3 - K2) * softplus_slope(a - phi2, width)


def three_segment_tangent(twist, T1, T2, K1, K2, K3):
    """Tangent stiffness dT/dφ of the three-segment law.

    Parameters
    ----------
    twist : float or array
        Twist [rad].
    T1, T2 : float or array
        Breakpoint torques [N·m].
    K1, K2, K3 : float or array
        Stiffness of the three segments [N·m/rad].

    Returns
    -------
    float or array
        dT/dφ [N·m/rad].
    """
    a = np.abs(twist)
    phi1 = T1 / K1
    phi2 = phi1 + (T2 - T1) / K2
    return np.where(a <= phi1, K1, np.where(a <= phi2, K2, K3))


def tanh_hardening_torque(twist, K0, K_inf, twist_scale):
    """Smooth hardening: ``T = K∞ φ − (K∞ − K0) φ_s tanh(φ/φ_s)``.

    Tangent stiffness rises smoothly from ``K0`` at zero twist to ``K∞`` well beyond
    ``φ_s``; a smooth alternative to the three-segment law.

    Parameters
    ----------
    twist : float or array
        Twist φ [rad].
    K0 : float or array
        Stiffness at zero twist [N·m/rad].
    K_inf : float or array
        Stiffness at large twist K∞ [N·m/rad].
    twist_scale : float or array
        Twist over which the stiffness rises, φ_s [rad], > 0.

    Returns
    -------
    float or array
        Torque [N·m].
    """
    return K_inf * twist - (K_inf - K0) * twist_scale * np.tanh(twist / twist_scale)


def tanh_hardening_tangent(twist, K0, K_inf, twist_scale):
    """Tangent stiffness of `tanh_hardening_torque`.

    Parameters
    ----------
    twist : float or array
        Twist φ [rad].
    K0 : float or array
        Stiffness at zero twist [N·m/rad].
    K_inf : float or array
        Stiffness at large twist [N·m/rad].
    twist_scale : float or array
        Twist over which the stiffness rises [rad], > 0.

    Returns
    -------
    float or array
        dT/dφ [N·m/rad].
    """
    return K_inf - (K_inf - K0) / np.cosh(twist / twist_scale) ** 2


def fit_three_segment(torque, twist, T1, T2):
    """Least-squares fit of the three-segment law with a free twist offset.

    Fits ``φ = φ0 + a1 T + a2 (T−T1)₊ + a3 (T−T2)₊`` (continuous, knots at the
    catalog breakpoints) to samples of one loading branch, with ``K1 = 1/a1``,
    ``K2 = 1/(a1+a2)``, ``K3 = 1/(a1+a2+a3)``. The free offset lets the fit ignore a
    backlash step or a hysteresis offset at the start of the branch.

    Parameters
    ----------
    torque : array_like
        Torque of one loading branch, ``torque ≥ 0`` [N·m].
    twist : array_like
        Twist at those torques [rad].
    T1, T2 : float
        Catalog breakpoint torques [N·m].

    Returns
    -------
    tuple of float
        ``(K1, K2, K3, φ0)``: stiffnesses [N·m/rad] and twist offset [rad]. A segment
        with no samples (e.g. T_max ≤ T2) gives NaN for its stiffness.
    """
    T = np.asarray(torque, dtype=float)
    phi = np.asarray(twist, dtype=float)
    columns = [np.ones_like(T), T, np.maximum(T - T1, 0.0), np.maximum(T - T2, 0.0)]
    used = [c for c in columns if np.ptp(c) > 0 or c is columns[0]]
    coef = np.linalg.lstsq(np.column_stack(used), phi, rcond=None)[0]
    coef = np.concatenate([coef, np.full(4 - len(coef), np.nan)])
    phi0, a1, a2, a3 = coef
    return 1.0 / a1, 1.0 / (a1 + a2), 1.0 / (a1 + a2 + a3), phi0
