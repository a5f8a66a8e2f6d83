"""The families of a running-torque test, as terms of the one running-torque law.

A running-torque record (a friction sweep) is fitted with the law of
`hdsim.model.input_friction` (``InputFriction.torque``), which is linear in every
amplitude once the Stribeck speed is fixed. Each family switches on the amplitudes it
owns; each term carries its own behaviour (`RunningTerm.columns` and
`RunningTerm.write_back`), so the fit and the diagnosis never ask which term is which:

| family | term (id) | amplitudes | signature in a sweep |
|---|---|---|---|
| base (always) | ``coulomb`` | ``F_c`` | one level, the same at every speed and both directions |
| ``friction`` | ``stribeck`` | ``F_s − F_c`` (Stribeck rise at low speed, grid over ``ω_s``), ``Δ`` (forward ≠ reverse) | excess at low speed; a level that depends on the direction |
| ``damping`` | ``viscous`` | ``b`` | torque growing in proportion to speed |
| ``ripple`` | ``ripple`` | ``F_c r_k cos φ_k``, ``F_c r_k sin φ_k`` at orders 1, 2, 4 of the WG angle and 1 of the output | torque periodic in angle, reversing with the motion |
| ``ripple`` | ``position_torque`` | ``g_k cos ψ_k``, ``g_k sin ψ_k`` at the same orders, not signed by the motion | torque periodic in angle, the same both ways (cogging) |

The columns are the law itself evaluated with one amplitude set to 1 and the others to 0
(the law is linear in them), so the fitted model is exactly ``InputFriction.torque``
with the fitted values: there is no second copy of the law. The base also holds the
inertia of motor and WG, ``J α``, which shows in a torque taken from motor current
wherever the speed changes.

The mesh-loss coefficient ``μ`` of the law is not a term: in a sweep at one constant load
it is a constant added to ``F_c`` and cannot be told from it (docs/physics.md,
running torque).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import ClassVar

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.model.family import FamilyKnowledge
from hdsim.model.input_friction import InputFriction

__all__ = ["RunningTerm", "CoulombLevel", "StribeckFriction", "ViscousLoss", "PositionRipple", "PositionTorque",
           "RUNNING_FAMILIES", "RUNNING_FORMS", "BASE_TERM", "unit_law", "parse_running_effects", "parse_running_forms",
           "running_term",
           "register_running_term"]

#: orders of the WG angle the ripple term carries (the output's 1× is added as 1/N)
WG_RIPPLE_ORDERS = (1.0, 2.0, 4.0)


def unit_law(velocity_scale: float, stribeck_speed: float = 1.0, **amplitudes) -> InputFriction:
    """The law with every amplitude 0 except those given (a column of the fit).

    Parameters
    ----------
    velocity_scale : float
        ω_ε [rad/s] of the smooth sign.
    stribeck_speed : float
        ω_s [rad/s].
    **amplitudes
        ``InputFriction`` fields to set (``coulomb_torque``, ``starting_torque``, …).

    Returns
    -------
    InputFriction
        The law.
    """
    fields = dict(starting_torque=0.0, coulomb_torque=0.0, viscous=0.0, stribeck_speed=stribeck_speed,
                  velocity_scale=velocity_scale)
    fields.update(amplitudes)
    return InputFriction(**fields)


def _sign(speed, velocity_scale):
    """The law's smooth sign of the speed (a unit Coulomb level), for the other shapes."""
    return unit_law(velocity_scale, coulomb_torque=1.0, starting_torque=1.0).torque(speed, 0.0)


@dataclass(frozen=True)
class Columns:
    """Columns of one term: names, matrix (n, k) and the bounds of each amplitude."""

    names: tuple[str, ...]
    matrix: np.ndarray
    lower: tuple[float, ...]
    upper: tuple[float, ...]

    def without(self, dropped: tuple) -> Columns:
        """These columns without those named in ``dropped``."""
        keep = [j for j, n in enumerate(self.names) if n not in dropped]
        if len(keep) == len(self.names):
            return self
        return replace(self, names=tuple(self.names[j] for j in keep), matrix=self.matrix[:, keep],
                       lower=tuple(self.lower[j] for j in keep), upper=tuple(self.upper[j] for j in keep))


