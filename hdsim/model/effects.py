"""Effect slots: one family each (contracts.md §2), each with an explicit "no effect".

Effects are frozen dataclasses that hold parameters only; the laws they use are
the pure functions in `hdsim.physics`. A field may be a float or an array of
equal length across the model (a batch of parameter sets evaluated at once).
Effects with memory declare ``state_names``; their memory lives in the ODE state
vector and is passed in and out, never stored on the object.

The elastic path of the drive, seen from the output, is::

    output ── [backlash dead zone] ── [body: spring (base compliance + hardening)
              ∥ damper ∥ body friction] ── [hysteretic compliance (series friction)]
              ── mesh (fixed by the wave generator),  + parallel friction torques

Everything here is in SI: torque [N·m], twist [rad], time [s].
"""

from __future__ import annotations

from dataclasses import MISSING, dataclass, field, fields
from typing import ClassVar

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.physics import backlash as bl
from hdsim.physics import damping as dp
from hdsim.physics import friction as fr
from hdsim.physics import kinematic_error as ke
from hdsim.physics import stiffness as st


def param(doc: str, unit: str, lower: float = 0.0, upper: float = np.inf, positive: bool = False,
          default=MISSING):
    """A numeric effect parameter with its unit and physical bounds (for fits and checks).

    A ``default`` makes the parameter optional in scenario and fitted-model files.
    """
    return field(default=default,
                 metadata={"doc": doc, "unit": unit, "bounds": (lower, upper), "positive": positive})


