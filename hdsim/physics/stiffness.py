"""Torsional stiffness laws: twist ↔ torque of the drive's elastic path.

All functions are pure, vectorised and odd in their argument (the drive is taken
as symmetric: the catalog gives one curve and applies it to |T|).
"""

from __future__ import annotations

import numpy as np


def three_segment_twist(torque, T1, T2, K1, K2, K3):
    """Catalog three-segment law: twist [rad] at output torque ``torque`` [N·m].

    φ = T/K1 (|T| ≤ T1); T1/K1 + (|T|−T1)/K2 (T1 < |T| ≤ T2); and
    T1/K1 + (T2−T1)/K2 + (|T|−T2)/K3 beyond, with the sign of T restored.
    Harmonic Drive LLC CSF/CSG catalog p. 48; HD AG CSD-2A manual.
    Stiffnesses in [N·m/rad], torques in [N·m].
    """
    a = np.abs(torque)
    phi = (np.minimum(a, T1) / K1
           + np.clip(a - T1, 0.0, T2 - T1) / K2
           + np.maximum(a - T2, 0.0) / K3)
    return np.sign(torque) * phi


def three_segment_torque(twist, T1, T2, K1, K2, K3):
    """Inverse of `three_segment_twist`: torque [N·m] at twist [rad]."""
    a = np.abs(twist)
    phi1 = T1 / K1
    phi2 = phi1 + (T2 - T1) / K2
    torque = (K1 * np.minimum(a, phi1)
              + K2 * np.clip(a - phi1, 0.0, phi2 - phi1)
              + K3 * np.maximum(a - phi2, 0.0))
    return np.sign(twist) * torque


def _softplus(x, width):
    """Smooth ``max(x, 0)`` over ``width``: ``w·log(1 + exp(x/w))``, overflow-safe."""
    z = x / width
    return width * (np.maximum(z, 0.0) + np.log1p(np.exp(-np.abs(z))))


def _sigmoid(x, width):
    return 0.5 * (1.0 + np.tanh(0.5 * x / width))


def smooth_three_segment_torque(twist, T1, T2, K1, K2, K3, width):
    """Three-segment law with its two knees rounded over ``width`` [rad] (softplus).

    Away from the knees it equals `three_segment_torque` to within
    ``(K_{i+1}−K_i)·width·e^{-|φ−φ_i|/width}``. The rounding keeps the right-hand side
    differentiable, which an implicit solver needs to take long steps.
    """
    a = np.abs(twist)
    phi1 = T1 / K1
    phi2 = phi1 + (T2 - T1) / K2
    torque = K1 * a + (K2 - K1) * _softplus(a - phi1, width) + (K3 - K2) * _softplus(a - phi2, width)
    return np.sign(twist) * torque


def smooth_three_segment_tangent(twist, T1, T2, K1, K2, K3, width):
    """Tangent stiffness [N·m/rad] of `smooth_three_segment_torque`."""
    a = np.abs(twist)
    phi1 = T1 / K1
    phi2 = phi1 + (T2 - T1) / K2
    return K1 + (K2 - K1) * _sigmoid(a - phi1, width) + (K3 - K2) * _sigmoid(a - phi2, width)


def three_segment_tangent(twist, T1, T2, K1, K2, K3):
    """Tangent stiffness dT/dφ [N·m/rad] of the three-segment law at ``twist``."""
    a = np.abs(twist)
    phi1 = T1 / K1
    phi2 = phi1 + (T2 - T1) / K2
    return np.where(a <= phi1, K1, np.where(a <= phi2, K2, K3))


def tanh_hardening_torque(twist, K0, K_inf, twist_scale):
    """Smooth hardening: ``T = K∞ φ − (K∞ − K0) φ_s tanh(φ/φ_s)``.

    Tangent stiffness rises smoothly from ``K0`` at zero twist to ``K∞`` well beyond
    ``φ_s`` [rad]; a smooth alternative to the three-segment law.
    """
    return K_inf * twist - (K_inf - K0) * twist_scale * np.tanh(twist / twist_scale)


def tanh_hardening_tangent(twist, K0, K_inf, twist_scale):
    """Tangent stiffness [N·m/rad] of `tanh_hardening_torque`."""
    return K_inf - (K_inf - K0) / np.cosh(twist / twist_scale) ** 2


def fit_three_segment(torque, twist, T1, T2):
    """Least-squares fit of the three-segment law with a free twist offset.

    Fits ``φ = φ0 + a1 T + a2 (T−T1)₊ + a3 (T−T2)₊`` (continuous, knots at the
    catalog breakpoints) to samples of one loading branch with ``torque ≥ 0``.
    Returns ``(K1, K2, K3, φ0)`` with ``K1 = 1/a1``, ``K2 = 1/(a1+a2)``,
    ``K3 = 1/(a1+a2+a3)``. The free offset lets the fit ignore a backlash step
    or a hysteresis offset at the start of the branch. A segment with no samples
    (e.g. T_max ≤ T2) returns NaN for its stiffness.
    """
    T = np.asarray(torque, dtype=float)
    phi = np.asarray(twist, dtype=float)
    columns = [np.ones_like(T), T, np.maximum(T - T1, 0.0), np.maximum(T - T2, 0.0)]
    used = [c for c in columns if np.ptp(c) > 0 or c is columns[0]]
    coef = np.linalg.lstsq(np.column_stack(used), phi, rcond=None)[0]
    coef = np.concatenate([coef, np.full(4 - len(coef), np.nan)])
    phi0, a1, a2, a3 = coef
    return 1.0 / a1, 1.0 / (a1 + a2), 1.0 / (a1 + a2 + a3), phi0
