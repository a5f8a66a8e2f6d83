"""Plane-stress finite-element check of the flexspline rim on the wave-generator balls.

The closed form `hdsim.physics.compliance.rim_between_balls_stiffness` idealises
the toothed rim between two balls as a simply supported beam. This module solves
the same problem as two-dimensional linear elasticity so that closed form can be
checked: a full annulus (bore radius ``R_i``, wall ``h``, face width ``b``) in plane
stress, quadratic triangles (scikit-fem ``ElementVector(ElementTriP2())``) on a
structured polar mesh whose edge midpoints lie on the true arcs, so the circular
boundaries are represented to fourth order.

Model
-----
- Two engagement zones, centred at θ = 0 and θ = π. In each, a radial inward force
  ``F`` is spread uniformly over an arc ``a`` of the outer surface (half-angle
  ``a / (2 (R_i + h))``).
- Balls sit at angles spaced ``2π / n_b``, one centred on each zone or two straddling
  it; the pitch is measured at the bore, ``p = 2π R_i / n_b``. A ball touches the rim
  when it is within the loaded half-angle plus 1.5 pitches of the zone centre.
- Each ball holds the bore radially over a patch of arc length ``w_c`` (default
  ``0.15 p``): either rigidly (``u_r = 0`` at every node of the patch; the rim may
  slide tangentially, i.e. frictionless) or through a radial spring of total
  stiffness ``ball_stiffness`` spread uniformly over the patch.
- All loads and reactions are radial, so only the rigid rotation is free; it is
  removed by a zero mean rotation (one Lagrange multiplier, whose force is zero since
  nothing loads that mode): the tangential constraint at a symmetry point, made
  insensitive to the triangulation's lack of mirror symmetry.
- Stiffness per zone ``k = F / w̄``, with ``w̄`` the mean inward radial displacement of
  the loaded arc (the displacement work-conjugate to the load).

A point support has a logarithmically singular displacement in two-dimensional
elasticity, hence the finite patch. The stiffness depends strongly on ``w_c``: the
patch shortens the free span between balls.

The mesh is graded towards every patch and load edge (smallest element
``min(w_c, h)/6``), with ``4 × refinement`` elements through the wall and elements
about ``h/2`` long inside the zones, ``1.5 h`` outside.

References
----------
- Thick cylinder under external pressure (Lamé): Timoshenko & Goodier, Theory of
  Elasticity, 3rd ed., §33.
- Thin ring under two opposite radial loads: Roark's Formulas for Stress and
  Strain, 8th ed. (Young & Budynas), Table 9.2 case 1.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from hdsim.errors import InputError, SolverError

_THETA0 = -0.5 * np.pi  # the mesh seam; both zones (0 and π) lie well inside one turn
_MARGIN_PITCHES = 1.5  # balls in contact: within the loaded half-arc plus this many pitches


@dataclass(frozen=True)
class RimResult:
    """Radial stiffness of the rim in one engagement zone.

    Attributes
    ----------
    stiffness : float
        Radial stiffness per zone, ``F / w̄`` [N/m].
    elements : int
        Number of quadratic triangles.
    seconds : float
        Wall time for mesh, assembly and solve [s].
    dofs : int
        Number of displacement unknowns.
    reactions : tuple of float
        Radial force of each ball of the zone at θ = 0 on the rim, per unit zone
        load, from the most negative angle up; positive pushes outward, i.e. a
        compressive contact [-]. They sum to about 1.
    ball_angles : tuple of float
        Angles of those balls [rad].
    arc_deflection : float
        Mean of the nodal inward radial displacement over the loaded arc at θ = 0,
        per newton of zone load [m/N]: an independent check, ``stiffness ×
        arc_deflection ≈ 1``.
    """

    stiffness: float
    elements: int
    seconds: float
    dofs: int = 0
    reactions: tuple = ()
    ball_angles: tuple = ()
    arc_deflection: float = float("nan")


@dataclass(frozen=True)
class RingResult:
    """A ring solved without supports (rigid-body motion removed).

    Attributes
    ----------
    displacement : float
        Mean inward radial displacement of the loaded surface, work-conjugate to
        the load [m].
    outer_radial : numpy.ndarray
        Radial displacement of every node on the outer surface, outward positive [m].
    elements : int
        Number of quadratic triangles.
    seconds : float
        Wall time [s].
    """

    displacement: float
    outer_radial: np.ndarray
    elements: int
    seconds: float


def _skfem():
    try:
        import skfem
        from skfem.models.elasticity import linear_elasticity
    except ImportError:
        raise InputError("the finite-element check needs scikit-fem: pip install 'hdsim[fe]'") from None
    return skfem, linear_elasticity


def _positive(**values):
    for name, value in values.items():
        if not (isinstance(value, (int, float, np.number)) and np.isfinite(value) and value > 0):
            raise InputError(f"{name} must be a positive finite number, got {value!r}")


def _material(E, nu, refinement):
    _positive(E=E, refinement=refinement)
    if not (isinstance(nu, (int, float, np.floating)) and -1.0 < nu < 0.5):
        raise InputError(f"nu must lie in (-1, 0.5), got {nu!r}")


def _gap(theta):
    """Signed angle folded into [-π, π) [rad]."""
    return (np.asarray(theta) + np.pi) % (2.0 * np.pi) - np.pi


def _angles(breaks, radius, fine, coarse, far, zones, growth=0.25):
    """Node angles over one turn: graded towards every break, coarser outside the zones.

    The local element length (arc at ``radius``) is ``min(cap, fine + growth d)``
    with ``d`` the distance to the nearest break and ``cap`` = ``coarse`` inside a
    zone, ``far`` outside it; nodes are placed by equidistributing its inverse.
    """
    breaks = np.unique(np.round((np.append(breaks, _THETA0) - _THETA0) % (2.0 * np.pi) + _THETA0, 14))
    ends = np.append(breaks, _THETA0 + 2.0 * np.pi)
    nodes = []
    for lo, hi in zip(ends[:-1], ends[1:]):
        s = np.linspace(lo, hi, 801)
        d = radius * np.minimum(s - lo, hi - s)
        inside = np.zeros(s.shape, bool)
        for centre, half in zones:
            inside |= np.abs(_gap(s - centre)) <= half
        size = np.minimum(np.where(inside, coarse, far), fine + growth * d)
        density = radius / size
        cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(s))])
        count = max(2, int(np.ceil(cumulative[-1])))
        nodes.append(np.interp(np.linspace(0.0, cumulative[-1], count + 1)[:-1], cumulative, s))
    return np.concatenate(nodes)


def _ring_mesh(skfem, r_in, r_out, n_r, thetas):
    """Structured annulus: quadrilaterals split into two triangles, curved (P2) geometry."""
    n_t = thetas.size
    radii = np.linspace(r_in, r_out, n_r + 1)
    rr, tt = np.meshgrid(radii, thetas, indexing="ij")  # index [j, i] -> j * n_t + i
    p = np.vstack([(rr * np.cos(tt)).ravel(), (rr * np.sin(tt)).ravel()])
    j, i = np.meshgrid(np.arange(n_r), np.arange(n_t), indexing="ij")
    a, b = (j * n_t + i).ravel(), (j * n_t + (i + 1) % n_t).ravel()
    linear = skfem.MeshTri(p, np.hstack([np.vstack([a, b, b + n_t]), np.vstack([a, b + n_t, a + n_t])]))
    doflocs = skfem.MeshTri2.from_mesh(linear).doflocs.copy()
    # move every edge midpoint to the mid-point in (r, θ): the arcs become exact to O(Δθ⁴)
    ends = p[:, linear.facets]
    r_mid = 0.5 * (np.hypot(*ends[:, 0]) + np.hypot(*ends[:, 1]))
    t0 = np.arctan2(ends[1, 0], ends[0, 0])
    t_mid = t0 + 0.5 * _gap(np.arctan2(ends[1, 1], ends[0, 1]) - t0)
    doflocs[:, linear.nvertices:] = np.vstack([r_mid * np.cos(t_mid), r_mid * np.sin(t_mid)])
    return linear, skfem.MeshTri2(doflocs, linear.t)


def _surface_facets(linear, radius, arcs):
    """Boundary facets on the circle ``radius`` whose mid-angle lies in one of ``arcs`` (all if None)."""
    facets = linear.boundary_facets()
    ends = linear.p[:, linear.facets[:, facets]]
    on = np.abs(0.5 * (np.hypot(*ends[:, 0]) + np.hypot(*ends[:, 1])) - radius) < 1e-6 * radius
    theta = np.arctan2(*ends.sum(axis=1)[::-1])
    if arcs is None:
        return facets[on]
    return [facets[on & (np.abs(_gap(theta - centre)) < half)] for centre, half in arcs]


class _Ring:
    """Assembled plane-stress annulus: stiffness, radial line loads, radial constraints."""

    def __init__(self, r_in, r_out, thickness, E, nu, refinement, thetas):
        self.skfem, linear_elasticity = _skfem()
        self.r_in, self.r_out = r_in, r_out
        self.linear, self.mesh = _ring_mesh(self.skfem, r_in, r_out, max(2, round(4 * refinement)), thetas)
        self.element = self.skfem.ElementVector(self.skfem.ElementTriP2())
        self.basis = self.skfem.Basis(self.mesh, self.element, intorder=4)
        lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
        lam_star = 2 * lam * mu / (lam + 2 * mu)  # plane stress
        self.K = (thickness * self.skfem.asm(linear_elasticity(lam_star, mu), self.basis)).tocsr()
        self.n = self.K.shape[0]

    def _facet_basis(self, facets):
        try:
            return self.skfem.FacetBasis(self.mesh, self.element, facets=facets, intorder=6)
        except Exception as exc:  # scikit-fem raises a bare Exception when its Newton inversion fails
            raise SolverError(f"scikit-fem could not map the boundary quadrature points: {exc}") from None

    def radial_load(self, facets, line_load):
        """Inward radial line load [N/m] on ``facets``; returns the vector and total force [N]."""
        fb = self._facet_basis(facets)

        @self.skfem.LinearForm
        def inward(v, w):
            return -line_load * (v[0] * w.x[0] + v[1] * w.x[1]) / np.hypot(*w.x)

        length = self.skfem.Functional(lambda w: 1.0 + 0.0 * w.x[0])
        return self.skfem.asm(inward, fb), line_load * self.skfem.asm(length, fb)

    def radial_spring(self, facets, stiffness_per_length):
        fb = self._facet_basis(facets)

        @self.skfem.BilinearForm
        def spring(u, v, w):
            x, y = w.x
            return stiffness_per_length * (u[0] * x + u[1] * y) * (v[0] * x + v[1] * y) / (x**2 + y**2)

        return self.skfem.asm(spring, fb)

    def pairs(self, facets):
        """(x-dof, y-dof) of every node on ``facets``, vertices and edge midpoints."""
        verts = np.unique(self.linear.facets[:, facets])
        return np.hstack([self.basis.nodal_dofs[:, verts], self.basis.facet_dofs[:, facets]])

    def radial(self, u, facets):
        """Angles [rad] and outward radial displacement [m] of the nodes on ``facets``."""
        ix, iy = np.unique(self.pairs(facets), axis=1)
        x, y = self.basis.doflocs[:, ix]
        return np.arctan2(y, x), (u[ix] * x + u[iy] * y) / np.hypot(x, y)

    def rigid_modes(self, which=("x", "y", "rot")):
        x, y = self.basis.doflocs
        is_x = np.zeros(self.n, bool)
        is_x[np.concatenate([self.basis.nodal_dofs[0], self.basis.facet_dofs[0]])] = True
        modes = {"x": is_x * 1.0, "y": (~is_x) * 1.0, "rot": np.where(is_x, -y, x) / self.r_out}
        return np.column_stack([modes[m] for m in which])

    def solve(self, f, *, radial_pairs=None, extra=None, modes=("rot",)):
        """Displacements with ``u_r = 0`` at ``radial_pairs``, rigid ``modes`` removed."""
        K = self.K if extra is None else self.K + extra
        T = sp.identity(self.n, format="csr")
        if radial_pairs is not None and radial_pairs.size:
            ix, iy = np.unique(radial_pairs, axis=1)  # x-dof kept as the tangential motion, y-dof dropped
            x, y = self.basis.doflocs[:, ix] / np.hypot(*self.basis.doflocs[:, ix])
            keep = np.setdiff1d(np.arange(self.n), iy)
            col = np.full(self.n, -1)
            col[keep] = np.arange(keep.size)
            free = np.setdiff1d(keep, ix)
            rows, cols = np.concatenate([free, ix, iy]), col[np.concatenate([free, ix, ix])]
            T = sp.csr_matrix((np.concatenate([np.ones(free.size), -y, x]), (rows, cols)),
                              shape=(self.n, keep.size))
        C = T.T @ self.rigid_modes(modes)
        A = sp.bmat([[T.T @ K @ T, sp.csr_matrix(C)], [sp.csr_matrix(C.T), None]], format="csc")
        rhs = np.concatenate([T.T @ f, np.zeros(C.shape[1])])
        u = T @ spla.spsolve(A, rhs)[: T.shape[1]]
        return u, K @ u - f


def rim_radial_stiffness_fe(*, bore_radius, wall, face_width, E, nu, balls, arc_length, contact_width=None,
                            ball_on_centre=True, refinement=1, ball_stiffness=None,
                            ball_offset=None) -> RimResult:
    """Radial stiffness per engagement zone of the rim on the wave-generator balls.

    Parameters
    ----------
    bore_radius : float
        Bore radius ``R_i``, where the balls' outer race touches [m].
    wall : float
        Rim wall under the teeth ``h`` [m]; outer radius ``R_i + h``.
    face_width : float
        Face width ``b`` (plane-stress thickness) [m].
    E, nu : float
        Young's modulus [Pa] and Poisson's ratio [-].
    balls : int
        Number of balls ``n_b``; pitch at the bore ``p = 2π R_i / n_b`` [m].
    arc_length : float
        Loaded arc ``a`` on the outer surface, per zone [m].
    contact_width : float, optional
        Arc length of each ball's support patch on the bore ``w_c`` [m]; default ``0.15 p``.
    ball_on_centre : bool
        One ball centred on each zone (True) or two straddling it (False).
    refinement : float
        Mesh density factor; 2 halves every element. The stiffness converges about
        linearly: 2 % too stiff at 1, 1 % at 2.
    ball_stiffness : float, optional
        Radial stiffness of one ball contact [N/m]; rigid balls if omitted.
    ball_offset : float, optional
        Turn of the ball set from the on-centre position, in pitches [-]: 0 is
        on-centre, 0.5 straddling; overrides ``ball_on_centre``. Both zones get the
        same set (a rigid set of balls for an even ``n_b``).

    Returns
    -------
    RimResult
        Stiffness per zone [N/m], mesh size, wall time and ball reactions.
    """
    start = time.perf_counter()
    _positive(bore_radius=bore_radius, wall=wall, face_width=face_width, arc_length=arc_length)
    _material(E, nu, refinement)
    if isinstance(balls, bool) or not isinstance(balls, (int, np.integer)) or balls < 4:
        raise InputError(f"balls must be an integer of at least 4, got {balls!r}")
    r_in, r_out = float(bore_radius), float(bore_radius + wall)
    pitch = 2.0 * np.pi * r_in / balls
    w_c = 0.15 * pitch if contact_width is None else contact_width
    _positive(contact_width=w_c, **({} if ball_stiffness is None else {"ball_stiffness": ball_stiffness}))
    if w_c >= 0.9 * pitch:
        raise InputError(f"contact_width {w_c:g} m must be below 0.9 of the ball pitch {pitch:g} m")
    beta = 2.0 * np.pi / balls
    phi = arc_length / (2.0 * r_out)
    reach = phi + _MARGIN_PITCHES * beta
    if reach + beta >= 0.5 * np.pi:
        raise InputError(f"arc_length {arc_length:g} m is too long: the two engagement zones would meet")
    half_patch = 0.5 * w_c / r_in
    offset = (0.0 if ball_on_centre else 0.5) if ball_offset is None else ball_offset
    if not (isinstance(offset, (int, float, np.floating)) and np.isfinite(offset)):
        raise InputError(f"ball_offset must be a finite number of pitches, got {ball_offset!r}")
    local = (np.arange(-balls, balls + 1) + offset) * beta
    local, centres = local[np.abs(local) <= reach + 1e-12], (0.0, np.pi)
    ball_angles = np.concatenate([c + local for c in centres])

    load_edges = [-phi, phi, np.pi - phi, np.pi + phi]
    breaks = np.concatenate([ball_angles - half_patch, ball_angles + half_patch, load_edges])
    thetas = _angles(breaks, r_in, min(w_c, wall) / 6.0 / refinement, wall / 2.0 / refinement,
                     1.5 * wall / refinement, [(c, reach + beta) for c in centres])
    ring = _Ring(r_in, r_out, face_width, E, nu, refinement, thetas)

    load_facets = np.concatenate(_surface_facets(ring.linear, r_out, [(c, phi) for c in centres]))
    f, total = ring.radial_load(load_facets, 1.0 / arc_length)  # 1 N per zone; the problem is linear
    patches = _surface_facets(ring.linear, r_in, [(a, half_patch) for a in ball_angles])
    all_patches = np.concatenate(patches)
    if ball_stiffness is None:
        u, residual = ring.solve(f, radial_pairs=ring.pairs(all_patches))
    else:
        springs = ring.radial_spring(all_patches, ball_stiffness / w_c)
        u, residual = ring.solve(f, extra=springs)
        residual = -(springs @ u)  # the springs' force on the rim
    deflection = float(f @ u) / total  # mean inward radial displacement of the loaded arcs
    reactions = tuple(float(ring.radial(residual, patch)[1].sum()) / (0.5 * total)
                      for patch in patches[: local.size])
    angles, radial = ring.radial(u, load_facets)
    near = np.abs(angles) < 0.5 * np.pi
    t, w = angles[near][np.argsort(angles[near])], -radial[near][np.argsort(angles[near])]
    arc = np.sum(0.5 * (w[1:] + w[:-1]) * np.diff(t)) / (2.0 * phi) / (0.5 * total)
    return RimResult(stiffness=0.5 * total / deflection, elements=int(ring.mesh.t.shape[1]),
                     seconds=time.perf_counter() - start, dofs=int(ring.n), reactions=reactions,
                     ball_angles=tuple(float(a) for a in local), arc_deflection=float(arc))


def _unsupported(ring, f, total, start):
    u, _ = ring.solve(f, modes=("x", "y", "rot"))
    radial = ring.radial(u, _surface_facets(ring.linear, ring.r_out, None))[1]
    return RingResult(displacement=float(f @ u) / total, outer_radial=radial,
                      elements=int(ring.mesh.t.shape[1]), seconds=time.perf_counter() - start)


def ring_under_external_pressure_fe(*, inner_radius, outer_radius, thickness, E, nu, pressure,
                                    refinement=1) -> RingResult:
    """Annulus under uniform external pressure, no supports (Lamé check of the assembly).

    Parameters
    ----------
    inner_radius, outer_radius : float
        Radii of the annulus [m].
    thickness : float
        Plane-stress thickness [m].
    E, nu : float
        Young's modulus [Pa] and Poisson's ratio [-].
    pressure : float
        External pressure [Pa].
    refinement : float
        Mesh density factor.

    Returns
    -------
    RingResult
        ``displacement`` is the mean inward radial displacement of the outer surface [m].
    """
    start = time.perf_counter()
    _positive(inner_radius=inner_radius, outer_radius=outer_radius, thickness=thickness, pressure=pressure)
    _material(E, nu, refinement)
    if outer_radius <= inner_radius:
        raise InputError("outer_radius must exceed inner_radius")
    thetas = _THETA0 + np.linspace(0.0, 2.0 * np.pi, int(np.ceil(64 * refinement)), endpoint=False)
    ring = _Ring(inner_radius, outer_radius, thickness, E, nu, refinement, thetas)
    f, total = ring.radial_load(_surface_facets(ring.linear, outer_radius, None), pressure * thickness)
    return _unsupported(ring, f, total, start)


def ring_pinched_fe(*, mean_radius, wall, face_width, E, nu, force, arc_length=None,
                    refinement=1) -> RingResult:
    """Ring pinched by two opposite inward radial loads on its outer surface (Roark check).

    Parameters
    ----------
    mean_radius, wall, face_width : float
        Mid-wall radius ``R``, wall ``h`` and plane-stress thickness ``b`` [m].
    E, nu : float
        Young's modulus [Pa] and Poisson's ratio [-].
    force : float
        Each load ``F`` [N], at θ = 0 and θ = π.
    arc_length : float, optional
        Arc over which each load is spread [m]; default ``h / 2``.
    refinement : float
        Mesh density factor.

    Returns
    -------
    RingResult
        ``displacement`` is the mean inward displacement of one loaded arc; the
        diametral shortening is twice it [m].
    """
    start = time.perf_counter()
    _positive(mean_radius=mean_radius, wall=wall, face_width=face_width, force=force)
    _material(E, nu, refinement)
    if wall >= mean_radius:
        raise InputError("wall must be thinner than the mean radius")
    a = 0.5 * wall if arc_length is None else arc_length
    _positive(arc_length=a)
    r_in, r_out = mean_radius - 0.5 * wall, mean_radius + 0.5 * wall
    phi = a / (2.0 * r_out)
    if phi >= 0.25 * np.pi:
        raise InputError("arc_length is too long for a pinched ring")
    thetas = _angles([-phi, phi, np.pi - phi, np.pi + phi], r_in, min(a, wall) / 6.0 / refinement,
                     wall / refinement, wall / refinement, [])
    ring = _Ring(r_in, r_out, face_width, E, nu, refinement, thetas)
    facets = np.concatenate(_surface_facets(ring.linear, r_out, [(0.0, phi), (np.pi, phi)]))
    f, total = ring.radial_load(facets, force / a)
    return _unsupported(ring, f, total, start)
