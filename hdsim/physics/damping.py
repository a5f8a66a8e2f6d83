"""Rate-dependent (viscous) loss laws."""

from __future__ import annotations


def load_dependent_coefficient(coefficient, stiffness_share, tangent_ratio):
    """Viscous coefficient ``c₀ [(1 − s) + s K_t/K₀]`` at tangent stiffness ``K_t``.

    Parameters
    ----------
    coefficient : float or array
        ``c₀``, the coefficient at zero twist [N·m·s/rad].
    stiffness_share : float or array
        ``s`` in [0, 1]: the share of ``c₀`` that is stiffness-proportional
        (Rayleigh damping, ``β K_t``; Rayleigh, *The Theory of Sound*, 1877, §97;
        Chopra, *Dynamics of Structures*, §11.4). ``s = 0`` is a constant coefficient.
    tangent_ratio : float or array
        ``K_t/K₀``, the tangent stiffness of the spring relative to its zero-twist value [-].

    Returns
    -------
    float or array
        Viscous coefficient [N·m·s/rad].
    """
    return coefficient * (1.0 - stiffness_share + stiffness_share * tangent_ratio)