@dataclass(frozen=True)
class RunningTerm(FamilyKnowledge):
    """One family's part of the running-torque law, and what a diagnosis knows of the family."""

    family: ClassVar[str] = ""
    id: ClassVar[str] = ""
    #: what the term looks like in a sweep (for reports)
    signature: ClassVar[str] = ""
    #: the unit of a column's amplitude where it is not a torque [N·m] (for reports)
    column_units: ClassVar[Mapping[str, str]] = MappingProxyType({})
    #: amplitudes seen only as a difference between the directions: on a record that runs one
    #: way their columns are the level's, and the fit holds them at 0 (`write_back` reads them
    #: as 0 when absent)
    direction_columns: ClassVar[tuple[str, ...]] = ()

    def grid(self, speeds: np.ndarray) -> tuple[float, ...]:
        """Values of the term's non-linear parameter to try (``()``: none)."""
        return ()

    def columns(self, speed, angle, velocity_scale: float, ratio: float, nonlinear: float | None) -> Columns:
        """The law's columns for this term along the record."""
        raise NotImplementedError

    def write_back(self, law: InputFriction, coefficients: dict, nonlinear: float | None) -> InputFriction:
        """The law with this term's fitted amplitudes (``coefficients`` by column name)."""
        raise NotImplementedError

    def holds(self, law: InputFriction, coefficients: dict) -> bool:
        """True when `write_back` puts ``coefficients`` into ``law`` (the law with the terms
        before this one written back) exactly. The columns span amplitudes the law may not
        hold (a ripple on a level of 0); the fit then keeps a solution that it does hold
        (`hdsim.identification.running_fit.fit_running`). Default: always."""
        return True

    def other_shapes(self, speed, angle, velocity_scale: float, ratio: float, nonlinear) -> Columns | None:
        """Shapes of the same family that the law's form lacks (None: none).

        Not part of the law: a diagnosis lets a family already in the model take these
        too before it credits a new family with what is left, so that a family is not
        added only because another family's form is imperfect (docs/physics.md, running
        torque; `hdsim.identification.running_diagnosis`).
        """
        return None


@dataclass(frozen=True)
class CoulombLevel(RunningTerm):
    """Base: one Coulomb level ``F_c``, the same both ways and at every speed."""

    family: ClassVar[str] = "base"
    id: ClassVar[str] = "coulomb"
    signature: ClassVar[str] = "one level at every speed, both directions"

    def columns(self, speed, angle, velocity_scale, ratio, nonlinear):
        law = unit_law(velocity_scale, coulomb_torque=1.0, starting_torque=1.0)
        return Columns(("coulomb_torque",), law.torque(speed, angle)[:, None], (0.0,), (math.inf,))

    def write_back(self, law, coefficients, nonlinear):
        level = float(coefficients["coulomb_torque"])
        return replace(law, coulomb_torque=level, starting_torque=level)


