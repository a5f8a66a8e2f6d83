"""Finite-element torsional compliance of a cup-type flexspline on its (r, z) section.

A second opinion for the closed forms of `hdsim.physics.compliance`: the same torque
path (diaphragm, end-radius fillet, cylinder, lead radius, undercut) solved as a
body of revolution instead of a chain of thin shells.

Torsion of a body of revolution (Timoshenko & Goodier, Theory of Elasticity, 3rd ed.,
§§ 119-120, torsion of shafts of varying diameter) has the circumferential
displacement ``u_θ = r ψ(r, z)`` as its only displacement, with shear strains
``γ_rθ = r ∂ψ/∂r`` and ``γ_zθ = r ∂ψ/∂z``. The strain energy is
``U = π G ∫∫ r³ |∇ψ|² dr dz``, so ψ solves ``∫ r³ ∇ψ·∇v dA = 0`` with ψ = 0 on the
clamped face, ψ = 1 rad on the twisted face and free faces as the natural condition.
The torque for that unit twist is ``T = 2 U = 2π G ∫ r³ |∇ψ|² dA`` and the compliance
is ``C = 1/T``. The closed-form checks (tube ``C = L/(G J)``, annular plate
``C = (1/r_i² − 1/r_o²)/(4π G t)``) are Roark's Formulas for Stress and Strain, 8th ed.,
Table 10.1 and Table 11.2 case 16.

scikit-fem is an optional dependency: it is imported only when a solve is asked for.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from hdsim.errors import InputError, SolverError

# The weak form's integrand is (P1 gradient)² · r³, a degree-5 polynomial on a
# straight-sided triangle: order 6 integrates it exactly.
_INTORDER = 6
# Samples of a segment's element-density integral used to place the node columns;
# the density is smooth, so this only has to resolve its shape, not be exact.
_GRADING_SAMPLES = 400


@dataclass(frozen=True)
class FEResult:
    """Outcome of one finite-element torsion solve.

    Attributes
    ----------
    compliance : float
        Torsional compliance between the clamped and the twisted face [rad/(N·m)].
    elements : int
        Number of quadratic triangles [-].
    dofs : int
        Number of degrees of freedom [-].
    seconds : float
        Wall time of meshing, assembly and solve [s].
    change : float
        Relative change of the compliance from the previous refinement level [-];
        NaN for a single solve (only `converged_cup_compliance` fills it).
    """

    compliance: float
    elements: int
    dofs: int
    seconds: float
    change: float = math.nan


def _skfem():
    try:
        import skfem
    except ImportError:
        raise InputError("the finite-element check needs scikit-fem: pip install 'hdsim[fe]'") from None
    return skfem


def _require_positive(**values) -> None:
    for name, value in values.items():
        if not (np.isfinite(value) and value > 0.0):
            raise InputError(f"{name} must be a positive finite number, got {value!r}")


def _through_wall(elements_through_wall) -> int:
    n = int(elements_through_wall)
    if n != elements_through_wall or n < 1:
        raise InputError(f"elements_through_wall must be a positive integer, got {elements_through_wall!r}")
    return n


#: the most elements a section's mesh may have: 200,000 take about 1 GB and a minute; a wall
#: a hundred times thinner than the catalog's would need twenty times more
MAX_ELEMENTS = 200_000


def _graded(density) -> np.ndarray:
    """Logical positions σ ∈ [0, 1] of node columns, one element per unit of ``∫ density dσ``.

    ``density(σ)`` is the element count per unit σ wanted locally (arc length per σ
    over the target element length); equidistributing it grades the columns.
    """
    sigma = np.linspace(0.0, 1.0, _GRADING_SAMPLES + 1)
    d = density(sigma)
    cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (d[1:] + d[:-1]) * np.diff(sigma))])
    count = max(1, math.ceil(cumulative[-1] - 1e-9))
    return np.interp(np.linspace(0.0, cumulative[-1], count + 1), cumulative, sigma)


def _structured_mesh(r: np.ndarray, z: np.ndarray):
    """Triangle mesh of a mapped grid; ``r, z`` have shape (columns, nodes across the wall).

    Returns the mesh and the facet indices of the first and the last column (the two
    loaded faces). Every quad is split into two triangles; a fold-over in the map
    shows up as triangles of both signs or of zero area and is refused.
    """
    columns, rows = r.shape
    elements = 2 * (columns - 1) * (rows - 1)
    if elements > MAX_ELEMENTS:  # elements are about as long as the wall is thick: memory grows as 1/wall
        raise InputError(f"the FE check would need {elements:,} elements for this section (its thinnest wall "
                         f"is too thin for its length); it stops at {MAX_ELEMENTS:,} (about 1 GB): the closed "
                         "forms hold without it")
    skfem = _skfem()
    ids = np.arange(columns * rows).reshape(columns, rows)
    a, b = ids[:-1, :-1].ravel(), ids[1:, :-1].ravel()
    c, d = ids[1:, 1:].ravel(), ids[:-1, 1:].ravel()
    tri = np.hstack([np.vstack([a, b, c]), np.vstack([a, c, d])])
    p = np.vstack([r.ravel(), z.ravel()])
    e1, e2 = p[:, tri[1]] - p[:, tri[0]], p[:, tri[2]] - p[:, tri[0]]
    area = 0.5 * (e1[0] * e2[1] - e1[1] * e2[0])
    scale = np.max(np.abs(area))
    if not (np.all(area > 1e-12 * scale) or np.all(area < -1e-12 * scale)):
        raise InputError("the section mesh folds over: the geometry does not close into one wall")
    if area[0] < 0.0:  # keep one orientation so skfem's element maps are all positive
        tri = tri[[0, 2, 1]]
    mesh = skfem.MeshTri(p, tri)
    first = np.nonzero(np.all(np.isin(mesh.facets, ids[0]), axis=0))[0]
    last = np.nonzero(np.all(np.isin(mesh.facets, ids[-1]), axis=0))[0]
    return mesh, first, last


def _face_dofs(mesh, facets) -> np.ndarray:
    """Indices of the quadratic element's DOFs (vertices and edge midpoints) on ``facets``."""
    skfem = _skfem()
    from skfem.assembly import Dofs

    return Dofs(mesh, skfem.ElementTriP2()).get_facet_dofs(facets).all()


