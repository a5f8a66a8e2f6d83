"""Friction and hysteresis laws. Memory is always an ODE state passed in and out."""

from __future__ import annotations

import math

import numpy as np


def smooth_coulomb(velocity, coulomb_torque, velocity_scale):
    """Coulomb friction smoothed by tanh: ``F_c tanh(v / v_s)``.

    Parameters
    ----------
    velocity : float or array
        Sliding velocity v [rad/s].
    coulomb_torque : float or array
        Coulomb level F_c [N·m].
    velocity_scale : float or array
        Smoothing velocity v_s [rad/s], > 0.

    Returns
    -------
    float or array
        Friction torque [N·m].
    """
    return coulomb_torque * np.tanh(velocity / velocity_scale)


def stribeck(velocity, coulomb_torque, static_torque, stribeck_velocity, viscous, velocity_scale):
    """Coulomb + Stribeck + viscous friction (Armstrong-Hélouvry, 1991).

    ``[F_c + (F_s − F_c) exp(−(v/v_St)²)] tanh(v/v_s) + b v``.

    Parameters
    ----------
    velocity : float or array
        Sliding velocity v [rad/s].
    coulomb_torque : float or array
        Coulomb level F_c [N·m].
    static_torque : float or array
        Breakaway level F_s [N·m].
    stribeck_velocity : float or array
        Stribeck velocity v_St [rad/s].
    viscous : float or array
        Viscous coefficient b [N·m·s/rad].
    velocity_scale : float or array
        Smoothing velocity v_s of the sign [rad/s], > 0.

    Returns
    -------
    float or array
        Friction torque [N·m].
    """
    level = coulomb_torque + (static_torque - coulomb_torque) * np.exp(-(velocity / stribeck_velocity) ** 2)
    return level * np.tanh(velocity / velocity_scale) + viscous * velocity


def dahl_slope(state, direction, stiffness, saturation):
    """Dahl model slope ``dz/dx = σ (1 − z/z_max · d)``, floored at 0 (Dahl, 1968).

    The floor only acts on a state pushed past saturation by round-off.

    Parameters
    ----------
    state : float or array
        Friction state z (a torque [N·m] or a twist [rad], see `dahl_rate`).
    direction : float or array
        Sign of the motion, ``d = sgn ẋ``, or a smooth stand-in for it in [−1, 1].
    stiffness : float or array
        Rest stiffness σ (units of z per unit of x).
    saturation : float or array
        Saturation level z_max (units of z).

    Returns
    -------
    float or array
        dz/dx (units of σ).
    """
    return stiffness * np.maximum(1.0 - state / saturation * direction, 0.0)


def dahl_rate(state, velocity, stiffness, saturation):
    """Dahl model rate ``ż = σ (1 − z/z_max · sgn v) v`` (Dahl, 1968).

    Used in torque form (z a torque, σ [N·m/rad]) and in compliance form (z a twist,
    σ = 1/k [rad/(N·m)] driven by a torque rate); the law is the same.

    Parameters
    ----------
    state : float or array
        Friction state z.
    velocity : float or array
        Rate of the driving variable v ([rad/s], or [N·m/s] in compliance form).
    stiffness : float or array
        Rest stiffness σ.
    saturation : float or array
        Saturation level z_max.

    Returns
    -------
    float or array
        ż (units of z per second).
    """
    return dahl_slope(state, np.sign(velocity), stiffness, saturation) * velocity


