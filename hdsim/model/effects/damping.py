"""Damping family: rate-dependent loss across the flexspline body."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import ClassVar

import numpy as np

from hdsim.model.effects.base import Effect, FitContext, FreeParameter, parameter_rows
from hdsim.model.parameters import param
from hdsim.physics import damping as dp


class Damping(Effect):
    """Base of the damping family: a viscous coefficient that may depend on the tangent stiffness."""

    family: ClassVar[str] = "damping"
    rate_partner: ClassVar[str] = "friction"
    rate_dependent: ClassVar[bool] = True
    separated_by: ClassVar[Mapping[str, str]] = MappingProxyType({
        "friction": "a second loading rate: a damping loop widens with the rate, a friction loop does not",
        "backlash": "a second loading rate: backlash does not change with the rate, damping does",
        "hardening": "a second loading rate: hardening does not change with the rate",
    })

    def coefficient_at(self, tangent_ratio):
        """Damping coefficient [N·m·s/rad] where the tangent stiffness is ``tangent_ratio·K₀``."""
        return 0.0

    @property
    def follows_stiffness(self) -> bool:
        """True when the coefficient depends on the tangent stiffness (it must then be
        evaluated at every twist)."""
        return False


@dataclass(frozen=True, eq=False)
class NoDamping(Damping):
    """No rate-dependent loss."""

    id: ClassVar[str] = "none"
    is_null: ClassVar[bool] = True

    def compiled(self, size, c_struct, c_mesh):
        if not self.keeps_law_of(NoDamping, ("coefficient_at",)):
            return None
        from hdsim.model.effects import kernels
        return (kernels.no_damping,), parameter_rows(size)


@dataclass(frozen=True, eq=False)
class ViscousDamping(Damping):
    """Viscous (Kelvin–Voigt) damping across the body, ``τ = c(δ) δ̇``.

    ``c(δ) = c₀ [(1 − s) + s K_t(δ)/K₀]`` (`hdsim.physics.damping.load_dependent_coefficient`):
    the share ``s`` of the damping follows the tangent stiffness, as the damping of the
    tooth contacts does when more teeth come into mesh (stiffness-proportional, Rayleigh
    damping), the rest (lubricant shear, cylinder material) stays constant. Without
    hardening, or with ``s = 0``, it is a constant coefficient ``c₀``.
    """

    id: ClassVar[str] = "viscous"
    coefficient: float = param("viscous coefficient at zero twist", "N·m·s/rad", 0.0, 1e6)
    stiffness_share: float = param("share of the coefficient proportional to the tangent stiffness",
                                   "-", 0.0, 1.0, default=0.0)

    def coefficient_at(self, tangent_ratio):
        return dp.load_dependent_coefficient(self.coefficient, self.stiffness_share, tangent_ratio)

    def compiled(self, size, c_struct, c_mesh):
        # the kernel takes the tangent ratio always; with share 0 it does not matter
        if not self.keeps_law_of(ViscousDamping, ("coefficient_at",)):
            return None
        from hdsim.model.effects import kernels
        return (kernels.viscous_damping,), parameter_rows(size, self.coefficient, self.stiffness_share)

    @property
    def follows_stiffness(self) -> bool:
        return bool(np.any(np.asarray(self.stiffness_share) != 0.0))

    def free_parameters(self, context: FitContext):
        # a loop of width w at zero torque under loading rate Ṫ: w ≈ 2 c Ṫ / K²
        width = max(context.loop_width, 2e-5)
        k = context.stiffness
        start = float(np.clip(0.5 * width * k * k / (2.0 * max(context.rate, 1e-9)), 1e-3, 5e5))
        out = (FreeParameter("coefficient", 0.0, 1e6, start),)
        if not context.linear_spring:  # the share acts only through the tangent stiffness
            out += (FreeParameter("stiffness_share", 0.0, 1.0, 0.5),)
        return out

    @classmethod
    def neutral(cls):
        return cls(coefficient=0.0, stiffness_share=0.0)

    @classmethod
    def placeholder(cls, rated_torque, stiffness):
        return cls(coefficient=0.005 * stiffness, stiffness_share=0.0)