def _solve_torsion(mesh, G, clamped_dofs, twisted_dofs) -> FEResult:
    """Solve ``∫ r³ ∇ψ·∇v dA = 0`` with ψ = 0 / 1 rad on the two faces; return the compliance.

    Parameters
    ----------
    mesh : skfem.MeshTri
        Section mesh, x[0] = r [m], x[1] = z [m].
    G : float
        Shear modulus [Pa].
    clamped_dofs, twisted_dofs : numpy.ndarray
        P2 DOF indices held at ψ = 0 and ψ = 1 rad (see `_face_dofs`).

    Returns
    -------
    FEResult
        ``seconds`` covers assembly and solve only.
    """
    skfem = _skfem()
    from skfem.helpers import dot, grad

    start = time.perf_counter()

    @skfem.BilinearForm
    def weighted_laplace(u, v, w):
        return w.x[0] ** 3 * dot(grad(u), grad(v))

    basis = skfem.Basis(mesh, skfem.ElementTriP2(), intorder=_INTORDER)
    K = weighted_laplace.assemble(basis)
    psi = np.zeros(basis.N)
    psi[twisted_dofs] = 1.0
    held = np.concatenate([clamped_dofs, twisted_dofs])
    psi = skfem.solve(*skfem.condense(K, x=psi, D=held))
    # ψᵀKψ = ∫ r³|∇ψ|² dA: twice the strain energy over π G, i.e. the torque over 2π G.
    torque = 2.0 * np.pi * G * float(psi @ (K @ psi))
    if not (np.isfinite(torque) and torque > 0.0):
        raise SolverError(f"the torsion solve gave a torque of {torque!r} N·m for a unit twist")
    return FEResult(compliance=1.0 / torque, elements=int(mesh.t.shape[1]), dofs=int(basis.N),
                    seconds=time.perf_counter() - start)


def _solve_grid(r, z, G, start) -> FEResult:
    mesh, first, last = _structured_mesh(r, z)
    result = _solve_torsion(mesh, G, _face_dofs(mesh, first), _face_dofs(mesh, last))
    return replace(result, seconds=time.perf_counter() - start)


def tube_torsion_fe(*, r_inner, r_outer, length, G, elements_through_wall=4) -> FEResult:
    """Hollow circular tube twisted between its end faces (check against ``G J / L``).

    Parameters
    ----------
    r_inner, r_outer : float
        Bore and outer radius [m].
    length : float
        Axial length [m]; ψ = 0 on the face z = 0, ψ = 1 rad on z = length.
    G : float
        Shear modulus [Pa].
    elements_through_wall : int
        Element layers across the wall [-]; elements are about as long as they are thick.

    Returns
    -------
    FEResult
        Compliance [rad/(N·m)]; ψ linear in z is in the P2 space, so it is exact.
    """
    start = time.perf_counter()
    _require_positive(r_inner=r_inner, length=length, G=G)
    if not r_outer > r_inner:
        raise InputError(f"r_outer must exceed r_inner, got {r_outer!r} <= {r_inner!r}")
    n = _through_wall(elements_through_wall)
    along = max(1, math.ceil(length / ((r_outer - r_inner) / n)))
    zz, rr = np.meshgrid(np.linspace(0.0, length, along + 1), np.linspace(r_inner, r_outer, n + 1),
                         indexing="ij")
    return _solve_grid(rr, zz, G, start)


