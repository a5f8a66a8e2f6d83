"""Kinematic (transmission) error as a Fourier series in the wave-generator and output angles."""

from __future__ import annotations

import numpy as np


def fourier_kinematic_error(wg_angle, output_angle, wg_orders, wg_amplitudes, wg_phases,
                            out_orders, out_amplitudes, out_phases):
    """Kinematic error ``Σ a_k sin(k θ_WG + φ_k) + Σ b_j sin(j θ_out + ψ_j)``.

    Ghorbel, Gandhi & Alpeter, ASME J. Mech. Des. 123 (2001) 90–97: the 2× WG
    harmonic dominates, with 1× and 4×; the 1× output term is eccentricity.

    Parameters
    ----------
    wg_angle : float or array
        Wave-generator angle θ_WG [rad].
    output_angle : float or array
        Output angle θ_out [rad].
    wg_orders, wg_amplitudes, wg_phases : sequence of float
        Orders k [-], amplitudes a_k [rad] and phases φ_k [rad] of the wave-generator
        harmonics.
    out_orders, out_amplitudes, out_phases : sequence of float
        Orders j [-], amplitudes b_j [rad] and phases ψ_j [rad] of the output harmonics.

    Returns
    -------
    float or array
        Kinematic error [rad].
    """
    e = 0.0
    for k, a, p in zip(wg_orders, wg_amplitudes, wg_phases):
        e = e + a * np.sin(k * wg_angle + p)
    for j, b, q in zip(out_orders, out_amplitudes, out_phases):
        e = e + b * np.sin(j * output_angle + q)
    return e
