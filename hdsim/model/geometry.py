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


def validate_geometry(g: FlexsplineGeometry) -> None:
    """Refuse shapes that cannot be built or that break the thin-shell closed forms.

    Parameters
    ----------
    g : FlexsplineGeometry
        The geometry (a batch is checked sample by sample).

    Raises
    ------
    InputError
        Naming the first offending sample of a batch, for: a field that is not a positive
        finite number, an undercut deeper than the rim wall, ν ≥ 0.5, a pressure angle
        of 45° or more, a tooth count that is not whole, teeth that do not fit the pitch
        radius (`PITCH_TOLERANCE`), walls thicker than 10 % of the bore radius, an end radius that
        does not fit between hub and cylinder, or no plain cylinder left in the cup.
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
    def fmt(x, i):
        x = _at(x, i)
        return f"{x * 1e3:.4g} mm" if abs(x) < 1e300 else f"{x:.4g} m"  # 1e3·x would overflow (a warning)

    checks = [
        (g.h_p >= g.h_pz, lambda i: f"undercut depth h_p = {fmt(g.h_p, i)} must be less than the "
                                    f"thickness under the teeth h_pz = {fmt(g.h_pz, i)}"),
        (g.nu >= 0.5, lambda i: "Poisson's ratio must be below 0.5"),
        (g.pressure_angle >= np.pi / 4,
         lambda i: f"pressure angle {_at(g.pressure_angle, i):.4g} rad must be below 45° (0.785 rad)"),
        (np.maximum(g.h_pz, g.h_c) > 0.1 * g.R_i,
         lambda i: f"walls thicker than 10 % of the bore radius ({fmt(0.1 * g.R_i, i)}) break the "
                   "thin-shell assumption"),
        (g.R_k >= g.R_c - g.r_hub,
         lambda i: f"end radius R_k = {fmt(g.R_k, i)} does not fit between hub and cylinder "
                   f"({fmt(g.R_c - g.r_hub, i)} available)"),
        (not_whole(g.teeth), lambda i: whole_count_message("flexspline.teeth", _at(g.teeth, i), "teeth")),
        (np.abs(0.5 * g.module * g.teeth - g.pitch_radius) > PITCH_TOLERANCE * g.pitch_radius,
         lambda i: f"module × teeth / 2 = {fmt(0.5 * g.module * g.teeth, i)} must be the pitch radius "
                   f"R_i + h_pz + {DEDENDUM_MODULES:g} module = {fmt(g.pitch_radius, i)} (within "
                   f"{100 * PITCH_TOLERANCE:g} %): change module, teeth and R_i together"),
        (g.cylinder_length <= 0.0,
         lambda i: f"R_k + R_v + undercut + face width exceed the cup length {fmt(g.cup_length, i)}: "
                   f"no cylinder left (R_v = {fmt(g.R_v, i)}, R_k = {fmt(g.R_k, i)})"),
    ]
    for condition, message in checks:
        i = _first_bad(condition)
        if i is not None:
            _fail(message(i), i, batched)
