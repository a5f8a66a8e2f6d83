"""Torsional compliance of the flexspline torque path from closed forms.

Every function is pure and vectorised and takes SI inputs; the compliances are
torsional [rad/(N·m)], the support stiffnesses radial [N/m]. The torque path from
the output flange to the teeth is a series chain, so compliances add (`series`; the
chain of a drive is `hdsim.model.drive.compliance_chain`).

References
----------
- Thin tube in torsion and annular plate in torsion: Roark's Formulas for Stress
  and Strain, 8th ed. (Young & Budynas), Table 10.1 and Table 11.2 case 16.
- Edge of a long cylindrical shell under a ring load: Timoshenko & Woinowsky-Krieger,
  Theory of Plates and Shells, 2nd ed., §114 (``w = Q / (2 β³ D)``).
- Beam with both ends fixed under a uniform load: Roark Table 8.1 case 2d; the
  effective span of the rim on the balls from a plane-stress finite-element model
  (`hdsim.physics.fe_rim`).
- The chain and why it is calibrated against the catalog stiffness: docs/physics.md,
  sections 3 and 4.
"""

from __future__ import annotations

import numpy as np

# Gauss-Legendre nodes on [0, 1] for the smooth fillet integrals: 24 points
# integrate these rational integrands to ~1e-12 relative, far below model error.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(24)
_GL_X = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W


def thin_tube(length, mean_radius, wall, G):
    """Thin-walled tube in torsion: ``L / (2 π G R³ t)``.

    Parameters
    ----------
    length : float or array
        Tube length [m].
    mean_radius : float or array
        Mid-wall radius [m].
    wall : float or array
        Wall thickness [m].
    G : float
        Shear modulus [Pa].

    Returns
    -------
    float or array
        Torsional compliance [rad/(N·m)].
    """
    return length / (2.0 * np.pi * G * mean_radius**3 * wall)


def annular_diaphragm(r_inner, r_outer, thickness, G):
    """Flat annular plate twisted between its edges: ``(1/r_i² − 1/r_o²) / (4 π G t)``.

    Parameters
    ----------
    r_inner : float or array
        Inner radius r_i [m].
    r_outer : float or array
        Outer radius r_o [m].
    thickness : float or array
        Plate thickness t [m].
    G : float
        Shear modulus [Pa].

    Returns
    -------
    float or array
        Torsional compliance [rad/(N·m)].
    """
    return (1.0 / r_inner**2 - 1.0 / r_outer**2) / (4.0 * np.pi * G * thickness)


def _integrate_unit(integrand):
    """∫₀¹ integrand(s) ds by Gauss-Legendre; ``integrand`` broadcasts over s."""
    s = _GL_X.reshape((-1,) + (1,) * 0)
    values = integrand(s[:, None])
    return np.tensordot(_GL_W, values, axes=(0, 0)).squeeze()


def toroidal_fillet(fillet_radius, cylinder_radius, wall, G):
    """Quarter-circle fillet joining a diaphragm to a cylinder, in torsion.

    The mid-surface is the arc of radius ``R_k`` tangent to both: centred at
    ``(r, z) = (R_c − R_k, R_k)``, from the diaphragm at ``(R_c − R_k, 0)`` to the cylinder
    at ``(R_c, R_k)``, so the element ``ds = R_k dα`` sits at radius
    ``r(α) = R_c − R_k (1 − sin α)``; each element is a short tube:
    ``dφ/T = ds / (2π G r³ t)``.

    Parameters
    ----------
    fillet_radius : float or array
        Fillet radius R_k [m].
    cylinder_radius : float or array
        Mid-wall radius of the cylinder R_c [m].
    wall : float or array
        Wall thickness t [m].
    G : float
        Shear modulus [Pa].

    Returns
    -------
    float or numpy.ndarray
        Torsional compliance [rad/(N·m)].
    """
    Rk, Rc, t = (np.asarray(a, dtype=float) for a in (fillet_radius, cylinder_radius, wall))

    def integrand(s):
        alpha = 0.5 * np.pi * s
        r = Rc - Rk * (1.0 - np.sin(alpha))
        return 0.5 * np.pi * Rk / (2.0 * np.pi * G * r**3 * t)

    return _integrate_unit(integrand)


def wall_transition(length, bore_radius, wall_start, wall_end, G):
    """Axial transition whose wall grows from ``wall_start`` to ``wall_end`` over ``length``.

    Models the lead radius R_v between the cylinder and the toothed rim: the wall
    follows a quarter-cosine blend (tangent to the cylinder, as a fillet is); the
    mid-wall radius is ``R_i + t/2``.

    Parameters
    ----------
    length : float or array
        Axial length of the transition [m].
    bore_radius : float or array
        Bore (inner) radius R_i [m].
    wall_start : float or array
        Wall thickness at the cylinder end [m].
    wall_end : float or array
        Wall thickness at the rim end [m].
    G : float
        Shear modulus [Pa].

    Returns
    -------
    float or numpy.ndarray
        Torsional compliance [rad/(N·m)].
    """
    L, Ri, t0, t1 = (np.asarray(a, dtype=float) for a in (length, bore_radius, wall_start, wall_end))

    def integrand(s):
        t = t0 + (t1 - t0) * (1.0 - np.cos(0.5 * np.pi * s))
        r = Ri + 0.5 * t
        return L / (2.0 * np.pi * G * r**3 * t)

    return _integrate_unit(integrand)


