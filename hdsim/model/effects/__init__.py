"""Effect slots: one family each, each with an explicit "no effect", and their registry.

Effects are frozen dataclasses of parameters that carry their own behaviour (see
`hdsim.model.effects.base`); the laws they use are the pure functions in
`hdsim.physics`. A field may be a float or a 1-D array (a batch of parameter sets).

The registry maps family → effect id → class. `register` adds a law written
anywhere (a user's module, a test) so that simulation, fit and diagnosis can use
it by id; one effect per family is the default a fit or a diagnosis uses when only
the family is named.
"""

from __future__ import annotations

from dataclasses import MISSING, fields

from hdsim.errors import InputError, unknown_name
from hdsim.model.effects.backlash import Backlash, DeadZoneBacklash, GradualDeadZone, NoBacklash
from hdsim.model.effects.base import Effect, FitContext, FreeParameter
from hdsim.model.effects.damping import Damping, NoDamping, ViscousDamping
from hdsim.model.effects.distributed_slip import DistributedSlip
from hdsim.model.effects.friction import (CoulombFriction, DahlFriction, DahlSlip, Friction, MaxwellSlip,
                                          NoFriction)
from hdsim.model.effects.hardening import Hardening, NoHardening, TanhHardening, ThreeSegmentHardening
from hdsim.model.effects.kinematic_error import FourierKinematicError, KinematicError, NoKinematicError
from hdsim.model.parameters import Parameters, param

__all__ = ["Effect", "FitContext", "FreeParameter", "Parameters", "param",
           "Hardening", "NoHardening", "ThreeSegmentHardening", "TanhHardening",
           "Backlash", "NoBacklash", "DeadZoneBacklash",
           "Friction", "NoFriction", "DahlFriction", "CoulombFriction", "MaxwellSlip", "DahlSlip",
           "DistributedSlip",
           "Damping", "NoDamping", "ViscousDamping",
           "KinematicError", "NoKinematicError", "FourierKinematicError",
           "FAMILIES", "NO_EFFECT", "FAMILY_BASES", "register", "unregister", "effect_class", "make_effect",
           "default_effect", "set_default_effect"]

#: the base class every effect of a family derives from
FAMILY_BASES: dict[str, type[Effect]] = {"hardening": Hardening, "backlash": Backlash, "friction": Friction,
                                         "damping": Damping, "kinematic_error": KinematicError}
#: family -> effect id -> class
FAMILIES: dict[str, dict[str, type[Effect]]] = {family: {} for family in FAMILY_BASES}
#: the explicit "no effect" instance of every family
NO_EFFECT: dict[str, Effect] = {}
#: the effect a fit or diagnosis uses when only the family is named
_DEFAULTS: dict[str, str] = {}


def register(cls: type[Effect], *, default: bool = False) -> type[Effect]:
    """Add an effect class to the registry (usable as a class decorator).

    Parameters
    ----------
    cls : type
        A frozen dataclass deriving from its family's base class (`FAMILY_BASES`) with
        a unique ``id``.
    default : bool
        Make it the effect fits and diagnoses use for its family when only the family is named.

    Raises
    ------
    InputError
        Unknown family, a class that does not derive from the family base, or an id
        already taken by another class.
    """
    family = cls.family
    if family not in FAMILY_BASES:
        raise unknown_name("effect family", family, FAMILY_BASES)
    if not issubclass(cls, FAMILY_BASES[family]):
        raise InputError(f"{cls.__name__} must derive from {FAMILY_BASES[family].__name__}")
    if not cls.id:
        raise InputError(f"{cls.__name__} needs an id")
    taken = FAMILIES[family].get(cls.id)
    if taken is not None and taken is not cls:
        raise InputError(f"{family} effect id '{cls.id}' is taken by {taken.__name__}")
    FAMILIES[family][cls.id] = cls
    if cls.is_null:
        NO_EFFECT[family] = cls()
    if default:
        _DEFAULTS[family] = cls.id
    return cls


def unregister(cls: type[Effect]) -> None:
    """Remove an effect class registered with `register` (the built-in defaults are restored)."""
    FAMILIES[cls.family].pop(cls.id, None)
    if _DEFAULTS.get(cls.family) == cls.id:
        _DEFAULTS[cls.family] = _BUILTIN_DEFAULTS[cls.family]


def default_effect(family: str) -> str:
    """Id of the effect a fit or diagnosis uses when only ``family`` is named."""
    if family not in _DEFAULTS:
        raise unknown_name("effect family", family, FAMILY_BASES)
    return _DEFAULTS[family]


def set_default_effect(family: str, effect_id: str) -> None:
    """Make ``effect_id`` the default of ``family`` (see `default_effect`)."""
    effect_class(family, effect_id)
    _DEFAULTS[family] = effect_id


def effect_class(family: str, effect_id: str) -> type[Effect]:
    """The registered class of ``family`` with ``effect_id``; InputError with close matches."""
    if family not in FAMILIES:
        raise unknown_name("effect family", family, FAMILIES)
    if effect_id not in FAMILIES[family]:
        raise unknown_name(f"{family} effect", effect_id, FAMILIES[family])
    return FAMILIES[family][effect_id]


def make_effect(family: str, effect_id: str, **values) -> Effect:
    """An effect by family and id from parameter values (fields with a default may be left out)."""
    cls = effect_class(family, effect_id)
    known = {f.name for f in fields(cls)}
    for name in values:
        if name not in known:
            raise unknown_name(f"parameter of {family}.{effect_id}", name, known or {"(none)"})
    missing = {f.name for f in fields(cls) if f.default is MISSING} - set(values)
    if missing:
        raise InputError(f"{family}.{effect_id} needs {', '.join(sorted(missing))}")
    return cls(**values)


for _cls in (NoHardening, ThreeSegmentHardening, NoBacklash, GradualDeadZone, NoFriction, DahlSlip,
             CoulombFriction, MaxwellSlip, DistributedSlip, NoDamping, NoKinematicError):
    register(_cls)
for _cls in (TanhHardening, DeadZoneBacklash, DahlFriction, ViscousDamping, FourierKinematicError):
    register(_cls, default=True)
_BUILTIN_DEFAULTS = dict(_DEFAULTS)