class Parameters:
    """Base of every parameter holder (effects, wave generator, drive data, calibration):
    bound checks on construction and the listing of fields with their metadata."""

    #: dotted-name prefix used in messages (``drive``, ``wave_generator`` …)
    prefix: ClassVar[str] = ""

    def __post_init__(self):
        for f in fields(self):
            value = np.asarray(getattr(self, f.name), dtype=float)
            lower, upper = f.metadata["bounds"]
            bad = ~np.isfinite(value) | (value < lower) | (value > upper)
            if f.metadata["positive"]:
                bad |= value <= 0.0
            if np.any(bad):
                raise InputError(
                    f"{self.prefix}.{f.name} = {np.atleast_1d(value)[np.argmax(np.atleast_1d(bad))]:g} "
                    f"is outside [{lower:g}, {upper:g}] {f.metadata['unit']}")

    def params(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def param_meta(cls) -> dict:
        return {f.name: dict(f.metadata) for f in fields(cls)}


class Effect(Parameters):
    """Base of all effects: one family each, with the states its memory needs."""

    family: ClassVar[str] = ""
    id: ClassVar[str] = ""
    state_names: ClassVar[tuple[str, ...]] = ()
    #: unit of each state, "rad" or "N·m": sets the solver's absolute tolerance
    state_unit: ClassVar[str] = "rad"

    @property
    def prefix(self) -> str:
        return self.family


# --------------------------------------------------------------------------- hardening
@dataclass(frozen=True, eq=False)
class NoHardening(Effect):
    """Linear stiffness: the base compliance alone, ``T = K δ``."""

    family: ClassVar[str] = "hardening"
    id: ClassVar[str] = "none"

    def torque(self, twist, c_struct, c_mesh):
        return twist / (c_struct + c_mesh)

    def tangent(self, twist, c_struct, c_mesh):
        return np.broadcast_to(1.0 / (c_struct + c_mesh), np.shape(twist))


@dataclass(frozen=True, eq=False)
class ThreeSegmentHardening(Effect):
    """Catalog three-segment law; more teeth share the load above T1 and T2.

    The mesh-zone compliance is divided by the engagement ratio ``e2`` between T1
    and T2 and by ``e3`` above T2 (``e = 1`` below T1); the structural compliance is
    unchanged. K_i = 1 / (C_struct + C_mesh / e_i).
    """

    family: ClassVar[str] = "hardening"
    id: ClassVar[str] = "three_segment"
    T1: float = param("first breakpoint torque", "N·m", positive=True)
    T2: float = param("second breakpoint torque", "N·m", positive=True)
    e2: float = param("engagement ratio between T1 and T2", "-", 1.0, 100.0)
    e3: float = param("engagement ratio above T2", "-", 1.0, 100.0)
    #: knee rounding as a fraction of the twist at T1: small enough that the fitted
    #: K1..K3 move by < 0.5 %, large enough that implicit solvers step over the knees
    knee_rounding: ClassVar[float] = 0.03

    def stiffnesses(self, c_struct, c_mesh):
        return (1.0 / (c_struct + c_mesh), 1.0 / (c_struct + c_mesh / self.e2),
                1.0 / (c_struct + c_mesh / self.e3))

    def _args(self, c_struct, c_mesh):
        K = self.stiffnesses(c_struct, c_mesh)
        return (self.T1, self.T2, *K, self.knee_rounding * self.T1 / K[0])

    def torque(self, twist, c_struct, c_mesh):
        return st.smooth_three_segment_torque(twist, *self._args(c_struct, c_mesh))

    def tangent(self, twist, c_struct, c_mesh):
        return st.smooth_three_segment_tangent(twist, *self._args(c_struct, c_mesh))


@dataclass(frozen=True, eq=False)
class TanhHardening(Effect):
    """Smooth hardening: tangent stiffness from K0 to K∞ = 1/(C_struct + C_mesh/e_inf).

    The transition is centred on the twist reached at ``T_s`` under K0.
    """

    family: ClassVar[str] = "hardening"
    id: ClassVar[str] = "tanh"
    e_inf: float = param("engagement ratio at high load", "-", 1.0, 100.0)
    T_s: float = param("transition torque", "N·m", positive=True)

    def _k(self, c_struct, c_mesh):
        k0 = 1.0 / (c_struct + c_mesh)
        return k0, 1.0 / (c_struct + c_mesh / self.e_inf), self.T_s / k0

    def torque(self, twist, c_struct, c_mesh):
        return st.tanh_hardening_torque(twist, *self._k(c_struct, c_mesh))

    def tangent(self, twist, c_struct, c_mesh):
        return st.tanh_hardening_tangent(twist, *self._k(c_struct, c_mesh))


# --------------------------------------------------------------------------- backlash
@dataclass(frozen=True, eq=False)
class NoBacklash(Effect):
    """No dead zone."""

    family: ClassVar[str] = "backlash"
    id: ClassVar[str] = "none"

    def engage(self, twist):
        """(twist seen by the spring, contact factor 0…1) for a twist across the dead zone."""
        return twist, 1.0

    def contact_torque(self, spring_torque, damping_torque):
        return spring_torque + damping_torque


@dataclass(frozen=True, eq=False)
class DeadZoneBacklash(Effect):
    """Dead zone of total width ``gap`` seen at the output (seed paper eq. 2, b = 2 b_s).

    The corners are rounded over ``contact_rounding·gap``, so an implicit solver crosses
    the gap without chattering. With series or parallel friction the contact follows a
    smooth form of the Modelica ElastoBacklash law (the damping never pulls, torque is
    continuous at contact onset); with body friction or none, a damped body sits in
    series with the dead zone and keeps its own twist (`hdsim.simulation.path.ElasticPath`).
    """

    family: ClassVar[str] = "backlash"
    id: ClassVar[str] = "dead_zone"
    gap: float = param("total backlash at the output", "rad", 0.0, 0.05)
    #: contact rounding as a fraction of the gap: 0.2 halves the solver's work at
    #: each crossing against 0.05 and moves the ±4 % lost motion by < 0.1 %
    contact_rounding: ClassVar[float] = 0.2

    def engage(self, twist):
        width = self.contact_rounding * self.gap + 1e-12
        half = 0.5 * self.gap
        return bl.smooth_dead_zone(twist, half, width), bl.smooth_contact(twist, half, width)

    def contact_torque(self, spring_torque, damping_torque):
        return bl.smooth_elasto_backlash_torque(spring_torque, damping_torque)


# --------------------------------------------------------------------------- friction
@dataclass(frozen=True, eq=False)
class NoFriction(Effect):
    """No hysteretic loss."""

    family: ClassVar[str] = "friction"
    id: ClassVar[str] = "none"
    #: "series" effects add a hysteretic twist to the elastic path, "parallel" ones a
    #: torque across the whole path (dead zone included, like a bearing), "body" ones a
    #: torque across the spring only, behind the dead zone. Their states are laid out
    #: after the mechanical states.
    kind: ClassVar[str] = "none"

    def series_rates(self, states, twist_rate, tangent, elastic_torque):
        return ()

    def series_twist(self, states):
        return 0.0

    def parallel_torque(self, states, twist_rate):
        return 0.0

    def parallel_rates(self, states, twist_rate):
        return ()


@dataclass(frozen=True, eq=False)
class DahlSlip(NoFriction):
    """Micro-slip in the mesh: a Dahl-friction slider with end stops in series with the spring.

    Sticks until the torque nears ``slip_torque``, then slides up to ``±slip_max``. A
    cycle beyond the slip torque gains ``2·slip_max`` of width at zero torque
    (hysteresis loss); a smaller one stays elastic (docs/physics.md).
    """

    id: ClassVar[str] = "dahl_slip"
    kind: ClassVar[str] = "series"
    state_names: ClassVar[tuple[str, ...]] = ("slip",)
    slip_torque: float = param("torque at which the slider slides", "N·m", positive=True)
    slip_max: float = param("slip range to each stop", "rad", 0.0, 0.05, positive=True)
    #: stick and stop stiffness relative to slip torque / slip range: stiff enough that
    #: sticking adds < 1 % compliance, soft enough to stay well-conditioned
    stiffness_ratio: ClassVar[float] = 200.0
    #: direction switch smoothing [rad/s]: ~1e-3 of the twist rate of a catalog test
    velocity_scale: ClassVar[float] = 1e-6

    def series_twist(self, states):
        return np.asarray(states)[0]

    def series_rates(self, states, twist_rate, tangent, elastic_torque):
        states = np.asarray(states)
        torque = np.asarray(self.slip_torque)[None]
        reach = np.asarray(self.slip_max)[None]
        stiffness = self.stiffness_ratio * torque / reach
        return tuple(fr.dahl_slip_rates(states, twist_rate, tangent, elastic_torque, torque, reach,
                                        stiffness, 0.02 * reach, self.velocity_scale))


@dataclass(frozen=True, eq=False)
class DahlFriction(NoFriction):
    """Dahl friction in the flexspline body, behind the dead zone (Dahl, 1968), state z [N·m].

    The body is the spring ∥ this friction ∥ the damper; the dead zone (the Oldham
    coupling and tooth play) sits in series with it. So the backlash step lies at zero
    torque and an unloaded body keeps the twist its friction holds (``u(e) = −z``)
    while the output crosses the gap (docs/physics.md, "friction in the body").
    Without backlash this is exactly a Dahl torque in parallel with the spring.
    """

    id: ClassVar[str] = "dahl"
    kind: ClassVar[str] = "body"
    state_names: ClassVar[tuple[str, ...]] = ("torque",)
    state_unit: ClassVar[str] = "N·m"
    torque_max: float = param("Coulomb (saturation) torque", "N·m", positive=True)
    sigma: float = param("initial (sticking) stiffness", "N·m/rad", positive=True)

    def body_slope(self, state, body_rate):
        """dz/de [N·m/rad]: Dahl's slope for the direction of the body's motion."""
        return fr.dahl_slope(state, np.sign(body_rate), self.sigma, self.torque_max)


@dataclass(frozen=True, eq=False)
class CoulombFriction(NoFriction):
    """Smoothed Coulomb torque in parallel with the drive (e.g. output bearing)."""

    id: ClassVar[str] = "coulomb"
    kind: ClassVar[str] = "parallel"
    torque: float = param("Coulomb torque", "N·m", 0.0, 1e5)
    velocity_scale: float = param("tanh smoothing velocity", "rad/s", 0.0, 1.0, positive=True)

    def parallel_torque(self, states, twist_rate):
        return fr.smooth_coulomb(twist_rate, self.torque, self.velocity_scale)


@dataclass(frozen=True, eq=False)
class MaxwellSlip(NoFriction):
    """Maxwell-slip elements in parallel with the spring (Tjahjowidodo et al., 2013).

    ``n`` elements of equal stiffness ``k_total/n`` and slip torques rising linearly
    to ``slip_torque_max``: a loop whose width grows with amplitude, as in HD tests.
    """

    id: ClassVar[str] = "maxwell_slip"
    kind: ClassVar[str] = "parallel"
    n_elements: ClassVar[int] = 4
    state_names: ClassVar[tuple[str, ...]] = tuple(f"slip_{i}" for i in range(4))
    k_total: float = param("total element stiffness", "N·m/rad", positive=True)
    slip_torque_max: float = param("largest element slip torque", "N·m", positive=True)
    velocity_scale: float = param("direction switch smoothing", "rad/s", 0.0, 1.0, positive=True)

    def _elements(self, states):
        """Element stiffnesses and slip torques shaped to broadcast against ``states``
        (element axis first, sample axis last)."""
        n = self.n_elements
        shape = (n,) + (1,) * (np.ndim(states) - 2) + (-1,)
        k = (np.ones(n)[:, None] * np.atleast_1d(self.k_total) / n).reshape(shape)
        f = (np.arange(1, n + 1)[:, None] / n * np.atleast_1d(self.slip_torque_max)).reshape(shape)
        return k, f

    def parallel_torque(self, states, twist_rate):
        states = np.asarray(states)
        k, _ = self._elements(states)
        return fr.maxwell_slip_torque(states, k)

    def parallel_rates(self, states, twist_rate):
        states = np.asarray(states)
        k, f = self._elements(states)
        return tuple(fr.maxwell_slip_rates(states, twist_rate, k, f, self.velocity_scale))


# --------------------------------------------------------------------------- damping
@dataclass(frozen=True, eq=False)
class NoDamping(Effect):
    """No rate-dependent loss."""

    family: ClassVar[str] = "damping"
    id: ClassVar[str] = "none"
    coefficient = 0.0
    stiffness_share = 0.0

    def coefficient_at(self, tangent_ratio):
        return 0.0


@dataclass(frozen=True, eq=False)
class ViscousDamping(Effect):
    """Viscous (Kelvin–Voigt) damping across the spring, ``τ = c(δ) δ̇``.

    ``c(δ) = c₀ [(1 − s) + s K_t(δ)/K₀]`` (`hdsim.physics.damping.load_dependent_coefficient`):
    the share ``s`` of the damping follows the tangent stiffness, as the damping of the
    tooth contacts does when more teeth come into mesh (stiffness-proportional, Rayleigh
    damping), the rest (lubricant shear, cylinder material) stays constant. Without
    hardening, or with ``s = 0``, it is a constant coefficient ``c₀``.
    """

    family: ClassVar[str] = "damping"
    id: ClassVar[str] = "viscous"
    coefficient: float = param("viscous coefficient at zero twist", "N·m·s/rad", 0.0, 1e6)
    stiffness_share: float = param("share of the coefficient proportional to the tangent stiffness",
                                   "-", 0.0, 1.0, default=0.0)

    def coefficient_at(self, tangent_ratio):
        """Damping coefficient [N·m·s/rad] where the tangent stiffness is ``tangent_ratio·K₀``."""
        return dp.load_dependent_coefficient(self.coefficient, self.stiffness_share, tangent_ratio)


# --------------------------------------------------------------------------- kinematic error
@dataclass(frozen=True, eq=False)
class NoKinematicError(Effect):
    """Perfect kinematics: θ_out = θ_WG / N."""

    family: ClassVar[str] = "kinematic_error"
    id: ClassVar[str] = "none"

    def displacement(self, wg_angle, output_angle, load_fraction):
        return 0.0


@dataclass(frozen=True, eq=False)
class FourierKinematicError(Effect):
    """Kinematic error harmonics at 1×, 2×, 4× the wave-generator angle and 1× output.

    Amplitudes scale with ``1 + load_gain·|T|/T_N`` (Ghorbel et al., 2001, observed
    KE varying with load).
    """

    family: ClassVar[str] = "kinematic_error"
    id: ClassVar[str] = "fourier"
    a1: float = param("1× WG amplitude", "rad", 0.0, 0.01)
    a2: float = param("2× WG amplitude", "rad", 0.0, 0.01)
    a4: float = param("4× WG amplitude", "rad", 0.0, 0.01)
    p1: float = param("1× WG phase", "rad", -10.0, 10.0)
    p2: float = param("2× WG phase", "rad", -10.0, 10.0)
    p4: float = param("4× WG phase", "rad", -10.0, 10.0)
    a_out: float = param("1× output amplitude (eccentricity)", "rad", 0.0, 0.01)
    p_out: float = param("1× output phase", "rad", -10.0, 10.0)
    load_gain: float = param("relative amplitude change at rated torque", "-", -1.0, 10.0)

    def displacement(self, wg_angle, output_angle, load_fraction):
        scale = 1.0 + self.load_gain * np.abs(load_fraction)
        return scale * ke.fourier_kinematic_error(
            wg_angle, output_angle, (1, 2, 4), (self.a1, self.a2, self.a4), (self.p1, self.p2, self.p4),
            (1,), (self.a_out,), (self.p_out,))


# --------------------------------------------------------------------------- registry
FAMILIES: dict[str, dict[str, type[Effect]]] = {}
for _cls in (NoHardening, ThreeSegmentHardening, TanhHardening, NoBacklash, DeadZoneBacklash,
             NoFriction, DahlSlip, DahlFriction, CoulombFriction, MaxwellSlip, NoDamping, ViscousDamping,
             NoKinematicError, FourierKinematicError):
    FAMILIES.setdefault(_cls.family, {})[_cls.id] = _cls

NO_EFFECT = {family: classes["none"]() for family, classes in FAMILIES.items()}


def effect_class(family: str, effect_id: str) -> type[Effect]:
    if family not in FAMILIES:
        raise unknown_name("effect family", family, FAMILIES)
    if effect_id not in FAMILIES[family]:
        raise unknown_name(f"{family} effect", effect_id, FAMILIES[family])
    return FAMILIES[family][effect_id]


def make_effect(family: str, effect_id: str, **values) -> Effect:
    cls = effect_class(family, effect_id)
    known = {f.name for f in fields(cls)}
    for name in values:
        if name not in known:
            raise unknown_name(f"parameter of {family}.{effect_id}", name, known or {"(none)"})
    missing = {f.name for f in fields(cls) if f.default is MISSING} - set(values)
    if missing:
        raise InputError(f"{family}.{effect_id} needs {', '.join(sorted(missing))}")
    return cls(**values)