@dataclass(frozen=True)
class StribeckFriction(RunningTerm):
    """Friction: the Stribeck rise ``F_s − F_c`` below ``ω_s`` and the direction asymmetry ``Δ``."""

    family: ClassVar[str] = "friction"
    id: ClassVar[str] = "stribeck"
    signature: ClassVar[str] = "more torque at low speed; a level that depends on the direction"
    direction_columns: ClassVar[tuple[str, ...]] = ("coulomb_asymmetry",)
    separated_by: ClassVar[Mapping[str, str]] = MappingProxyType({
        "damping": "a sweep over at least three speeds a decade apart: viscous loss grows with speed, a "
                   "Stribeck rise falls with it",
        "ripple": "longer plateaus (several wave-generator revolutions each): a ripple averages out over a "
                  "revolution, a friction level does not",
    })

    def grid(self, speeds):
        """Stribeck speeds from a fifth of the slowest to the fastest steady speed (log-spaced)."""
        slow, fast = float(np.min(speeds)), float(np.max(speeds))
        return tuple(np.geomspace(0.2 * slow, max(fast, 0.4 * slow), 16))

    def columns(self, speed, angle, velocity_scale, ratio, nonlinear):
        rise = unit_law(velocity_scale, stribeck_speed=nonlinear, starting_torque=1.0).torque(speed, angle)
        asym = unit_law(velocity_scale, coulomb_asymmetry=1.0).torque(speed, angle)
        return Columns(("stribeck_rise", "coulomb_asymmetry"), np.column_stack([rise, asym]),
                       (0.0, -math.inf), (math.inf, math.inf))

    def other_shapes(self, speed, angle, velocity_scale, ratio, nonlinear):
        sign = _sign(speed, velocity_scale)
        x = np.abs(speed) / nonlinear
        return Columns(("stribeck_exponential", "stribeck_lorentzian"),
                       np.column_stack([sign * np.exp(-x), sign / (1.0 + x * x)]), (0.0, 0.0), (math.inf, math.inf))

    def write_back(self, law, coefficients, nonlinear):
        asymmetry = float(coefficients.get("coulomb_asymmetry", 0.0))  # absent: held at 0 (one way)
        return replace(law, starting_torque=law.coulomb_torque + float(coefficients["stribeck_rise"]),
                       stribeck_speed=float(nonlinear), coulomb_asymmetry=asymmetry)


@dataclass(frozen=True)
class ViscousLoss(RunningTerm):
    """Damping: the viscous (churning) loss ``b ω``."""

    family: ClassVar[str] = "damping"
    id: ClassVar[str] = "viscous"
    signature: ClassVar[str] = "torque growing in proportion to speed"
    column_units: ClassVar[Mapping[str, str]] = MappingProxyType({
        "viscous": "N·m·s/rad", "churning_sqrt": "N·m·(s/rad)^½", "churning_square": "N·m·s²/rad²"})
    separated_by: ClassVar[Mapping[str, str]] = MappingProxyType({
        "ripple": "longer plateaus at several speeds: a ripple averages out over a revolution, a viscous loss "
                  "grows with speed",
    })

    def columns(self, speed, angle, velocity_scale, ratio, nonlinear):
        law = unit_law(velocity_scale, viscous=1.0)
        return Columns(("viscous",), law.torque(speed, angle)[:, None], (0.0,), (math.inf,))

    def other_shapes(self, speed, angle, velocity_scale, ratio, nonlinear):
        sign = _sign(speed, velocity_scale)
        w = np.abs(speed)
        return Columns(("churning_sqrt", "churning_square"), np.column_stack([sign * np.sqrt(w), sign * w * w]),
                       (0.0, 0.0), (math.inf, math.inf))

    def write_back(self, law, coefficients, nonlinear):
        return replace(law, viscous=float(coefficients["viscous"]))