def shell_edge_radial_stiffness(radius, wall, E, nu, arc_length):
    """Radial stiffness of the open edge of a long cylinder over an arc.

    Timoshenko's ring-load solution ``w = Q/(2β³D)`` per unit circumference, with
    ``β⁴ = 3(1−ν²)/(R² h²)`` and ``D = E h³ / (12 (1−ν²))``, applied over ``arc_length``.

    Parameters
    ----------
    radius : float or array
        Mid-wall radius R [m].
    wall : float or array
        Wall thickness h [m].
    E : float
        Young's modulus [Pa].
    nu : float
        Poisson's ratio [-].
    arc_length : float or array
        Loaded arc of the edge [m].

    Returns
    -------
    float or array
        Radial stiffness [N/m].
    """
    D = E * wall**3 / (12.0 * (1.0 - nu**2))
    beta = (3.0 * (1.0 - nu**2) / (radius**2 * wall**2)) ** 0.25
    return 2.0 * beta**3 * D * arc_length


def rim_between_balls_stiffness(wall, face_width, E, nu, ball_pitch, support_width, arc_length):
    """Radial stiffness of the toothed rim resting on the wave-generator balls.

    Each span between two balls is a beam clamped at both ends (the rim is continuous
    over the balls) under the uniform load of the teeth, with bending and shear
    (Timoshenko) deflection. Its mean deflection is ``q L⁴/(720 E I) + q L²/(12 κ G b h)``
    (Roark Table 8.1 case 2d, uniform load, both ends fixed; shear term with κ = 5/6)
    and the ``a/p`` spans of one zone carry the load ``q a`` together:

        k = a / (L⁴/(720 E I) + L²/(12 κ G b h)),   I = b h³/12,   L = p − w_c + 0.8 h .

    The effective span ``L`` is the clear span between the support patches plus 0.4 h
    at each end, where a plane-stress finite-element model of the ring puts the
    effective clamp; with it the formula is within 4.5 % of that model for support
    patches from 5 % to 20 % of the pitch, and within 2.4 % for walls of ±10 % at the
    built-in support (docs/physics.md §3.7).

    Parameters
    ----------
    wall : float or array
        Rim thickness h [m].
    face_width : float or array
        Face width b [m].
    E : float
        Young's modulus [Pa].
    nu : float
        Poisson's ratio [-].
    ball_pitch : float or array
        Distance between neighbouring balls along the bore p [m].
    support_width : float or array
        Arc of the bore each ball holds through its race w_c [m].
    arc_length : float or array
        Engagement arc a [m].

    Returns
    -------
    float or array
        Radial stiffness per engagement zone [N/m].
    """
    inertia = face_width * wall**3 / 12.0
    shear_modulus = E / (2.0 * (1.0 + nu))
    span = ball_pitch - support_width + 0.8 * wall
    bending = span**4 / (720.0 * E * inertia)
    shear = span**2 / (12.0 * (5.0 / 6.0) * shear_modulus * face_width * wall)
    return arc_length / (bending + shear)


def mesh_zone(k_radial, pitch_radius, pressure_angle):
    """Torsional compliance of the mesh from the radial support of the teeth.

    Two engagement zones share the torque: ``F_t = T / (2 r_p)`` per zone. The flank
    force has the radial component ``F_t tan α``, which pushes the support in by
    ``u_r = F_t tan α / k_r``. The flanks stay in contact along their normal, so a radial
    retreat ``u_r`` frees a tangential motion ``u_r tan α``: the teeth advance by
    ``F_t tan²α / k_r`` and the output turns by that over ``r_p``, so
    ``C = tan²α / (2 k_r r_p²)``.

    Parameters
    ----------
    k_radial : float or array
        Radial stiffness of the tooth support per engagement zone, k_r [N/m].
    pitch_radius : float or array
        Pitch radius r_p [m].
    pressure_angle : float or array
        Pressure angle of the flanks α [rad].

    Returns
    -------
    float or array
        Torsional compliance [rad/(N·m)].
    """
    return np.tan(pressure_angle) ** 2 / (2.0 * k_radial * pitch_radius**2)


def series(*compliances):
    """Compliances in series add.

    Parameters
    ----------
    *compliances : float or array
        Compliances of the members [rad/(N·m)].

    Returns
    -------
    float or array
        Compliance of the chain [rad/(N·m)].
    """
    return sum(compliances)
