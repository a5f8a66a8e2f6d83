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
- Thin ring under two opposite point loads and a beam between supports:
  Roark Table 9.2 case 1 and Table 8.1 case 1e.
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

    The mid-surface runs from the diaphragm (radius ``R_c − R_k``) to the cylinder
    (radius ``R_c``) along an arc of radius ``R_k``; each element ``ds`` at radius
    ``r(α) = R_c − R_k cos α`` is a short tube: ``dφ/T = ds / (2π G r³ t)``.

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
        r = Rc - Rk * np.cos(alpha)
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


def rim_between_balls_stiffness(wall, face_width, E, ball_pitch, arc_length):
    """Radial stiffness of the toothed rim spanning the wave-generator balls.

    Each span between two balls is a simply supported beam with a central load,
    ``k = 48 E I / s³`` with ``I = b h³/12``; the spans inside one engagement arc
    act in parallel.

    Parameters
    ----------
    wall : float or array
        Rim thickness h [m].
    face_width : float or array
        Face width b [m].
    E : float
        Young's modulus [Pa].
    ball_pitch : float or array
        Distance between neighbouring balls s [m].
    arc_length : float or array
        Engagement arc [m].

    Returns
    -------
    float or array
        Radial stiffness [N/m].
    """
    inertia = face_width * wall**3 / 12.0
    spans = arc_length / ball_pitch
    return spans * 48.0 * E * inertia / ball_pitch**3


def mesh_zone(k_radial, pitch_radius):
    """Torsional compliance of the mesh from the radial support of the teeth.

    Two engagement zones share the torque: ``F_t = T / (2 r_p)`` per zone. The radial
    force component ``F_t tan α`` deflects the support by ``F_t tan α / k_r``, which lets
    the flanks slide tangentially by that amount divided by ``tan α``; the twist is
    ``F_t / (k_r r_p)`` and the pressure angle cancels: ``C = 1 / (2 k_r r_p²)``.

    Parameters
    ----------
    k_radial : float or array
        Radial stiffness of the tooth support per engagement zone, k_r [N/m].
    pitch_radius : float or array
        Pitch radius r_p [m].

    Returns
    -------
    float or array
        Torsional compliance [rad/(N·m)].
    """
    return 1.0 / (2.0 * k_radial * pitch_radius**2)


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
