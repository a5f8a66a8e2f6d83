"""Flexspline geometry: the five design dimensions of the seed paper plus the fixed ones.

All lengths in metres. Fields may be floats or equal-length numpy arrays (a batch of
geometries for a Sobol study); every check is vectorised and names the first
offending sample.

Layout along the cup axis, from the bottom (hub) to the open end::

    hub | diaphragm (t_d) | end radius R_k | cylinder (h_c) | lead radius R_v |
        undercut (wall h_pz - h_p, width w_u) | toothed rim (h_pz, face width b)

The bore radius ``R_i`` is set by the wave generator and does not change with the
wall thicknesses; the tooth root sits at ``R_i + h_pz`` and the pitch circle one
dedendum (`DEDENDUM_MODULES` = 1.25 modules, the usual full-depth proportion)
further out.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

import numpy as np

from hdsim.errors import InputError
from hdsim.model.parameters import as_numbers, not_whole, whole_count_message

#: dedendum of the flexspline teeth in modules: the usual full-depth proportion
#: (addendum 1 m, dedendum 1.25 m), which leaves a root clearance of 0.25 m
DEDENDUM_MODULES = 1.25
#: the teeth must fit the rim: module × teeth / 2 within this share of the pitch radius
#: (a design study moves h_pz by ±10 %, the pitch radius by ±0.3 %; a module typed in
#: metres instead of millimetres is a thousandfold off)
PITCH_TOLERANCE = 0.05
#: Young's modulus of the materials a flexspline is made of [Pa]: from engineering plastics
#: (POM, PA: 2-3 GPa; 1 GPa leaves room for softer ones) to beyond the stiffest metals of
#: gearing (steels 190-215 GPa, tungsten alloys about 400 GPa). A modulus typed in GPa or
#: MPa is a billion or a million times too small. A drive file's E must lie in this range.
E_MATERIALS = (1e9, 500e9)
#: the stiffest modulus a model may carry [Pa]: a millionfold the stiffest material, the
#: rigid limit a fit stiffens the structure towards (hdsim.identification.problem, up to
#: 1e6 × the nominal E) and a rigid reference uses; the closed forms overflow near 1e300
E_RIGID = 1e6 * E_MATERIALS[1]
#: walls (h_pz, h_c, t_d and the wall under the undercut) as shares of the bore radius R_i:
#: above 10 % the thin-shell closed forms do not hold; below 0.1 % (R/h = 1000) the wall is
#: a foil, a twentieth of the built-in proportions' 2-3.5 %, and its cube underflows long
#: before a value such as 1e-200 m reaches the closed forms
WALL_SHARE = (1e-3, 0.1)
#: the hub radius at least this share of the bore radius: the hub carries the output
#: flange (the built-in proportions put it at about half the bore), and the diaphragm's
#: compliance grows as 1/r_hub², without bound for a point-like hub
HUB_SHARE = 0.1
#: the cup at most this many bore radii long: flexspline cups are 0.5-1 diameter long (the
#: built-in proportions 0.8 d, 1.7 R_i); a cup length in millimetres is a thousandfold off
CUP_LENGTH_RADII = 10.0
#: the flanks' pressure angle from 5° (involute gearing uses 14.5-30°; at a vanishing angle
#: the mesh loses its radial component and its closed form its compliance) to below 45°
PRESSURE_ANGLE = (np.radians(5.0), np.pi / 4)
#: the walls the thin-shell closed forms take: rim under the teeth, cylinder, diaphragm
WALLS = ("h_pz", "h_c", "t_d")


def _dim(doc: str, unit: str = "m", symbol: str = "", design: bool = False, count: str = ""):
    metadata = {"doc": doc, "unit": unit, "symbol": symbol, "design": design}
    if count:  # what it counts (as `hdsim.model.parameters.param`): whole numbers only
        metadata["count"] = count
    return field(metadata=metadata)


@dataclass(frozen=True)
class FlexsplineGeometry:
    """Dimensions of a cup-type flexspline [m, Pa]."""

    h_pz: float = _dim("thickness under the teeth (rim wall)", symbol="h_pz", design=True)
    h_c: float = _dim("wall thickness of the cylindrical part", symbol="h_c", design=True)
    R_v: float = _dim("lead radius of the gearing (cylinder-to-rim transition)", symbol="R_v", design=True)
    R_k: float = _dim("end radius of the cylinder (diaphragm-to-cylinder fillet)", symbol="R_k", design=True)
    h_p: float = _dim("depth of the undercut below the tooth root", symbol="h_p", design=True)
    R_i: float = _dim("bore radius, set by the wave generator")
    face_width: float = _dim("face width of the toothed rim b")
    cup_length: float = _dim("cup length from diaphragm mid-plane to the open end L")
    undercut_width: float = _dim("axial width of the undercut groove w_u")
    t_d: float = _dim("diaphragm thickness")
    r_hub: float = _dim("outer radius of the rigid hub (inner edge of the diaphragm)")
    module: float = _dim("gear module m")
    teeth: float = _dim("flexspline tooth count z_fs", unit="-", count="teeth")
    pressure_angle: float = _dim("pressure angle of the tooth flanks α", unit="rad")
    E: float = _dim("Young's modulus", unit="Pa")
    nu: float = _dim("Poisson's ratio", unit="-")

    def __post_init__(self):
        validate_geometry(self)

    # Derived radii and lengths: computed, never stored, so a replace() cannot leave
    # them stale.
    @property
    def G(self):
        """Shear modulus [Pa]."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def R_c(self):
        """Mean radius of the cylinder wall [m]."""
        return self.R_i + 0.5 * self.h_c

    @property
    def R_rim(self):
        """Mean radius of the toothed rim wall [m]."""
        return self.R_i + 0.5 * self.h_pz

    @property
    def pitch_radius(self):
        """Pitch radius, one dedendum (1.25 modules) beyond the tooth root [m]."""
        return self.R_i + self.h_pz + DEDENDUM_MODULES * self.module

    @property
    def cylinder_length(self):
        """Length of the plain cylinder between the two fillets [m]."""
        return self.cup_length - self.R_k - self.R_v - self.undercut_width - self.face_width

    def replace(self, **changes) -> "FlexsplineGeometry":
        """A copy with some fields changed (checked again).

        Parameters
        ----------
        **changes : float or numpy.ndarray
            Field name -> new value [m, Pa or -, as the field].

        Returns
        -------
        FlexsplineGeometry
            The new geometry.

        Raises
        ------
        InputError
            If the new geometry fails `validate_geometry`.
        """
        return replace(self, **changes)

    @classmethod
    def design_names(cls) -> tuple[str, ...]:
        """Names of the five design dimensions of the seed paper.

        Returns
        -------
        tuple of str
            ``('h_pz', 'h_c', 'R_v', 'R_k', 'h_p')``.
        """
        return tuple(f.name for f in fields(cls) if f.metadata["design"])

    def as_dict(self) -> dict:
        """Every field by name.

        Returns
        -------
        dict
            Field name -> value [m, Pa or -].
        """
        return {f.name: getattr(self, f.name) for f in fields(self)}


