"""The harmonic drive model: geometry, calibration, inertias, five effect slots, input friction.

A `HarmonicDrive` holds parameters only. Every numeric parameter has a
dotted name (``flexspline.h_c``, ``friction.k_h``, ``drive.J_out``,
``input_friction.coulomb_torque`` …) so studies,
fits and the CLI's ``--set`` address them uniformly; `HarmonicDrive.with_updates`
returns a new model and accepts arrays, giving a *batch* model that the solver
integrates for all parameter sets at once.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import ClassVar

import numpy as np

from hdsim.model import effects as fx
from hdsim.model.parameters import Parameters, as_numbers, numeric_fields, param
from hdsim.errors import InputError, unknown_name
from hdsim.model.geometry import FlexsplineGeometry
from hdsim.model.input_friction import InputFriction, catalog_friction
from hdsim.physics import compliance as cc

SLOTS = ("hardening", "backlash", "friction", "damping", "kinematic_error")


@dataclass(frozen=True, eq=False)
class WaveGenerator(Parameters):
    """Wave generator data that set the radial support of the teeth."""

    k_bearing: float = param("radial stiffness of the WG bearing per engagement zone", "N/m",
                             positive=True)
    balls: float = param("ball count of the WG bearing", "-", 3, 200, count="balls")
    support_width: float = param("arc of the bore each ball holds through the bearing's outer race", "m",
                                 positive=True)
    engagement_fraction: float = param(
        "circumference share of one engagement zone at light load", "-", 0.01, 0.5)

    prefix: ClassVar[str] = "wave_generator"

    def ball_pitch(self, bore_radius):
        """Distance between neighbouring balls along the flexspline bore [m].

        The rim rests on the balls (through the outer race) at their angular pitch
        ``2π/n_b``; the span it bridges is that angle times the bore radius.
        """
        return 2.0 * np.pi * bore_radius / self.balls


@dataclass(frozen=True, eq=False)
class DriveData(Parameters):
    """Ratio, rating and inertias of the drive on its test bench."""

    ratio: float = param("transmission ratio N (output turns 1/N per WG turn)", "-", -1e4, 1e4)
    rated_torque: float = param("rated output torque T_N", "N·m", positive=True)
    J_in: float = param("inertia on the wave-generator shaft (motor + WG)", "kg·m²", positive=True)
    J_out: float = param("inertia on the output (flange + load fixture)", "kg·m²", positive=True)
    prefix: ClassVar[str] = "drive"

    def __post_init__(self):
        super().__post_init__()
        if np.any(np.abs(np.asarray(self.ratio)) < 1.0):
            raise InputError("drive.ratio must be at least 1 in magnitude")


@dataclass(frozen=True, eq=False)
class Calibration(Parameters):
    """Per-unit calibration of the closed forms against the catalog (see docs/physics.md).

    ``kappa_mesh`` multiplies the closed-form mesh-zone compliance so that the nominal
    geometry reproduces the catalog K1. It is a property of the unit, fixed when the
    unit is built: a change of geometry acts through the closed forms, not through it.
    """

    kappa_mesh: float = param("mesh-zone compliance factor", "-", 1e-3, 1e5)
    prefix: ClassVar[str] = "calibration"


@dataclass(frozen=True)
class ComplianceChain:
    """Torsional compliances of the torque path [rad/(N·m)], output flange to mesh."""

    diaphragm: np.ndarray
    end_radius: np.ndarray
    cylinder: np.ndarray
    lead_radius: np.ndarray
    undercut: np.ndarray
    rim: np.ndarray
    mesh_zone: np.ndarray

    @property
    def structure(self):
        """Shell part of the chain (everything but the mesh zone)."""
        return self.diaphragm + self.end_radius + self.cylinder + self.lead_radius + self.undercut + self.rim

    @property
    def total(self):
        return self.structure + self.mesh_zone

    def as_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class RadialSupport:
    """Radial stiffness of the teeth's support over one engagement zone [N/m] and the
    lengths it follows from [m] (`radial_support`)."""

    zone_arc: np.ndarray
    ball_pitch: np.ndarray
    rim: np.ndarray
    bearing: np.ndarray
    cup: np.ndarray

    @property
    def total(self):
        """Rim spanning the balls in series with the bearing, in parallel with the cup wall."""
        return 1.0 / (1.0 / self.rim + 1.0 / self.bearing) + self.cup


def radial_support(g: FlexsplineGeometry, wg: WaveGenerator) -> RadialSupport:
    """The three radial supports of the teeth for geometry ``g`` (docs/physics.md §3.5)."""
    zone_arc = wg.engagement_fraction * 2.0 * np.pi * g.R_rim
    pitch = wg.ball_pitch(g.R_i)
    if np.any(wg.support_width >= pitch):
        raise InputError(f"wave_generator.support_width ({np.max(wg.support_width) * 1e3:.4g} mm) must be "
                         f"shorter than the ball pitch along the bore ({np.min(pitch) * 1e3:.4g} mm)")
    rim = cc.rim_between_balls_stiffness(g.h_pz, g.face_width, g.E, g.nu, pitch, wg.support_width, zone_arc)
    return RadialSupport(zone_arc=zone_arc, ball_pitch=pitch, rim=rim,
                         bearing=np.asarray(wg.k_bearing, dtype=float),
                         cup=cc.shell_edge_radial_stiffness(g.R_c, g.h_c, g.E, g.nu, zone_arc))


def compliance_chain(g: FlexsplineGeometry, wg: WaveGenerator, kappa_mesh=1.0) -> ComplianceChain:
    """The series chain of closed forms for geometry ``g`` (see `hdsim.physics.compliance`)."""
    G = g.G
    fillet_wall = 0.5 * (g.t_d + g.h_c)
    undercut_wall = g.h_pz - g.h_p
    return ComplianceChain(
        diaphragm=cc.annular_diaphragm(g.r_hub, g.R_c - g.R_k, g.t_d, G),
        end_radius=cc.toroidal_fillet(g.R_k, g.R_c, fillet_wall, G),
        cylinder=cc.thin_tube(g.cylinder_length, g.R_c, g.h_c, G),
        lead_radius=cc.wall_transition(g.R_v, g.R_i, g.h_c, g.h_pz, G),
        undercut=cc.thin_tube(g.undercut_width, g.R_i + 0.5 * undercut_wall, undercut_wall, G),
        # torque enters the rim evenly over the face width: effective length b/2
        rim=cc.thin_tube(0.5 * g.face_width, g.R_rim, g.h_pz, G),
        mesh_zone=kappa_mesh * cc.mesh_zone(radial_support(g, wg).total, g.pitch_radius, g.pressure_angle),
    )


@functools.lru_cache(maxsize=None)
def _dotted_names(parts: tuple) -> frozenset:
    """The dotted parameter names of holders ``((prefix, class), …)``: a class's numeric
    fields are the same for every instance, and a fit asks at every pass."""
    return frozenset(f"{prefix}.{name}" for prefix, cls in parts for name in numeric_fields(cls))


_COMPONENTS = {"flexspline": "geometry", "wave_generator": "wave_generator", "drive": "drive",
               "calibration": "calibration", "input_friction": "input_friction"}


@dataclass(frozen=True, eq=False)
class HarmonicDrive:
    """A harmonic drive: named unit, geometry, calibration, inertias, effect slots and input friction.

    ``input_friction`` is the running-torque law of the wave-generator shaft
    (`hdsim.model.input_friction.InputFriction`), which the driven bench runs; left out, it
    is the catalog law of the unit (`hdsim.model.input_friction.catalog_friction`).
    """

    name: str
    geometry: FlexsplineGeometry
    wave_generator: WaveGenerator
    drive: DriveData
    calibration: Calibration
    hardening: fx.Effect = field(default_factory=lambda: fx.NO_EFFECT["hardening"])
    backlash: fx.Effect = field(default_factory=lambda: fx.NO_EFFECT["backlash"])
    friction: fx.Effect = field(default_factory=lambda: fx.NO_EFFECT["friction"])
    damping: fx.Effect = field(default_factory=lambda: fx.NO_EFFECT["damping"])
    kinematic_error: fx.Effect = field(default_factory=lambda: fx.NO_EFFECT["kinematic_error"])
    provenance: dict = field(default_factory=dict)
    input_friction: InputFriction | None = None

    def __post_init__(self):
        for slot in SLOTS:
            effect = getattr(self, slot)
            if not isinstance(effect, fx.Effect) or effect.family != slot:
                raise InputError(f"slot {slot} holds {type(effect).__name__}, not a {slot} effect")
        if self.input_friction is None:
            # frozen: the default depends on the unit's name and rating, so it is set here once
            object.__setattr__(self, "input_friction", catalog_friction(self))
        elif not isinstance(self.input_friction, InputFriction):
            raise InputError(f"input_friction holds {type(self.input_friction).__name__}, not an InputFriction")

    # ----------------------------------------------------------- compliance
    def compliance(self) -> ComplianceChain:
        """The series chain of compliances [rad/(N·m)] of this geometry, calibrated."""
        return compliance_chain(self.geometry, self.wave_generator, self.calibration.kappa_mesh)

    def split(self):
        """(structural, mesh-zone) compliance [rad/(N·m)] as used by the hardening law."""
        chain = self.compliance()
        return chain.structure, chain.mesh_zone

    @property
    def base_stiffness(self):
        """Low-torque stiffness of the elastic path, 1/C_total [N·m/rad]."""
        return 1.0 / self.compliance().total

    # ----------------------------------------------------------- effects
    def effects(self) -> dict[str, fx.Effect]:
        """The five slots, family name to effect."""
        return {slot: getattr(self, slot) for slot in SLOTS}

    def require_consistent(self) -> "HarmonicDrive":
        """This drive, or InputError naming the first effect whose values contradict each other
        (`Effect.inconsistency`, element by element in a batch): the one check of the values a
        user gives, made where they reach a run (``--set``, a study's rows, `run_scenario`)
        rather than in `with_updates`, through which a fit's trial models pass."""
        for effect in self.effects().values():
            reason = effect.inconsistency()
            if reason:
                raise InputError(reason)
        return self

    def active_families(self) -> list[str]:
        """Families whose slot holds an effect other than "none"."""
        return [slot for slot in SLOTS if not getattr(self, slot).is_null]

    def with_effects(self, **slots) -> "HarmonicDrive":
        """A new model with slots replaced, e.g. ``with_effects(backlash=DeadZoneBacklash(gap=1e-4))``."""
        for slot in slots:
            if slot not in SLOTS:
                raise unknown_name("effect family", slot, SLOTS)
        return replace(self, **slots)

    def without(self, *families) -> "HarmonicDrive":
        """A new model with the named families switched to their "no effect"."""
        for family in families:
            if family not in fx.NO_EFFECT:
                raise unknown_name("effect family", family, fx.NO_EFFECT)
        return self.with_effects(**{f: fx.NO_EFFECT[f] for f in families})

    def with_input_friction(self, law: InputFriction) -> "HarmonicDrive":
        """A new model whose wave-generator shaft runs ``law`` (on the input shaft, [N·m])."""
        if not isinstance(law, InputFriction):
            raise InputError(f"input_friction must be an InputFriction, got {type(law).__name__}")
        return replace(self, input_friction=law)

    # ----------------------------------------------------------- parameters
    def _parts(self) -> dict[str, object]:
        """Every parameter holder by the prefix of its dotted names."""
        parts = {prefix: getattr(self, attr) for prefix, attr in _COMPONENTS.items()}
        parts.update(self.effects())
        return parts

    def params(self) -> dict[str, float]:
        """Every numeric parameter by dotted name."""
        return {f"{prefix}.{name}": getattr(part, name) for prefix, part in self._parts().items()
                for name in numeric_fields(type(part))}

    def param_info(self, name: str) -> dict:
        """Metadata of one dotted parameter: ``doc``, ``unit`` and, where known, ``bounds``."""
        prefix, _, attr = name.partition(".")
        part = self._parts().get(prefix)
        for f in fields(part) if part is not None else ():
            if f.name == attr and f.metadata:
                return dict(f.metadata)
        raise unknown_name("parameter", name, self.params())

    def with_updates(self, updates: dict) -> "HarmonicDrive":
        """A new model with ``{dotted name: value}`` changed.

        Each value is a number or a 1-D array of numbers (a batch of models, one per
        element); a string, even one that reads as a number, is refused: the CLI parses
        ``--set`` text itself. Values that contradict each other (a three-segment law's
        T1 at or above T2) build, since a fit's trial models pass through them; running
        the model refuses them (`require_consistent`).

        Raises
        ------
        InputError
            On an unknown name, a value that is not a number or 1-D array of numbers
            (naming the parameter and the value's type), a value outside its bounds, or
            batch arrays of different lengths.
        """
        if not isinstance(updates, Mapping):
            raise InputError(f"updates are a dict of dotted names and values, e.g. {{'flexspline.h_c': 6e-4}}, "
                             f"got {type(updates).__name__}")
        known = _dotted_names(tuple((prefix, type(part)) for prefix, part in self._parts().items()))
        grouped: dict[str, dict] = {}
        for name, value in updates.items():
            if name not in known:
                raise unknown_name("parameter", name, self.params())
            prefix, _, attr = name.partition(".")
            numbers = as_numbers(name, value)  # a string or a bool is refused here, by its name and type
            if isinstance(value, (list, tuple, np.ndarray)):  # a batch: the parameter holders compute on arrays
                value = numbers
                if value.size == 0:
                    raise InputError(f"{name} is an empty array; expected a number or a 1-D array of values")
            grouped.setdefault(prefix, {})[attr] = value
        changes = {}
        for prefix, values in grouped.items():
            attr = _COMPONENTS.get(prefix, prefix)
            changes[attr] = replace(getattr(self, attr), **values)
        model = replace(self, **changes)
        model.batch_size  # arrays of different lengths are refused here, with their names' lengths
        return model

    @functools.cached_property  # frozen: an optimiser's pass asks a model for it several times
    def batch_size(self) -> int:
        """1 for a single model, else the common length of its array parameters."""
        sizes = {1 if type(v) is float else np.size(v) for v in self.params().values()}
        sizes.discard(1)
        if len(sizes) > 1:
            raise InputError(f"batch parameters have different lengths {sorted(sizes)}")
        return sizes.pop() if sizes else 1