def annular_plate_torsion_fe(*, r_inner, r_outer, thickness, G, elements_through_wall=4) -> FEResult:
    """Flat annular plate twisted between its edges (check against Roark Table 11.2 case 16).

    Parameters
    ----------
    r_inner, r_outer : float
        Inner (clamped, ψ = 0) and outer (twisted, ψ = 1 rad) radius [m].
    thickness : float
        Plate thickness [m].
    G : float
        Shear modulus [Pa].
    elements_through_wall : int
        Element layers across the thickness [-].

    Returns
    -------
    FEResult
        Compliance [rad/(N·m)]; the exact ψ ∝ 1/r² is approximated, so it converges.
    """
    start = time.perf_counter()
    _require_positive(r_inner=r_inner, thickness=thickness, G=G)
    if not r_outer > r_inner:
        raise InputError(f"r_outer must exceed r_inner, got {r_outer!r} <= {r_inner!r}")
    n = _through_wall(elements_through_wall)
    along = max(1, math.ceil((r_outer - r_inner) / (thickness / n)))
    rr, zz = np.meshgrid(np.linspace(r_inner, r_outer, along + 1),
                         np.linspace(0.5 * thickness, -0.5 * thickness, n + 1), indexing="ij")
    return _solve_grid(rr, zz, G, start)


def _cup_grid(g: dict, n: int):
    """Node coordinates (r, z) of the cup section, columns from the hub to the rim.

    η runs from the inside of the wall (top of the diaphragm, centre side of the
    fillet, bore of the cylinder) to the outside, so the segments join without a twist
    of the grid. Every segment places its columns so that elements are about the local
    wall thickness over ``n`` long (on the fillet, measured on its longer, outer side).
    The diaphragm needs no extra grading towards the hub: at that element length its
    1/r² twist profile is already resolved to ~1e-6 (see the annular-plate check).
    """
    eta = np.linspace(0.0, 1.0, n + 1)[None, :]
    R_c = g["R_i"] + 0.5 * g["h_c"]
    r_fillet = R_c - g["R_k"]
    L_d = r_fillet - g["r_hub"]

    def diaphragm():
        s = _graded(lambda s: np.full_like(s, L_d * n / g["t_d"]))[:, None]
        return np.broadcast_arrays(g["r_hub"] + s * L_d, 0.5 * g["t_d"] - eta * g["t_d"])

    def fillet():
        def wall(s):
            return g["t_d"] + (g["h_c"] - g["t_d"]) * s

        s = _graded(lambda s: 0.5 * np.pi * (g["R_k"] + 0.5 * wall(s)) * n / wall(s))[:, None]
        alpha, t = 0.5 * np.pi * s, wall(s)
        rho = g["R_k"] - 0.5 * t + eta * t
        return r_fillet + rho * np.sin(alpha), g["R_k"] - rho * np.cos(alpha)

    def axial(z0, length, wall):
        s = _graded(lambda s: length * n / wall(s))[:, None]
        return np.broadcast_arrays(g["R_i"] + eta * wall(s), z0 + s * length)

    h_c, h_pz, h_u = g["h_c"], g["h_pz"], g["h_pz"] - g["h_p"]
    z_lead = g["R_k"] + g["cylinder_length"]
    z_step = z_lead + g["R_v"]
    parts = [diaphragm(), fillet(),
             axial(g["R_k"], g["cylinder_length"], lambda s: np.full_like(s, h_c)),
             axial(z_lead, g["R_v"], lambda s: h_c + (h_pz - h_c) * (1.0 - np.cos(0.5 * np.pi * s))),
             axial(z_step, g["undercut_width"], lambda s: np.full_like(s, h_u))]
    # Neighbouring segments share their junction column: keep the first copy.
    r = np.vstack([parts[0][0]] + [p[0][1:] for p in parts[1:]])
    z = np.vstack([parts[0][1]] + [p[1][1:] for p in parts[1:]])
    # The step h_pz → h_pz − h_p cannot be a sharp corner in a structured grid; giving its
    # column the mean wall centres the ramp on the step (one element either side), so the
    # thinned and thickened halves cancel to first order in the element length.
    step = len(r) - len(parts[4][0])
    r[step] = g["R_i"] + eta[0] * 0.5 * (h_pz + h_u)
    return r, z


