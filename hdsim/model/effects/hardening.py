"""Hardening family: the spring law of the flexspline body, torque against twist.

Every law starts from the base stiffness ``K₀ = 1/(C_struct + C_mesh)`` of the
compliance chain and can only remove mesh-zone compliance as more teeth share the
load (docs/physics.md, "hardening").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from hdsim.model.effects.base import Effect, FitContext, FreeParameter, parameter_rows
from hdsim.model.parameters import param
from hdsim.physics import stiffness as st


#: the methods a compiled twin stands for (`Effect.keeps_law_of`)
_LAW = ("torque", "tangent", "spring_law")

#: a fitted first breakpoint stays above this fraction of the record's peak torque. The
#: catalog's T1 is 16-20 % of the rated torque for every size (K2/K1 = 1.3-1.6), so a
#: first segment that ends within a few per cent of zero torque, many times softer than
#: the next, is not a hardening: it is a dead zone whose contact stiffens (the backlash
#: family's shape), and a fit of a smooth gap lets it be one (T1 at 0.5 % of the peak with
#: the next segment 29x stiffer)
MIN_FIRST_BREAKPOINT = 0.05


class Hardening(Effect):
    """Base of the hardening family; subclasses give ``torque`` and ``tangent``."""

    family: ClassVar[str] = "hardening"

    def torque(self, twist, c_struct, c_mesh):
        """Spring torque [N·m] at body twist ``twist`` [rad]."""
        raise NotImplementedError

    def tangent(self, twist, c_struct, c_mesh):
        """Tangent stiffness dT/dtwist [N·m/rad]."""
        raise NotImplementedError

    def spring_law(self, c_struct, c_mesh):
        """A function ``twist -> (torque, tangent)`` with the law's arguments computed once."""
        return lambda twist: (self.torque(twist, c_struct, c_mesh), self.tangent(twist, c_struct, c_mesh))


@dataclass(frozen=True, eq=False)
class NoHardening(Hardening):
    """Linear stiffness: the base compliance alone, ``T = K₀ δ``."""

    id: ClassVar[str] = "none"
    is_null: ClassVar[bool] = True

    def torque(self, twist, c_struct, c_mesh):
        return twist / (c_struct + c_mesh)

    def tangent(self, twist, c_struct, c_mesh):
        return np.zeros_like(np.asarray(twist, dtype=float)) + 1.0 / (c_struct + c_mesh)

    def spring_law(self, c_struct, c_mesh):
        k = 1.0 / (c_struct + c_mesh)
        return lambda twist: (k * twist, k)

    def compiled(self, size, c_struct, c_mesh):
        if not self.keeps_law_of(NoHardening, _LAW):
            return None
        from hdsim.model.effects import kernels
        return (kernels.linear_spring,), parameter_rows(size, 1.0 / (c_struct + c_mesh))


@dataclass(frozen=True, eq=False)
class ThreeSegmentHardening(Hardening):
    """Catalog three-segment law; more teeth share the load above T1 and T2.

    The mesh-zone compliance is divided by the engagement ratio ``e2`` between T1
    and T2 and by ``e3`` above T2 (``e = 1`` below T1); the structural compliance is
    unchanged. ``K_i = 1 / (C_struct + C_mesh / e_i)``.
    """

    id: ClassVar[str] = "three_segment"
    other_forms: ClassVar[tuple[str, ...]] = ("tanh",)
    T1: float = param("first breakpoint torque", "N·m", positive=True)
    T2: float = param("second breakpoint torque", "N·m", positive=True)
    e2: float = param("engagement ratio between T1 and T2", "-", 1.0, 100.0)
    e3: float = param("engagement ratio above T2", "-", 1.0, 100.0)
    #: knee rounding as a fraction of the twist at T1: small enough that the fitted
    #: K1..K3 move by < 0.5 %, large enough that implicit solvers step over the knees
    knee_rounding: ClassVar[float] = 0.03

    def stiffnesses(self, c_struct, c_mesh):
        """(K1, K2, K3) [N·m/rad] of the three segments."""
        return (1.0 / (c_struct + c_mesh), 1.0 / (c_struct + c_mesh / self.e2),
                1.0 / (c_struct + c_mesh / self.e3))

    def _args(self, c_struct, c_mesh):
        K = self.stiffnesses(c_struct, c_mesh)
        return (self.T1, self.T2, *K, self.knee_rounding * self.T1 / K[0])

    def torque(self, twist, c_struct, c_mesh):
        return st.smooth_three_segment_torque(twist, *self._args(c_struct, c_mesh))

    def tangent(self, twist, c_struct, c_mesh):
        return st.smooth_three_segment_tangent(twist, *self._args(c_struct, c_mesh))

    def spring_law(self, c_struct, c_mesh):
        args = self._args(c_struct, c_mesh)
        return lambda twist: (st.smooth_three_segment_torque(twist, *args),
                              st.smooth_three_segment_tangent(twist, *args))

    def compiled(self, size, c_struct, c_mesh):
        if not self.keeps_law_of(ThreeSegmentHardening, _LAW + ("_args",)):
            return None
        from hdsim.model.effects import kernels
        return (kernels.smooth_three_segment_spring,), parameter_rows(size, *self._args(c_struct, c_mesh))

    def inconsistency(self) -> str:
        # element by element: a batch may vary T1 alone, against one T2
        T1, T2 = np.broadcast_arrays(np.atleast_1d(np.asarray(self.T1, dtype=float)),
                                     np.atleast_1d(np.asarray(self.T2, dtype=float)))
        bad = T1 >= T2
        if not bad.any():
            return ""
        k = int(np.argmax(bad))
        where = f" in sample {k} of the batch" if bad.size > 1 else ""
        return (f"hardening.T1 = {T1[k]:g} must be below hardening.T2 = {T2[k]:g} N·m{where} "
                "(more teeth engage at the second breakpoint)")

    def free_parameters(self, context: FitContext):
        t = context.max_torque
        return (FreeParameter("T1", MIN_FIRST_BREAKPOINT * t, np.inf, 0.15 * t),
                FreeParameter("T2", 0.0, np.inf, 0.5 * t),
                FreeParameter("e2", 1.0, 100.0, 1.5), FreeParameter("e3", 1.0, 100.0, 2.5))

    @classmethod
    def neutral(cls):
        return cls(T1=1.0, T2=2.0, e2=1.0, e3=1.0)

    @classmethod
    def placeholder(cls, rated_torque, stiffness):
        return cls(T1=0.15 * rated_torque, T2=0.5 * rated_torque, e2=2.0, e3=3.0)