@dataclass(frozen=True)
class PositionRipple(RunningTerm):
    """Ripple: the Coulomb level modulated at orders 1, 2, 4 of the WG angle and 1 of the output.

    ``output_order`` False drops the output's 1×: over less than one output revolution
    a periodic term cannot be told from a drift.
    """

    family: ClassVar[str] = "ripple"
    id: ClassVar[str] = "ripple"
    signature: ClassVar[str] = "torque periodic in the wave-generator or output angle"
    output_order: bool = True

    def orders(self, ratio: float) -> tuple[float, ...]:
        """Orders of the WG angle [-]."""
        return WG_RIPPLE_ORDERS + ((1.0 / abs(ratio),) if self.output_order else ())

    def columns(self, speed, angle, velocity_scale, ratio, nonlinear):
        level = unit_law(velocity_scale, coulomb_torque=1.0, starting_torque=1.0).torque(speed, angle)
        names, cols = [], []
        for k in self.orders(ratio):
            for part, phase in (("cos", 0.0), ("sin", -0.5 * math.pi)):
                law = unit_law(velocity_scale, coulomb_torque=1.0, starting_torque=1.0,
                               ripple_orders=(k,), ripple_amplitudes=(1.0,), ripple_phases=(phase,))
                names.append(f"ripple_{part}_{k:.6g}")
                cols.append(law.torque(speed, angle) - level)
        n = len(names)
        return Columns(tuple(names), np.column_stack(cols), (-math.inf,) * n, (math.inf,) * n)

    def other_shapes(self, speed, angle, velocity_scale, ratio, nonlinear):
        sign = _sign(speed, velocity_scale)
        names, cols = [], []
        for k in (3.0, 6.0, 8.0):
            names += [f"harmonic_cos_{k:g}", f"harmonic_sin_{k:g}"]
            cols += [sign * np.cos(k * angle), sign * np.sin(k * angle)]
        return Columns(tuple(names), np.column_stack(cols), (-math.inf,) * 6, (math.inf,) * 6)

    def holds(self, law, coefficients):
        # the ripple modulates the level: on a level of 0 it is lost, on a level so small
        # that the relative amplitude overflows it cannot be written
        if not any(coefficients.values()):
            return True
        level = float(law.coulomb_torque)
        return level > 0.0 and math.isfinite(sum(abs(a) for a in coefficients.values()) / level)

    def write_back(self, law, coefficients, nonlinear):
        level = law.coulomb_torque
        orders, amps, phases = [], [], []
        for name, a in coefficients.items():
            part, k = name.split("_")[1:]
            if part != "cos":
                continue
            b = coefficients[f"ripple_sin_{k}"]
            # F_c r cos(kθ + φ) = a cos kθ + b sin kθ  ->  r = |(a, b)|/F_c, φ = atan2(−b, a)
            orders.append(float(k))
            amps.append(math.hypot(a, b) / level if level > 0 else 0.0)
            phases.append(math.atan2(-b, a))
        return replace(law, ripple_orders=tuple(orders), ripple_amplitudes=tuple(amps), ripple_phases=tuple(phases))


@dataclass(frozen=True)
class PositionTorque(PositionRipple):
    """Ripple, its second form: a torque periodic in the WG angle (orders 1, 2, 4, and the
    output's 1×) that does not reverse with the motion — a motor's cogging, an unbalance,
    gravity on the output. Added to the law, not modulating its level; amplitudes in N·m.

    With both directions recorded it is told from the modulated form (which reverses with
    the motion); with one it is not (`hdsim.identification.running_diagnosis`)."""

    id: ClassVar[str] = "position_torque"
    signature: ClassVar[str] = "torque periodic in angle, the same in both directions"

    def columns(self, speed, angle, velocity_scale, ratio, nonlinear):
        names, cols = [], []
        for k in self.orders(ratio):
            names += [f"position_cos_{k:.6g}", f"position_sin_{k:.6g}"]
            cols += [np.cos(k * angle), np.sin(k * angle)]
        n = len(names)
        return Columns(tuple(names), np.column_stack(cols), (-math.inf,) * n, (math.inf,) * n)

    def other_shapes(self, speed, angle, velocity_scale, ratio, nonlinear):
        # higher harmonics, and the output's own order (over less than one output turn a slow
        # drift, the same both ways, which a direction asymmetry of the friction level would
        # otherwise take); not a constant: that is the asymmetry itself, the same both ways
        names, cols = [], []
        for k in (3.0, 6.0, 8.0, 1.0 / abs(ratio)):
            names += [f"harmonic_cos_{k:.6g}", f"harmonic_sin_{k:.6g}"]
            cols += [np.cos(k * angle), np.sin(k * angle)]
        n = len(names)
        return Columns(tuple(names), np.column_stack(cols), (-math.inf,) * n, (math.inf,) * n)

    def holds(self, law, coefficients):
        return True  # an additive torque needs no level to ride on

    def write_back(self, law, coefficients, nonlinear):
        orders, amps, phases = [], [], []
        for name, a in coefficients.items():
            part, k = name.split("_")[1:]
            if part == "cos":
                b = coefficients[f"position_sin_{k}"]
                orders.append(float(k))
                amps.append(math.hypot(a, b))
                phases.append(math.atan2(-b, a))
        return replace(law, position_orders=tuple(orders), position_amplitudes=tuple(amps),
                       position_phases=tuple(phases))


