"""The effect protocol: what every effect supplies to the simulator, the quasi-static
evaluator and the fit.

An effect is a frozen dataclass of parameters (`hdsim.model.parameters.param`
fields) that belongs to one family (``hardening``, ``backlash``, ``friction``,
``damping``, ``kinematic_error``) and carries its own behaviour: the family base
classes (`hdsim.model.effects.hardening.Hardening` …) declare the methods the
elastic path calls, with the "no effect" behaviour as default, so the code that
assembles a model never asks which effect sits in a slot. Memory (friction states,
the dead-zone closure) is ODE state named in ``state_names`` and passed in and out.

For fits every effect also declares its free parameters with bounds and start
values taken from the data (`FitContext`), how the fitted values map back onto
its fields (`Effect.fit_updates`), the values at which it does nothing
(`Effect.neutral`), and a placeholder instance for a model built from a family
name (`Effect.placeholder`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import ClassVar

import numpy as np

from hdsim.model.family import FamilyKnowledge
from hdsim.model.parameters import Parameters


@dataclass(frozen=True)
class FitContext:
    """What the data say before any fit: the numbers effects draw start values from.

    Attributes
    ----------
    stiffness : float
        Secant stiffness of the loading branch [N·m/rad].
    max_torque : float
        Largest absolute torque of the record [N·m].
    loop_width : float
        Width of the loop at zero torque [rad].
    step : float
        Step of the twist across zero torque [rad].
    rate : float
        Median absolute loading rate [N·m/s].
    linear_spring : bool
        True when the model has no hardening (a parameter that acts only through the
        tangent stiffness is then not identifiable).
    test : str
        The measurement's test (``stiffness``, ``kinematic_error``).
    """

    stiffness: float
    max_torque: float
    loop_width: float = 0.0
    step: float = 0.0
    rate: float = 0.0
    linear_spring: bool = True
    test: str = "stiffness"


@dataclass(frozen=True)
class FreeParameter:
    """One parameter a fit frees: name, bounds of the search and a start value.

    ``name`` is a field of the effect or an internal coordinate the effect maps onto
    its fields in `Effect.fit_updates`. A finite ``upper`` gives a logistic transform,
    an infinite one a logarithmic transform above ``lower``.
    """

    name: str
    lower: float
    upper: float
    start: float


class Effect(Parameters, FamilyKnowledge):
    """Base of all effects: one family, the states its memory needs, the fit protocol, and
    what a diagnosis knows of the family (`FamilyKnowledge`, set on the family's base class)."""

    family: ClassVar[str] = ""
    id: ClassVar[str] = ""
    #: True for the explicit "no effect" of a family
    is_null: ClassVar[bool] = False
    state_names: ClassVar[tuple[str, ...]] = ()
    #: unit of each state, "rad" or "N·m": sets the solver's absolute tolerance
    state_unit: ClassVar[str] = "rad"
    #: ids of effects of the same family that describe the same physics with another
    #: shape (a smooth hardening and the catalog's three segments). Before a diagnosis
    #: adds a family it tries these in place of this effect: an imperfect shape leaves a
    #: residual that another family would otherwise be added to absorb (a proxy)
    other_forms: ClassVar[tuple[str, ...]] = ()
    #: ids of effects of the same family that a diagnosis also tries when the family enters
    #: the model, the best passing form standing for the family: for forms so different in
    #: kind that the family would lose its round to another family's proxy (friction in
    #: series with the spring and beside it)
    entry_forms: ClassVar[tuple[str, ...]] = ()

    @property
    def prefix(self) -> str:
        return self.family

    def inconsistency(self) -> str:
        """Why the values given together do not make this effect ('' when they do): the bounds of
        each value alone are checked on construction; this is what relates them, element by
        element in a batch, naming the first sample that fails (a fit's trial models may pass
        through such values, so only what a user gives is refused by it:
        `HarmonicDrive.require_consistent`)."""
        return ""

    # ------------------------------------------------------------------ fit protocol
    def free_parameters(self, context: FitContext) -> tuple[FreeParameter, ...]:
        """The parameters a fit frees, with bounds and start values from ``context``.

        Default: nothing for a "no effect", else every numeric field within its physical
        bounds, started from the effect's current value.
        """
        if self.is_null:
            return ()
        out = []
        for name, meta in self.param_meta().items():
            lower, upper = meta["bounds"]
            start = float(np.asarray(getattr(self, name)).reshape(-1)[0])
            out.append(FreeParameter(name, float(lower), float(upper), start))
        return tuple(out)

    def other_starts(self, context: FitContext) -> tuple[dict, ...]:
        """Further start values ``{parameter: value}`` worth a fit of their own.

        For a law whose fit has distant minima (a friction that holds the body's windup
        against the load, or one that slips at a small fraction of it); every start is
        fitted in the same lockstep and the lowest cost wins. Default: none.
        """
        return ()

    def neutral_start(self, context: FitContext) -> dict | None:
        """Free-parameter values ``{parameter: value}`` at which this effect does nothing.

        A fit that adds this effect's family to a fitted model starts there too, so that it
        never ends worse than the model it contains (`hdsim.identification.problem.make_problem`).
        Default: the `neutral` instance's value of every free parameter; None when the
        effect declares no neutral values or frees a parameter that is not one of its
        fields (such an effect overrides this).
        """
        if self.is_null:
            return {}
        try:
            neutral = type(self).neutral()
        except NotImplementedError:
            return None
        fields_ = self.param_meta()
        out = {}
        for fp in self.free_parameters(context):
            if fp.name not in fields_:
                return None
            out[fp.name] = float(np.asarray(getattr(neutral, fp.name), dtype=float).reshape(-1)[0])
        return out

    def fit_updates(self, values: dict, engagement=None) -> dict:
        """Dotted model updates ``{"family.field": value}`` from fitted ``values``.

        ``engagement`` is the engagement ratio the base stiffness split chose (used by
        hardening laws that fit a stiffness ratio); other effects ignore it.
        """
        return {f"{self.family}.{name}": value for name, value in values.items()}

    def stiffness_ratio(self, values: dict):
        """High-load over low-load stiffness this effect asks of the base split (1: none)."""
        return 1.0

    # ------------------------------------------------------------------ compiled form
    def compiled(self, size: int, c_struct, c_mesh):
        """This law's compiled scalar form for the compiled quasi-static evaluator, or None.

        ``(functions, rows)``: the law's kernels (`hdsim.model.effects.kernels`, one
        signature per family) and its parameters as a C-ordered float array of ``size``
        rows, one per parameter set. None (the default) sends the evaluator to the
        numpy law, which every effect has. Needs numba; the caller checks it is there.
        """
        return None

    def keeps_law_of(self, owner: type, methods: tuple[str, ...]) -> bool:
        """True when this instance's class takes ``methods`` from ``owner`` unchanged: a
        subclass that redefines its law must not inherit a compiled twin of the old one."""
        return all(getattr(type(self), name) is getattr(owner, name) for name in methods)

    @classmethod
    def neutral(cls) -> "Effect":
        """An instance that acts exactly as "no effect" (used to stack models that
        lack the family into one batch with models that have it); a "no effect" is its own."""
        if cls.is_null:
            return cls()
        raise NotImplementedError(f"{cls.family} effect '{cls.id}' declares no neutral values")

    @classmethod
    def placeholder(cls, rated_torque: float, stiffness: float) -> "Effect":
        """An instance with plausible values for a drive of this rating and stiffness,
        the starting structure of a fit that names only the family."""
        raise NotImplementedError(f"{cls.family} effect '{cls.id}' has no placeholder values")

    @classmethod
    def stack(cls, effects: list["Effect"], sizes: list[int]) -> "Effect":
        """One batch instance from several instances of this class (or "no effect",
        replaced by `neutral`), ``sizes[i]`` rows each."""
        columns = {name: [] for name in cls.param_meta()}
        for effect, size in zip(effects, sizes):
            source = effect if isinstance(effect, cls) else cls.neutral()
            for name in columns:
                value = np.asarray(getattr(source, name), dtype=float)
                columns[name].append(np.broadcast_to(value, (size,)))
        return cls.unchecked(**{name: np.concatenate(parts) for name, parts in columns.items()})

    def describe(self) -> str:
        """``family=id`` with the parameter values, for logs and reports."""
        values = ", ".join(f"{f.name}={np.asarray(getattr(self, f.name)).reshape(-1)[0]:.4g}"
                           for f in fields(self) if f.metadata)
        return f"{self.family}={self.id}" + (f"({values})" if values else "")


def parameter_rows(size: int, *columns) -> np.ndarray:
    """Columns (scalars or arrays of ``size``) as a C-ordered (size, n) float array, the
    layout of a compiled law's parameters (`Effect.compiled`)."""
    if not columns:
        columns = (0.0,)
    return np.ascontiguousarray(np.column_stack([np.broadcast_to(np.asarray(c, dtype=float), (size,))
                                                 for c in columns]))
