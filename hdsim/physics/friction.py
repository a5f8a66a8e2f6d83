"""Friction and hysteresis laws. Memory is always an ODE state passed in and out."""

from __future__ import annotations

import numpy as np


def smooth_coulomb(velocity, coulomb_torque, velocity_scale):
    """Coulomb friction smoothed by tanh: ``F_c tanh(v / v_s)`` [N·m]."""
    return coulomb_torque * np.tanh(velocity / velocity_scale)


def stribeck(velocity, coulomb_torque, static_torque, stribeck_velocity, viscous, velocity_scale):
    """Coulomb + Stribeck + viscous friction [N·m] (Armstrong-Hélouvry, 1991)."""
    level = coulomb_torque + (static_torque - coulomb_torque) * np.exp(-(velocity / stribeck_velocity) ** 2)
    return level * np.tanh(velocity / velocity_scale) + viscous * velocity


def dahl_rate(state, velocity, stiffness, saturation):
    """Dahl model rate ``ż = σ (1 − z/z_max · sgn v) v`` (Dahl, 1968).

    Used in torque form (z a torque, σ [N·m/rad]) and in compliance form (z a twist,
    σ = 1/k [rad/(N·m)] driven by a torque rate); the law is the same.
    """
    return stiffness * (1.0 - state / saturation * np.sign(velocity)) * velocity


def dahl_slip_rate(slip, twist_rate, elastic_tangent, elastic_torque, slip_torque, slip_max,
                   stick_stiffness, stop_stiffness, stop_width, velocity_scale):
    """Slip rate [rad/s] of a Dahl-friction slider with end stops, in series with the spring.

    Micro-slip of the teeth: a slider that sticks (initial stiffness σ) until the
    torque through it nears ``slip_torque``, then slides until it meets a stop at
    ``±slip_max`` (stiffness ``k_stop``). Its friction torque is what the stops do
    not carry, ``z = T − k_stop·dz(s)``, and obeys Dahl's law (Dahl, 1968) in the slip
    ``s``: ``dz/ds = σ (1 − z/F sgn ṡ)`` (sgn smoothed as tanh over ``velocity_scale``
    [rad/s], far below test twist rates), so the slider's tangent stiffness is
    ``D = σ (1 − z/F sgn ṡ) + k_stop·contact(s)``. The spring (tangent ``K_t``) and the
    slider share the twist rate: ``ṡ = K_t δ̇ / (K_t + D)`` — all of it goes into
    the slider while it slides freely (D → 0), none in a backlash gap (K_t = 0).
    """
    from hdsim.physics.backlash import smooth_contact, smooth_dead_zone

    stop_torque = stop_stiffness * smooth_dead_zone(slip, slip_max, stop_width)
    friction_torque = elastic_torque - stop_torque
    direction = np.tanh(twist_rate / velocity_scale)
    stick = stick_stiffness * np.maximum(1.0 - friction_torque / slip_torque * direction, 0.0)
    D = stick + stop_stiffness * smooth_contact(slip, slip_max, stop_width)
    return elastic_tangent * twist_rate / (elastic_tangent + D + 1e-300)


def maxwell_slip_rates(deflections, velocity, stiffnesses, slip_torques, velocity_scale):
    """Maxwell-slip element deflection rates [rad/s] (Lampaert, Al-Bender & Swevers, 2003).

    Each element is a spring ``k_i`` in series with a slider ``f_i``: it sticks
    (``ż_i = v``) until ``k_i |z_i| = f_i`` and then slides (``ż_i = 0`` while pushed
    outward). The switch is smoothed over ``velocity_scale`` relative to the
    saturation to keep the right-hand side continuous. ``deflections`` has the
    element axis first.
    """
    load = stiffnesses * deflections / slip_torques
    outward = 0.5 * (1.0 + np.tanh(velocity / velocity_scale)) * np.clip(load, 0, None) \
        + 0.5 * (1.0 - np.tanh(velocity / velocity_scale)) * np.clip(-load, 0, None)
    gate = 1.0 - np.clip(outward, 0.0, 1.0) ** 8
    return gate * velocity


def maxwell_slip_torque(deflections, stiffnesses):
    """Total Maxwell-slip torque ``Σ k_i z_i`` [N·m]."""
    return np.sum(stiffnesses * deflections, axis=0)