def _unit(name: str) -> str:
    return next(f.metadata["unit"] for f in fields(FlexsplineGeometry) if f.name == name)


def _first_bad(condition) -> int | None:
    bad = np.atleast_1d(np.asarray(condition))
    if not bad.any():
        return None
    return int(np.flatnonzero(bad)[0])


def _at(x, i: int) -> float:
    """Sample ``i`` of a field that may be a scalar or a batch."""
    return float(np.atleast_1d(x)[min(i, np.size(x) - 1)])


def _fail(message: str, index: int | None, batched: bool) -> None:
    where = f" (sample {index})" if batched else ""
    raise InputError(f"flexspline geometry{where}: {message}")


def _mm(x) -> str:
    """A length as messages show it: in mm, or in m where 1e3·x would overflow."""
    x = float(x)
    return f"{x * 1e3:.4g} mm" if abs(x) < 1e300 else f"{x:.4g} m"


def _metres_hint(value: float, low: float, high: float) -> str:
    """'; lengths are in metres: …' when ``value`` read as millimetres would lie in [low, high]."""
    if low <= value * 1e-3 <= high:
        return f"; lengths are in metres: {value:.4g} mm is {value * 1e-3:.4g}"
    return ""


def _modulus_hint(E: float) -> str:
    """How a modulus given in GPa, MPa or kPa reads in Pa, where one of them fits `E_MATERIALS`."""
    for scale, unit in ((1e9, "GPa"), (1e6, "MPa"), (1e3, "kPa")):
        if E_MATERIALS[0] <= E * scale <= E_MATERIALS[1]:
            return f" ({E:.4g} {unit} is {E * scale:.4g})"
    return ""


