"""Backlash family: the dead zone in series with the flexspline body.

The dead zone (Oldham coupling, tooth play) sits between the output and the body
for every friction law (docs/physics.md, "one arrangement")::

    output ── dead zone ── body [spring with its friction ∥ damper] ── mesh

The backlash effect carries this series connection: given the output twist and
rate it finds the body twist and rate and the torque through the path
(`Backlash.transmit`). Without a gap the body follows the output; with one, the
dead zone transmits ``T = K₀·dz(v)`` with ``v`` its closure state, and the body
relaxes on its own while the output crosses the gap.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import ClassVar, Protocol

import numpy as np

from hdsim.model.effects.base import Effect, FitContext, FreeParameter, parameter_rows
from hdsim.model.parameters import param
from hdsim.physics import backlash as bl


class Body(Protocol):
    """What the dead zone needs from the body behind it (built by the elastic path)."""

    base_stiffness: object  # K₀ [N·m/rad]

    def static(self, body_twist):
        """(torque without the damper [N·m], spring torque [N·m], spring tangent [N·m/rad])."""

    def coefficient(self, body_twist, spring_tangent):
        """Damping coefficient of the body [N·m·s/rad]."""

    def path_tangent(self, direction, spring_torque, spring_tangent):
        """dB/de of the body moving in ``direction`` (±1) [N·m/rad], damper excluded."""


class Backlash(Effect):
    """Base of the backlash family; the "no effect" behaviour is a rigid connection."""

    family: ClassVar[str] = "backlash"
    separated_by: ClassVar[Mapping[str, str]] = MappingProxyType({
        "friction": "a small-amplitude cycle (±4 % T_N lost-motion test): backlash is a step of fixed width "
                    "at zero torque, a friction loop shrinks with the amplitude",
        "hardening": "a cycle to a larger torque and a small-amplitude cycle: hardening bends the curve at "
                     "high load, backlash acts only at zero torque",
    })

    def engage(self, twist):
        """(twist passed on by the dead zone [rad], contact factor 0…1)."""
        return twist, 1.0

    def transmit(self, twist, twist_rate, states, body: Body):
        """Torque through the path and the body's motion for output twist and rate.

        Returns
        -------
        tuple
            ``(torque [N·m], body twist [rad], body rate [rad/s], spring torque [N·m],
            spring tangent [N·m/rad], rates of this effect's states)``.
        """
        total, spring_torque, tangent = body.static(twist)
        torque = total + body.coefficient(twist, tangent) * twist_rate
        return torque, twist, twist_rate, spring_torque, tangent, ()

    def twist_at_torque(self, torque, base_stiffness):
        """Quasi-static angle [rad] the dead zone takes while it carries ``torque``."""
        return 0.0

    def stored_energy(self, states, base_stiffness):
        """Energy [J] stored in this effect's contact compliance."""
        return 0.0

    def settle(self, twist, states, body: Body):
        """This effect's states in balance with the body at output twist ``twist`` (an
        initial condition that transmits what the body carries)."""
        return np.asarray(states, dtype=float)


@dataclass(frozen=True, eq=False)
class NoBacklash(Backlash):
    """No dead zone: the body twists with the output."""

    id: ClassVar[str] = "none"
    is_null: ClassVar[bool] = True

    def compiled(self, size, c_struct, c_mesh):
        if not self.keeps_law_of(NoBacklash, ("twist_at_torque",)):
            return None
        from hdsim.model.effects import kernels
        return (kernels.no_gap_twist,), parameter_rows(size)


@dataclass(frozen=True, eq=False)
class DeadZoneBacklash(Backlash):
    """Dead zone of total width ``gap`` seen at the output (seed paper eq. 2, b = 2 b_s).

    The corners are rounded over ``contact_rounding·gap``, so an implicit solver crosses
    the gap without chattering. The dead zone carries the body's torque in series:
    ``T = K₀·dz(v)``, its angle ``g = v − (1 − ε)·dz(v)`` grows with ``T``, the body twist
    is ``e = x − g`` and obeys ``c(e) ė = T − B(e, s)`` (docs/physics.md). From
    ``ẋ = ė + g'(v) v̇``: ``v̇ = (ẋ − ė)/(1 − (1 − ε)κ)`` with ``κ`` the contact factor.
    A body without a damper holds ``T = B(e, s)`` at all times; differentiating it,
    ``K₀κ v̇ = D ė`` with ``D`` the body's path tangent, gives
    ``v̇ = D ẋ/(K₀κ + D g')``: no dissipation is added, so an undamped drive conserves
    energy. Quasi-statically the angle is ``g(T) = dz⁻¹(T/K₀) − T/K₀``.
    """

    id: ClassVar[str] = "dead_zone"
    other_forms: ClassVar[tuple[str, ...]] = ("gradual_dead_zone",)
    state_names: ClassVar[tuple[str, ...]] = ("closure",)
    gap: float = param("total backlash at the output", "rad", 0.0, 0.05)
    #: contact rounding as a fraction of the gap: 0.2 halves the solver's work at
    #: each crossing against 0.05 and moves the ±4 % lost motion by < 0.1 %
    contact_rounding: ClassVar[float] = 0.2
    #: contact compliance ε as a share of 1/K₀: keeps the closure equation regular in
    #: contact and adds ε·T/K₀ of twist, 3e-8 rad at rated torque, far below encoders
    contact_compliance_share: ClassVar[float] = 1e-5
    #: time constant [s] with which an undamped body is pulled back onto its torque
    #: balance when round-off drifts it off: far slower than any step the solver takes
    #: near contact, far faster than a test
    stabilisation_time: ClassVar[float] = 1e-3

    def _width(self):
        return _rounding_width(self.contact_rounding, self.gap)

    def engage(self, twist):
        width = self._width()
        half = 0.5 * self.gap
        return bl.smooth_dead_zone(twist, half, width), bl.smooth_contact(twist, half, width)

    def transmit(self, twist, twist_rate, states, body: Body):
        k0 = body.base_stiffness
        eps = self.contact_compliance_share
        closure = states[0]
        closed, contact = self.engage(closure)
        torque = k0 * closed
        body_twist = twist - (closure - (1.0 - eps) * closed)
        total, spring_torque, tangent = body.static(body_twist)
        c = body.coefficient(body_twist, tangent)
        slope = 1.0 - (1.0 - eps) * contact  # g'(v)
        # a single model's damped body as Python floats: numpy costs ~10x on a float
        scalar = isinstance(c, float) and isinstance(contact, float) and c > 0.0
        damped = True if scalar else np.greater(c, 0.0)
        # damped body: it relaxes towards the torque the dead zone passes on
        body_rate = (torque - total) / (c if scalar or damped is np.True_ else np.where(damped, c, 1.0))
        closure_rate = (twist_rate - body_rate) / slope
        # Deep in contact the body twists with the output; its relaxation rate equals ẋ up
        # to a transient of time constant c·ε/K₀ (a fraction of a nanosecond). There the
        # friction law is given the rate of that slow manifold, ẋ: its direction switch
        # then does not ride on the transient, which otherwise cost the implicit solver
        # twenty times the Jacobians on a driven run. The weight rises from 0 to 1 while
        # the contact factor goes from 0.99 to 0.999, so in the gap and in the rounded
        # corner the body's own rate counts (docs/physics.md §6.2).
        ramp = (contact - 0.99) / 0.009
        weight = min(max(ramp, 0.0), 1.0) if scalar else np.minimum(np.maximum(ramp, 0.0), 1.0)  # np.clip's cost / 3
        weight = weight * weight * (3.0 - 2.0 * weight)
        body_rate = weight * twist_rate + (1.0 - weight) * body_rate
        if not (scalar or damped.all()):
            # undamped body: the balance T = B holds; its time derivative fixes the rates, and
            # a slow pull (stabilisation_time) keeps round-off from drifting off the balance
            direction = np.where(np.asarray(twist_rate) >= 0.0, 1.0, -1.0)
            D = body.path_tangent(direction, spring_torque, tangent)
            held = (D * twist_rate + (total - torque) / self.stabilisation_time) / (k0 * contact + D * slope)
            closure_rate = np.where(damped, closure_rate, held)
            body_rate = np.where(damped, body_rate, twist_rate - slope * held)
        return torque, body_twist, body_rate, spring_torque, tangent, (closure_rate,)

    def settle(self, twist, states, body: Body, iterations: int = 50):
        # Newton on K₀·dz(v) = B(x − g(v)), increasing in v
        k0 = body.base_stiffness
        eps = self.contact_compliance_share
        v = np.array(twist, dtype=float)
        for _ in range(iterations):
            closed, contact = self.engage(v)
            slope = 1.0 - (1.0 - eps) * contact
            total, u, k = body.static(twist - (v - (1.0 - eps) * closed))
            residual = k0 * closed - total
            step = residual / (k0 * contact + body.path_tangent(np.sign(residual), u, k) * slope)
            v = v - step
            if np.all(np.abs(step) <= 1e-15 + 1e-12 * np.abs(v)):
                break
        return v[None]

    def stored_energy(self, states, base_stiffness):
        # ∫ T dg = K₀ [∫₀^v dz − (1 − ε) dz(v)²/2]: the contact compliance ε/K₀ in contact
        v = np.asarray(states, dtype=float)[0]
        width = self._width()
        closed, _ = self.engage(v)
        return base_stiffness * (bl.smooth_dead_zone_integral(v, 0.5 * self.gap, width)
                                 - 0.5 * (1.0 - self.contact_compliance_share) * closed**2)

    def twist_at_torque(self, torque, base_stiffness):
        v = np.asarray(torque, dtype=float) / base_stiffness
        gap = np.asarray(self.gap, dtype=float)
        rounding = np.asarray(self.contact_rounding, dtype=float)
        if gap.ndim == 1 and v.ndim == 2:  # a batch (M,) against (M, samples)
            rounding = np.broadcast_to(rounding, gap.shape)
            # rows without a gap (the other rows of a diagnosis round) carry no twist in
            # it and skip the inverse, a pass over every sample
            out = np.zeros_like(v)
            open_ = gap > 0.0
            out[open_] = _twist_in_gap(v[open_], gap[open_, None], rounding[open_, None])
            return out
        return _twist_in_gap(v, gap, rounding)

    def compiled(self, size, c_struct, c_mesh):
        if not self.keeps_law_of(DeadZoneBacklash, ("twist_at_torque", "_width")):
            return None
        from hdsim.model.effects import kernels
        half, width = 0.5 * np.asarray(self.gap, dtype=float), self._width()
        return (kernels.dead_zone_gap_twist,), parameter_rows(size, half, width, np.exp(-half / width))

    def free_parameters(self, context: FitContext):
        return (FreeParameter("gap", 0.0, 0.05, float(np.clip(context.step, 2e-5, 1e-2))),)

    @classmethod
    def neutral(cls):
        return cls(gap=0.0)

    @classmethod
    def placeholder(cls, rated_torque, stiffness):
        return cls(gap=1e-4)


def _rounding_width(rounding, gap):
    """Rounding width of the corners [rad] (never zero: the softplus needs a scale)."""
    return rounding * gap + 1e-12


def _twist_in_gap(contact_twist, gap, rounding):
    """Angle of the dead zone [rad] that carries the twist ``contact_twist`` of its contact."""
    return bl.inverse_smooth_dead_zone(contact_twist, 0.5 * gap, _rounding_width(rounding, gap)) - contact_twist


@dataclass(frozen=True, eq=False)
class GradualDeadZone(DeadZoneBacklash):
    """A dead zone whose flanks meet gradually: the rounding of its corners is a parameter.

    The flanks of a real gap do not close at one torque: contact compliance, tooth
    profile errors and the load shared by more teeth make the gap close over a range of
    torque of about ``K₀·contact_rounding·gap``. `DeadZoneBacklash` fixes the rounding
    at 0.2 (a numerical aid); this form fits it, from nearly sharp (0.01) to a gap that
    closes over ten times its width.
    """

    id: ClassVar[str] = "gradual_dead_zone"
    other_forms: ClassVar[tuple[str, ...]] = ("dead_zone",)
    contact_rounding: float = param("width of the closing as a share of the gap", "-", 0.01, 10.0, default=0.2)

    def free_parameters(self, context: FitContext):
        lower, upper = self.param_meta()["contact_rounding"]["bounds"]
        return super().free_parameters(context) + (FreeParameter("contact_rounding", lower, upper, 0.5),)

    @classmethod
    def neutral(cls):
        return cls(gap=0.0)

    @classmethod
    def placeholder(cls, rated_torque, stiffness):
        return cls(gap=1e-4, contact_rounding=0.5)