def dahl_slip_rates(slips, twist_rate, elastic_tangent, elastic_torque, slip_torques, slip_maxes,
                    stiffnesses, stop_width, velocity_scale):
    """Slip rates of Dahl-friction sliders with end stops, in series with the spring.

    Micro-slip of the teeth as ``n`` sliders in series (element axis first). Slider
    ``i`` sticks (stiffness σ_i) until the torque through it nears ``F_i``, then slides
    until it meets a stop at ``±s_max,i`` (stiffness k_i = σ_i). Its friction torque is
    what its stops do not carry, ``z_i = T − k_i·dz(s_i)``, and obeys Dahl's law
    (Dahl, 1968) in the slip: ``dz/ds = σ (1 − z/F sgn ṡ)`` (sgn smoothed as tanh over
    ``velocity_scale``, far below test twist rates). Its tangent stiffness is
    ``D_i = σ_i (1 − z_i/F_i sgn ṡ) + k_i·contact(s_i)``.

    Spring (tangent ``K_t``) and sliders carry the same torque, so compliances add:
    ``Ṫ = δ̇ / (1/K_t + Σ 1/D_j)`` and ``ṡ_i = Ṫ / D_i``. A freely sliding element
    (D_i → 0) takes the whole twist rate; in a backlash gap (K_t = 0) nothing slips.

    Parameters
    ----------
    slips : array
        Slip of each slider s_i, element axis first [rad].
    twist_rate : float or array
        Twist rate of the whole chain δ̇ [rad/s].
    elastic_tangent : float or array
        Tangent stiffness of the spring K_t [N·m/rad].
    elastic_torque : float or array
        Torque through the chain T [N·m].
    slip_torques : array
        Slip torque of each slider F_i [N·m].
    slip_maxes : array
        Stop position of each slider s_max,i [rad].
    stiffnesses : array
        Stick and stop stiffness of each slider σ_i = k_i [N·m/rad].
    stop_width : float or array
        Rounding width of the stops [rad].
    velocity_scale : float or array
        Smoothing velocity of the sign [rad/s].

    Returns
    -------
    numpy.ndarray
        Slip rate of each slider, element axis first [rad/s].
    """
    from hdsim.physics.backlash import smooth_contact, smooth_dead_zone

    # one slider of a single model comes as Python floats: `math` there, ten times numpy
    one = isinstance(slips, float)
    tanh, floor, total = (math.tanh, max, float) if one else (np.tanh, np.maximum, lambda c: np.sum(c, axis=0))
    stop_torque = stiffnesses * smooth_dead_zone(slips, slip_maxes, stop_width)
    friction_torque = elastic_torque - stop_torque
    direction = tanh(twist_rate / velocity_scale)
    stick = dahl_slope(friction_torque, direction, stiffnesses, slip_torques)
    D = stick + stiffnesses * smooth_contact(slips, slip_maxes, stop_width)
    # compliances, floored so a free slider is very compliant rather than infinitely so
    slider_compliance = 1.0 / floor(D, 1e-9 * stiffnesses)
    spring_compliance = 1.0 / floor(elastic_tangent, 1e-300)
    torque_rate = twist_rate / (spring_compliance + total(slider_compliance))
    return torque_rate * slider_compliance


def maxwell_slip_rates(deflections, velocity, stiffnesses, slip_torques, velocity_scale):
    """Maxwell-slip element deflection rates (Lampaert, Al-Bender & Swevers, 2003).

    Each element is a spring ``k_i`` in series with a slider ``f_i``: it sticks
    (``ż_i = v``) until ``k_i |z_i| = f_i`` and then slides (``ż_i = 0`` while pushed
    outward). The switch is smoothed over ``velocity_scale`` relative to the
    saturation to keep the right-hand side continuous.

    Parameters
    ----------
    deflections : array
        Spring deflection of each element z_i, element axis first [rad].
    velocity : float or array
        Twist rate v [rad/s].
    stiffnesses : array
        Spring stiffness of each element k_i [N·m/rad].
    slip_torques : array
        Slip torque of each element f_i [N·m].
    velocity_scale : float or array
        Smoothing velocity [rad/s].

    Returns
    -------
    numpy.ndarray
        Deflection rate of each element [rad/s].
    """
    load = stiffnesses * deflections / slip_torques
    outward = 0.5 * (1.0 + np.tanh(velocity / velocity_scale)) * np.clip(load, 0, None) \
        + 0.5 * (1.0 - np.tanh(velocity / velocity_scale)) * np.clip(-load, 0, None)
    gate = 1.0 - np.clip(outward, 0.0, 1.0) ** 8
    return gate * velocity


def maxwell_slip_torque(deflections, stiffnesses):
    """Total Maxwell-slip torque ``Σ k_i z_i``.

    Parameters
    ----------
    deflections : array
        Spring deflection of each element, element axis first [rad].
    stiffnesses : array
        Spring stiffness of each element [N·m/rad].

    Returns
    -------
    float or numpy.ndarray
        Torque [N·m].
    """
    return np.sum(stiffnesses * deflections, axis=0)