def _wall_checks(g: FlexsplineGeometry) -> list:
    """(condition, message) of each wall (`WALLS`) thicker than `WALL_SHARE` allows of the bore radius."""
    low, high = WALL_SHARE
    checks = []
    for name in WALLS:
        h = getattr(g, name)
        checks.append((h > high * g.R_i, lambda i, name=name, h=h: (
            f"flexspline.{name} = {_mm(_at(h, i))} is more than {100 * high:g} % of the bore radius "
            f"R_i = {_mm(_at(g.R_i, i))} (at most {_mm(high * _at(g.R_i, i))}): thicker walls break the "
            "thin-shell assumption" + _metres_hint(_at(h, i), low * _at(g.R_i, i), high * _at(g.R_i, i)))))
    return checks


def _thin_wall_checks(g: FlexsplineGeometry) -> list:
    """(condition, message) of each wall thinner than `WALL_SHARE` of the bore radius (the
    undercut's wall h_pz − h_p among them)."""
    low = WALL_SHARE[0]
    walls = {name: getattr(g, name) for name in WALLS}
    walls["h_pz - h_p"] = g.h_pz - g.h_p
    checks = []
    for name, h in walls.items():
        label = ("the wall under the undercut h_pz − h_p" if name == "h_pz - h_p" else f"flexspline.{name}")
        checks.append((h < low * g.R_i, lambda i, label=label, h=h: (
            f"{label} = {_mm(_at(h, i))} is less than {100 * low:g} % of the bore radius R_i = "
            f"{_mm(_at(g.R_i, i))} (at least {_mm(low * _at(g.R_i, i))}): a foil, not a flexspline wall")))
    return checks


