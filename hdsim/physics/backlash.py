"""Dead-zone backlash laws."""

from __future__ import annotations

import numpy as np

from hdsim.physics.elementary import tanh
from hdsim.physics.smooth import softplus


def dead_zone(twist, half_gap):
    """Dead zone of the seed paper, eq. (2): ``δ − b_s`` above ``b_s``, 0 inside, ``δ + b_s`` below.

    Parameters
    ----------
    twist : float or array
        Twist across the gap, δ [rad].
    half_gap : float or array
        Half the gap, b_s [rad].

    Returns
    -------
    float or array
        Twist carried by the contact [rad].
    """
    return np.where(twist > half_gap, twist - half_gap,
                    np.where(twist < -half_gap, twist + half_gap, 0.0))


def smooth_dead_zone(twist, half_gap, width):
    """`dead_zone` with its corners rounded over ``width`` (softplus).

    The rounding is a stiffening contact over ``width``, the way real flanks come
    into contact; it keeps the Jacobian continuous so the implicit solver does not
    chatter at contact.

    Parameters
    ----------
    twist : float or array
        Twist across the gap [rad].
    half_gap : float or array
        Half the gap [rad].
    width : float or array
        Rounding width [rad], > 0.

    Returns
    -------
    float or array
        Twist carried by the contact [rad].
    """
    return softplus(twist - half_gap, width) - softplus(-twist - half_gap, width)


def smooth_contact(twist, half_gap, width):
    """Slope of `smooth_dead_zone` with respect to the twist: 0 in the gap, 1 in contact.

    Parameters
    ----------
    twist : float or array
        Twist across the gap [rad].
    half_gap : float or array
        Half the gap [rad].
    width : float or array
        Rounding width [rad], > 0.

    Returns
    -------
    float or array
        d(smooth_dead_zone)/d(twist) [-].
    """
    return 1.0 + 0.5 * (tanh(0.5 * (twist - half_gap) / width) + tanh(0.5 * (-twist - half_gap) / width))


def elasto_backlash_torque(spring_torque, damping_torque):
    """Contact torque of a spring-damper behind a dead zone (Modelica ElastoBacklash).

    In contact the damping part never exceeds the spring part and the contact never
    pulls, so the torque is continuous (zero) at contact onset. The contact side is the
    sign of the spring torque. Modelica Standard Library,
    ``Mechanics.Rotational.Components.ElastoBacklash``.

    Parameters
    ----------
    spring_torque : float or array
        The spring law evaluated at the dead-zone twist, zero in the gap [N·m].
    damping_torque : float or array
        The viscous part ``d·ω`` [N·m].

    Returns
    -------
    float or array
        Contact torque [N·m].
    """
    pos = spring_torque + np.minimum(spring_torque, damping_torque)
    neg = spring_torque + np.maximum(spring_torque, damping_torque)
    pos = np.where(spring_torque + damping_torque < 0.0, 0.0, pos)
    neg = np.where(spring_torque + damping_torque > 0.0, 0.0, neg)
    return np.where(spring_torque > 0.0, pos, np.where(spring_torque < 0.0, neg, 0.0))


def smooth_elasto_backlash_torque(spring_torque, damping_torque):
    """ElastoBacklash's contact rule made smooth: ``τ_c + |τ_c| tanh(τ_d / |τ_c|)``.

    As in `elasto_backlash_torque` the damping part stays within ``±|τ_c|``, so
    the contact never pulls and the torque vanishes with the spring torque at contact
    onset; the hard ``min``/``max`` clip becomes a tanh so the Jacobian stays
    continuous and an implicit solver does not chatter at contact.

    Parameters
    ----------
    spring_torque : float or array
        The spring law evaluated at the dead-zone twist, τ_c [N·m].
    damping_torque : float or array
        The viscous part, τ_d [N·m].

    Returns
    -------
    float or array
        Contact torque [N·m].
    """
    limit = np.maximum(np.abs(spring_torque), 1e-300)
    return spring_torque + limit * np.tanh(damping_torque / limit)


def inverse_smooth_dead_zone(value, half_gap, width):
    """The twist ``y`` with ``smooth_dead_zone(y) = value``, in closed form.

    With ``a = exp(|y|/w)``, ``c = exp(−h/w)`` and ``D = exp(|value|/w)`` the softplus
    form reads ``D = a(1 + a c)/(a + c)``, a quadratic in ``a``:
    ``a = [(D − 1) + sqrt((D − 1)² + 4 c² D)]/(2c)`` (both terms positive: no
    cancellation). Beyond ``40·w`` of the gap the rounding is below ``1e-17·w`` and
    ``y = value ± h``.

    Parameters
    ----------
    value : float or array
        Twist carried by the contact [rad].
    half_gap : float or array
        Half the gap, h [rad].
    width : float or array
        Rounding width, w [rad], > 0.

    Returns
    -------
    numpy.ndarray
        Twist across the gap [rad].
    """
    value = np.asarray(value, dtype=float)
    half = np.broadcast_to(half_gap, value.shape)
    width = np.broadcast_to(width, value.shape)
    y = np.array(value + np.sign(value) * half, dtype=float)  # an array even for a scalar value
    near = np.abs(value) < 40.0 * width
    if np.any(near):
        v, h, w = value[near], half[near], width[near]
        c = np.exp(-h / w)
        d = np.exp(np.abs(v) / w)
        a = ((d - 1.0) + np.sqrt((d - 1.0) ** 2 + 4.0 * c * c * d)) / (2.0 * c)
        y[near] = np.sign(v) * w * np.log(a)
    return y


def _softplus_integral(x, width):
    """``∫_{-∞}^{x} sp(s; w) ds = −w² Li₂(−e^{x/w})`` [rad²], stable for any sign of x.

    For ``x > 0`` the inversion ``Li₂(−e^y) = −π²/6 − y²/2 − Li₂(−e^{−y})`` keeps the
    argument of the dilogarithm (``scipy.special.spence``) small.
    """
    from scipy.special import spence

    y = np.asarray(x, dtype=float) / width
    positive = width * width * (np.pi**2 / 6.0 + 0.5 * y * y + spence(1.0 + np.exp(-np.abs(y))))
    negative = -width * width * spence(1.0 + np.exp(np.minimum(y, 0.0)))
    return np.where(y > 0.0, positive, negative)


def smooth_dead_zone_integral(twist, half_gap, width):
    """``∫₀^δ smooth_dead_zone(s) ds`` [rad²] in closed form (dilogarithms of the softplus).

    With ``P`` the integral of the softplus, ``P(δ − h) + P(−δ − h) − 2 P(−h)``; the
    energy a contact of stiffness K stores through the rounded dead zone is K times this.
    """
    return (_softplus_integral(twist - half_gap, width) + _softplus_integral(-twist - half_gap, width)
            - 2.0 * _softplus_integral(-half_gap, width))