#: the base model of a running-torque test
BASE_TERM = CoulombLevel()
#: family -> its default term (the first registered form) of a running-torque test
RUNNING_FAMILIES: dict[str, RunningTerm] = {}
#: family -> every form of it, the default first (`register_running_term` adds one)
RUNNING_FORMS: dict[str, tuple[RunningTerm, ...]] = {}


def register_running_term(term: RunningTerm) -> RunningTerm:
    """Make ``term`` a form of its family in the running-torque law (as `hdsim.model.effects.register`
    does for the elastic path's effects): the first form registered for a family is its default;
    a form registered again under the same id is replaced.

    Raises
    ------
    InputError
        A term without a family or id, or the base level's family.
    """
    if not term.family or not term.id or term.family == BASE_TERM.family:
        raise InputError(f"{type(term).__name__} needs a family and an id other than the base level's")
    forms = [t for t in RUNNING_FORMS.get(term.family, ()) if t.id != term.id]
    forms.insert(0 if not forms or RUNNING_FAMILIES[term.family].id == term.id else len(forms), term)
    RUNNING_FORMS[term.family] = tuple(forms)
    RUNNING_FAMILIES[term.family] = forms[0]
    return term


def running_term(name: str) -> RunningTerm:
    """The term of a family name (its default form) or of a term id (that form).

    Raises
    ------
    InputError
        On a name that is neither.
    """
    if name in RUNNING_FAMILIES:
        return RUNNING_FAMILIES[name]
    for forms in RUNNING_FORMS.values():
        for term in forms:
            if term.id == name:
                return term
    raise unknown_name("running-torque family or effect", name,
                       [*RUNNING_FAMILIES, *(t.id for forms in RUNNING_FORMS.values() for t in forms)])


for _term in (StribeckFriction(), ViscousLoss(), PositionRipple(), PositionTorque()):
    register_running_term(_term)


def parse_running_effects(text) -> list[str]:
    """``'friction,ripple'`` or term ids (``'stribeck,viscous'``) -> the families, in the given order.

    Raises
    ------
    InputError
        On a name that is neither a running-torque family nor a term id.
    """
    return list(parse_running_forms(text))


def parse_running_forms(text) -> dict[str, str]:
    """``'friction,position_torque'``, ``'ripple=position_torque'`` or ``{'ripple': 'position_torque'}``
    -> family -> term id, in the given order: a family name stands for its default form, a term
    id or ``family=id`` for that form (as `hdsim.identification.fit.parse_effects` reads the
    elastic path's effects).

    Raises
    ------
    InputError
        On a name that is neither a running-torque family nor a term id, a form that is not
        its family's, or two forms of one family; with close matches.
    """
    if text is None:
        return {}
    if isinstance(text, dict):  # {family: term id}, checked as 'family=id' is
        text = [family if form is None else f"{family}={form}" for family, form in text.items()]
    items = text if isinstance(text, (list, tuple, set)) else str(text).split(",")
    by_id = {term.id: family for family, forms in RUNNING_FORMS.items() for term in forms}
    out: dict[str, str] = {}
    for raw in items:
        item, sep, form = (part.strip() for part in str(raw).strip().partition("="))
        if not item or item == "none":
            continue
        family = item if item in RUNNING_FAMILIES else by_id.get(item)
        if family is None:
            if item in ("hardening", "backlash", "kinematic_error"):
                raise InputError(f"the {item} family acts in the elastic path and is not part of a running-torque "
                                 f"test; its families are {', '.join(RUNNING_FAMILIES)}")
            raise unknown_name("running-torque family or effect", item, {*RUNNING_FAMILIES, *by_id})
        if sep:
            if item != family:
                raise unknown_name("running-torque family", item, RUNNING_FAMILIES)
            if form == "none":
                continue
            forms = [term.id for term in RUNNING_FORMS[family]]
            if form not in forms:
                raise unknown_name(f"{family} form", form, forms)
        else:
            form = RUNNING_FAMILIES[family].id if item == family else item
        if out.get(family, form) != form:
            raise InputError(f"the effects name two {family} forms, {out[family]} and {form}; give one per family")
        out[family] = form
    return out