@dataclass(frozen=True, eq=False)
class TanhHardening(Hardening):
    """Smooth hardening: tangent stiffness from K₀ to ``K∞ = 1/(C_struct + C_mesh/e_inf)``.

    The transition is centred on the twist reached at ``T_s`` under K₀.

    A fit frees it through the curvature ``(K∞/K₀ − 1)/T_s²`` [1/(N·m)²], which the data
    fix directly (it sets the tangent stiffness ``K₀ (1 + curvature·T²)`` at small load),
    and the transition torque ``T_s``, bounded below by `MIN_FIRST_BREAKPOINT` of the
    record's peak torque for the reason the three-segment law's T1 is; the stiffness ratio
    ``K∞/K₀ = 1 + curvature·T_s²`` (at most 40) becomes ``e_inf`` through the base
    stiffness split.
    """

    id: ClassVar[str] = "tanh"
    other_forms: ClassVar[tuple[str, ...]] = ("three_segment",)
    e_inf: float = param("engagement ratio at high load", "-", 1.0, 100.0)
    T_s: float = param("transition torque", "N·m", positive=True)
    #: range of K∞/K₀ a fit reaches (1 + curvature·T_s² is clipped to it)
    ratio_bounds: ClassVar[tuple[float, float]] = (1.0, 40.0)

    def _k(self, c_struct, c_mesh):
        k0 = 1.0 / (c_struct + c_mesh)
        return k0, 1.0 / (c_struct + c_mesh / self.e_inf), self.T_s / k0

    def torque(self, twist, c_struct, c_mesh):
        return st.tanh_hardening_torque(twist, *self._k(c_struct, c_mesh))

    def tangent(self, twist, c_struct, c_mesh):
        return st.tanh_hardening_tangent(twist, *self._k(c_struct, c_mesh))

    def spring_law(self, c_struct, c_mesh):
        args = self._k(c_struct, c_mesh)
        # far out on the law cosh overflows and the tangent tends to K∞ as it should; the
        # callers (solver, quasi-static evaluator) run under np.errstate(over="ignore")
        return lambda twist: (st.tanh_hardening_torque(twist, *args), st.tanh_hardening_tangent(twist, *args))

    def compiled(self, size, c_struct, c_mesh):
        if not self.keeps_law_of(TanhHardening, _LAW + ("_k",)):
            return None
        from hdsim.model.effects import kernels
        return (kernels.tanh_spring,), parameter_rows(size, *self._k(c_struct, c_mesh))

    def free_parameters(self, context: FitContext):
        # the start is the ratio 4 with the transition at 0.6 of the peak torque
        t = context.max_torque
        return (FreeParameter("curvature", 0.0, np.inf, 3.0 / (0.6 * t) ** 2),
                FreeParameter("T_s", MIN_FIRST_BREAKPOINT * t, np.inf, 0.6 * t))

    def neutral_start(self, context: FitContext):
        # the fit frees the curvature, not e_inf: a zero curvature is a ratio of 1 at any T_s
        return {"curvature": 0.0, "T_s": self.free_parameters(context)[1].start}

    def stiffness_ratio(self, values):
        ratio = np.clip(1.0 + np.asarray(values["curvature"], dtype=float)
                        * np.asarray(values["T_s"], dtype=float) ** 2, *self.ratio_bounds)
        return float(ratio) if ratio.ndim == 0 else ratio  # a float keys the stiffness split's cache

    def fit_updates(self, values, engagement=None):
        # a curvature at 0 means "no hardening" whatever T_s: far out, finite
        T_s = np.where(np.asarray(values["curvature"], dtype=float) > 0.0,
                       np.minimum(np.asarray(values["T_s"], dtype=float), 1e12), 1e12)
        return {"hardening.e_inf": engagement, "hardening.T_s": T_s}

    @classmethod
    def neutral(cls):
        return cls(e_inf=1.0, T_s=1.0)

    @classmethod
    def placeholder(cls, rated_torque, stiffness):
        return cls(e_inf=2.0, T_s=0.3 * rated_torque)