def validate_geometry(g: FlexsplineGeometry) -> None:
    """Refuse shapes that cannot be built or that break the thin-shell closed forms.

    Parameters
    ----------
    g : FlexsplineGeometry
        The geometry (a batch is checked sample by sample).

    Raises
    ------
    InputError
        Naming the first offending sample of a batch, and the dimensions and values at
        fault, for: a field that is not a positive finite number, a Young's modulus below
        1 GPa or above `E_RIGID`, an undercut deeper than the rim wall, ν ≥ 0.5, a pressure
        angle outside 5°-45°, a wall (`WALLS`) thicker than 10 % of the bore radius, an end
        radius that does not fit between hub and cylinder, a tooth count that is not
        whole, teeth that do not fit the pitch radius (`PITCH_TOLERANCE`), a wall thinner
        than 0.1 % of the bore radius, a hub under 10 % of it (`HUB_SHARE`), a face width
        under one module, a cup longer than 10 bore radii (`CUP_LENGTH_RADII`), or no
        plain cylinder left in the cup.
    """
    values = {}
    for f in fields(g):
        values[f.name] = as_numbers(f"flexspline.{f.name}", getattr(g, f.name))
    sizes = {v.size for v in values.values() if v.ndim == 1} - {1}
    if len(sizes) > 1:
        raise InputError(f"flexspline batch parameters have different lengths {sorted(sizes)}")
    batched = any(v.ndim > 0 for v in values.values())
    for name, v in values.items():
        i = _first_bad(~np.isfinite(v) | (v <= 0.0))
        if i is not None:
            _fail(f"{name} must be a positive finite number, got {np.atleast_1d(v)[i]:g} {_unit(name)}",
                  i, batched)
    cup_limit = CUP_LENGTH_RADII * g.R_i
    # the order puts a dimension typed in the wrong unit before the relations it upsets: a
    # wall in millimetres is named as the wall, not as teeth that no longer fit the rim
    checks = [
        (g.E < E_MATERIALS[0],
         lambda i: f"flexspline.E = {_at(g.E, i):.4g} Pa is below {E_MATERIALS[0] / 1e9:g} GPa, softer than any "
                   f"flexspline material (plastics 2-3 GPa, steels 190-215 GPa): E is in Pa{_modulus_hint(_at(g.E, i))}"),
        (g.E > E_RIGID,
         lambda i: f"flexspline.E = {_at(g.E, i):.4g} Pa is above {E_RIGID:.4g} Pa, a millionfold the stiffest "
                   "material: E is in Pa (steel 2.1e11)"),
        (g.h_p >= g.h_pz, lambda i: f"undercut depth h_p = {_mm(_at(g.h_p, i))} must be less than the "
                                    f"thickness under the teeth h_pz = {_mm(_at(g.h_pz, i))}"),
        (g.nu >= 0.5, lambda i: f"Poisson's ratio flexspline.nu = {_at(g.nu, i):.4g} must be below 0.5"),
        (g.pressure_angle >= PRESSURE_ANGLE[1],
         lambda i: f"pressure angle {_at(g.pressure_angle, i):.4g} rad must be below 45° (0.785 rad)"
                   + (f"; angles are in radians: {_at(g.pressure_angle, i):.4g}° is "
                      f"{np.radians(_at(g.pressure_angle, i)):.4g}" if _at(g.pressure_angle, i) < 45.0 else "")),
        (g.pressure_angle < PRESSURE_ANGLE[0],
         lambda i: f"pressure angle flexspline.pressure_angle = {_at(g.pressure_angle, i):.4g} rad must be at "
                   f"least 5° ({PRESSURE_ANGLE[0]:.4g} rad; involute flanks have 14.5-30°)"),
        *_wall_checks(g),
        (g.r_hub >= g.R_c,
         lambda i: f"hub radius flexspline.r_hub = {_mm(_at(g.r_hub, i))} does not fit inside the cylinder "
                   f"(mid-wall radius R_c = R_i + h_c/2 = {_mm(_at(g.R_c, i))})"
                   + _metres_hint(_at(g.r_hub, i), HUB_SHARE * _at(g.R_i, i), _at(g.R_c, i))),
        (g.R_k >= g.R_c - g.r_hub,
         lambda i: f"end radius flexspline.R_k = {_mm(_at(g.R_k, i))} does not fit between the hub "
                   f"(r_hub = {_mm(_at(g.r_hub, i))}) and the cylinder (R_c = {_mm(_at(g.R_c, i))}): "
                   f"{_mm(_at(g.R_c - g.r_hub, i))} available"),
        (not_whole(g.teeth), lambda i: whole_count_message("flexspline.teeth", _at(g.teeth, i), "teeth")),
        (np.abs(0.5 * g.module * g.teeth - g.pitch_radius) > PITCH_TOLERANCE * g.pitch_radius,
         lambda i: f"module × teeth / 2 = {_mm(_at(0.5 * g.module * g.teeth, i))} must be the pitch radius "
                   f"R_i + h_pz + {DEDENDUM_MODULES:g} module = {_mm(_at(g.pitch_radius, i))} (within "
                   f"{100 * PITCH_TOLERANCE:g} %): change module, teeth and R_i together"),
        *_thin_wall_checks(g),
        (g.r_hub < HUB_SHARE * g.R_i,
         lambda i: f"hub radius flexspline.r_hub = {_mm(_at(g.r_hub, i))} is less than {100 * HUB_SHARE:g} % of "
                   f"the bore radius R_i = {_mm(_at(g.R_i, i))} (at least {_mm(HUB_SHARE * _at(g.R_i, i))}): "
                   "a hub that small carries no output flange"),
        (g.face_width < g.module,
         lambda i: f"face width flexspline.face_width = {_mm(_at(g.face_width, i))} is narrower than one module "
                   f"(m = {_mm(_at(g.module, i))}): no toothed face"),
        (g.cup_length > cup_limit,
         lambda i: f"cup length flexspline.cup_length = {_mm(_at(g.cup_length, i))} is more than "
                   f"{CUP_LENGTH_RADII:g} bore radii (R_i = {_mm(_at(g.R_i, i))}; at most {_mm(_at(cup_limit, i))})"
                   + _metres_hint(_at(g.cup_length, i), 0.0, _at(cup_limit, i))),
        (g.cylinder_length <= 0.0,
         lambda i: f"R_k + R_v + undercut_width + face_width = "
                   f"{_mm(_at(g.R_k + g.R_v + g.undercut_width + g.face_width, i))} exceed the cup length "
                   f"cup_length = {_mm(_at(g.cup_length, i))}: no cylinder left (R_k = {_mm(_at(g.R_k, i))}, "
                   f"R_v = {_mm(_at(g.R_v, i))}, undercut_width = {_mm(_at(g.undercut_width, i))}, "
                   f"face_width = {_mm(_at(g.face_width, i))})"),
    ]
    for condition, message in checks:
        i = _first_bad(condition)
        if i is not None:
            _fail(message(i), i, batched)