def _check_cup(g: dict) -> None:
    _require_positive(**g)
    if not g["h_p"] < g["h_pz"]:
        raise InputError(f"h_p must be smaller than h_pz (the undercut keeps a wall), "
                         f"got {g['h_p']!r} >= {g['h_pz']!r}")
    if not g["R_k"] > 0.5 * max(g["t_d"], g["h_c"]):
        raise InputError(f"R_k = {g['R_k']!r} m must exceed half the wall it bends "
                         f"({0.5 * max(g['t_d'], g['h_c'])!r} m)")
    R_c = g["R_i"] + 0.5 * g["h_c"]
    if not R_c - g["R_k"] > g["r_hub"]:
        raise InputError(f"R_k = {g['R_k']!r} m is too large to fit: the diaphragm would end at "
                         f"r = {R_c - g['R_k']!r} m, inside the hub r_hub = {g['r_hub']!r} m")


def cup_torsion_fe(*, r_hub, t_d, R_k, R_i, h_c, h_pz, h_p, R_v, cylinder_length, undercut_width, G,
                   elements_through_wall=4) -> FEResult:
    """Torsional compliance of the flexspline cup from the hub to the start of the toothed rim.

    Parameters
    ----------
    r_hub : float
        Radius of the clamped hub edge of the diaphragm [m] (ψ = 0 on the face r = r_hub).
    t_d : float
        Diaphragm thickness [m] (the diaphragm spans z ∈ [−t_d/2, t_d/2]).
    R_k : float
        End-radius (fillet) radius of the mid-surface [m].
    R_i : float
        Bore radius of the cylinder [m].
    h_c : float
        Cylinder wall [m]; the fillet wall blends from t_d to h_c linearly in its angle.
    h_pz : float
        Wall at the end of the lead radius [m].
    h_p : float
        Depth of the undercut [m]; the undercut wall is h_pz − h_p.
    R_v : float
        Axial length of the lead radius [m] (wall ``h_c + (h_pz − h_c)(1 − cos(π s/2))``).
    cylinder_length : float
        Axial length of the cylinder [m].
    undercut_width : float
        Axial length of the undercut [m]; ψ = 1 rad on its end face.
    G : float
        Shear modulus [Pa].
    elements_through_wall : int
        Element layers across the wall [-]; element length along the wall follows the
        local wall thickness over this number.

    Returns
    -------
    FEResult
        Compliance of the cup [rad/(N·m)].

    Raises
    ------
    InputError
        Non-positive lengths, h_p ≥ h_pz, R_k not larger than half the wall or too large
        to fit between the hub and the cylinder; scikit-fem not installed.
    """
    start = time.perf_counter()
    g = dict(r_hub=r_hub, t_d=t_d, R_k=R_k, R_i=R_i, h_c=h_c, h_pz=h_pz, h_p=h_p, R_v=R_v,
             cylinder_length=cylinder_length, undercut_width=undercut_width, G=G)
    _check_cup(g)
    r, z = _cup_grid(g, _through_wall(elements_through_wall))
    return _solve_grid(r, z, G, start)


def converged_cup_compliance(*, tolerance=0.005, max_through_wall=16, **geometry) -> FEResult:
    """`cup_torsion_fe` refined (2, 4, 8, … elements through the wall) until it settles.

    Parameters
    ----------
    tolerance : float
        Largest accepted relative change of the compliance between two levels [-].
    max_through_wall : int
        Finest level tried [-].
    **geometry
        The keyword arguments of `cup_torsion_fe` except ``elements_through_wall``.

    Returns
    -------
    FEResult
        The last level, with ``change`` = |C_k − C_{k−1}| / C_k and ``seconds`` summed
        over all levels.

    Raises
    ------
    SolverError
        The change is still above ``tolerance`` at ``max_through_wall``.
    """
    _require_positive(tolerance=tolerance)
    if not max_through_wall >= 4:
        raise InputError(f"max_through_wall must be at least 4 (two levels to compare), "
                         f"got {max_through_wall!r}")
    if "elements_through_wall" in geometry:
        raise InputError("converged_cup_compliance chooses elements_through_wall itself")
    previous, seconds, n = None, 0.0, 2
    while n <= max_through_wall:
        result = cup_torsion_fe(**geometry, elements_through_wall=n)
        seconds += result.seconds
        if previous is not None:
            change = abs(result.compliance - previous.compliance) / result.compliance
            if change < tolerance:
                return replace(result, seconds=seconds, change=change)
        previous, n = result, 2 * n
    raise SolverError(f"the cup compliance did not settle to {tolerance:g} by {max_through_wall} "
                      f"elements through the wall (last change {change:.3g})")