def relay_switch(torque, thresholds, half_widths):
    """A smoothed relay's switching curve and its slope in the torque (Mayergoyz, 1991).

    ``ρ(x) = x (3 − x²)/2`` for ``x = (T − c)/w`` in [−1, 1], −1 below and +1 above: the
    relay turns from −1 to +1 over ``c ± w`` with a continuous slope, and is exactly
    saturated outside that band.

    Parameters
    ----------
    torque : float or array
        Torque through the relay T [N·m].
    thresholds : float or array
        Switching torque c [N·m] (negative for the downward curve, ``−c``).
    half_widths : float or array
        Half-width of the switching band w [N·m], > 0.

    Returns
    -------
    tuple
        ``(ρ, dρ/dT [1/(N·m)])``.
    """
    x = np.clip((torque - thresholds) / half_widths, -1.0, 1.0)
    return 0.5 * x * (3.0 - x * x), 1.5 * (1.0 - x * x) / half_widths


def relay_slips_on_branch(slips, torque, direction, thresholds, half_widths, amplitudes):
    """Relay slips after the torque moves monotonically in ``direction`` from where the
    slips were to ``torque``, and their slopes in the torque.

    Relay ``i`` holds ``s_i`` until its switching curve passes it, then follows it: rising,
    ``s_i = max(s_i⁰, a_i ρ((T − c_i)/w_i))``; falling, ``min(s_i⁰, a_i ρ((T + c_i)/w_i))``.
    The rule wipes out smaller excursions and returns to a branch where it left it
    (return-point memory), as Preisach's relays do.

    Parameters
    ----------
    slips : array
        Relay slips s_i⁰ [rad], relay axis first.
    torque : float or array
        Torque at the end of the monotone move T [N·m].
    direction : float or array
        +1 rising, −1 falling.
    thresholds, half_widths : array
        Switching torques c_i > 0 and band half-widths w_i [N·m], relay axis first.
    amplitudes : array
        Slip range to each side a_i [rad].

    Returns
    -------
    tuple
        ``(slips [rad], dslip/dT [rad/(N·m)])``, relay axis first; the slope is zero for a
        relay that holds.
    """
    rho, slope = relay_switch(torque, direction * thresholds, half_widths)
    curve = amplitudes * rho
    moved = direction * (curve - slips) > 0.0
    return np.where(moved, curve, slips), np.where(moved, amplitudes * slope, 0.0)


def relay_slip_rates(slips, twist_rate, elastic_tangent, elastic_torque, thresholds, half_widths, amplitudes,
                     velocity_scale):
    """Slip rates of smoothed relays in series with the spring (the ODE form of
    `relay_slips_on_branch`).

    A relay on its switching curve in the direction of motion slips at ``g_i Ṫ`` with
    ``g_i = a_i ρ'``; one off its curve holds (the gate opens over 10⁻³ a_i as the curve
    reaches it). Spring and relays carry the same torque, so compliances add:
    ``Ṫ = δ̇ / (1/K_t + Σ g_j)``.

    Parameters
    ----------
    slips : array
        Relay slips s_i [rad], relay axis first.
    twist_rate : float or array
        Twist rate of the chain δ̇ [rad/s].
    elastic_tangent, elastic_torque : float or array
        Spring tangent K_t [N·m/rad] and the torque through the chain T [N·m].
    thresholds, half_widths, amplitudes : array
        As in `relay_slips_on_branch`.
    velocity_scale : float or array
        Smoothing velocity of the direction [rad/s].

    Returns
    -------
    numpy.ndarray
        Slip rate of each relay [rad/s], relay axis first.
    """
    rising = 0.5 * (1.0 + np.tanh(twist_rate / velocity_scale))
    tol = 1e-3 * amplitudes + 1e-300  # a relay of no range (the neutral law) holds
    g = 0.0
    for direction, share in ((1.0, rising), (-1.0, 1.0 - rising)):
        rho, slope = relay_switch(elastic_torque, direction * thresholds, half_widths)
        # open where the curve has reached the slip (rising: curve >= slip)
        gate = np.clip(direction * (amplitudes * rho - slips) / tol + 1.0, 0.0, 1.0)
        g = g + share * gate * amplitudes * slope
    spring_compliance = 1.0 / np.maximum(elastic_tangent, 1e-300)
    torque_rate = twist_rate / (spring_compliance + np.sum(g, axis=0))
    return torque_rate * g
