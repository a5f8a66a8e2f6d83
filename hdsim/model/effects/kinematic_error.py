"""Kinematic-error family: a position-periodic displacement source in the mesh."""

from __future__ import annotations

import math

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from hdsim.errors import InputError
from hdsim.model.effects.base import Effect
from hdsim.model.parameters import param
from hdsim.physics import kinematic_error as ke
from hdsim.physics.elementary import cos, sin
from hdsim.physics.smooth import magnitude_and_sign


class KinematicError(Effect):
    """Base of the kinematic-error family: ``e(θ_w, θ_o, f)`` [rad], ``f = T/T_N``."""

    family: ClassVar[str] = "kinematic_error"
    separated_from_any: ClassVar[str] = (
        "a kinematic-error test over several output revolutions at constant load: the kinematic error "
        "repeats with the wave-generator angle, the other does not")
    #: step of the central differences of the default partial derivatives [rad] and [-]
    difference_step: ClassVar[float] = 1e-6

    def displacement(self, wg_angle, output_angle, load_fraction):
        """Kinematic error [rad] at WG angle, output angle [rad] and load ``T/T_N`` [-]."""
        return 0.0

    def displacement_and_partials(self, wg_angle, output_angle, load_fraction):
        """``(e, ∂e/∂θ_w, ∂e/∂θ_o, ∂e/∂f)``; central differences unless a law has them in closed form."""
        f, h = self.displacement, self.difference_step
        return (f(wg_angle, output_angle, load_fraction),
                (f(wg_angle + h, output_angle, load_fraction) - f(wg_angle - h, output_angle, load_fraction)) / (2 * h),
                (f(wg_angle, output_angle + h, load_fraction) - f(wg_angle, output_angle - h, load_fraction)) / (2 * h),
                (f(wg_angle, output_angle, load_fraction + h) - f(wg_angle, output_angle, load_fraction - h)) / (2 * h))

    def linear_basis(self, wg_angle, output_angle):
        """Columns the error is linear in (solved by least squares in a fit), or None."""
        return None

    def from_linear(self, coefficients) -> tuple["KinematicError", dict]:
        """The effect (and its parameter values) for least-squares ``coefficients`` of `linear_basis`."""
        raise NotImplementedError

    def linear_uncertainty(self, coefficients, covariance) -> dict:
        """Standard uncertainty of each parameter `from_linear` gives, from the covariance
        of ``coefficients`` (no parameters: none)."""
        return {}


@dataclass(frozen=True, eq=False)
class NoKinematicError(KinematicError):
    """Perfect kinematics: θ_out = θ_WG / N."""

    id: ClassVar[str] = "none"
    is_null: ClassVar[bool] = True

    def displacement_and_partials(self, wg_angle, output_angle, load_fraction):
        return 0.0, 0.0, 0.0, 0.0



def _per_sample(value):
    """A float for a single value (the solver's scalar path is faster on floats), else the
    per-sample array (M,), which broadcasts against angles of shape (M,) or (nt, M)."""
    value = np.asarray(value, dtype=float)
    return float(value) if value.size == 1 else value


@dataclass(frozen=True, eq=False)
class FourierKinematicError(KinematicError):
    """Kinematic error harmonics at 1×, 2×, 4× the wave-generator angle and 1× output.

    Amplitudes scale with ``max(1 + load_gain·|T|/T_N, 0)`` (Ghorbel et al., 2001, observed
    KE varying with load); a negative gain shrinks the error to zero and no further, so
    it never changes sign beyond ``|T| = T_N/|load_gain|``. In a fit the amplitudes and phases enter as sine/cosine
    coefficients solved by linear least squares; ``load_gain`` stays at 0.
    """

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
    wg_orders: ClassVar[tuple[int, ...]] = (1, 2, 4)
    output_orders: ClassVar[tuple[int, ...]] = (1,)

    @cached_property
    def _harmonics(self):
        """(WG terms, output terms, load gain) with per-sample values, computed once."""
        f = _per_sample
        wg = tuple((k, f(a), f(p)) for k, a, p in ((1.0, self.a1, self.p1), (2.0, self.a2, self.p2),
                                                     (4.0, self.a4, self.p4)))
        return wg, ((1.0, f(self.a_out), f(self.p_out)),), f(self.load_gain)

    def displacement(self, wg_angle, output_angle, load_fraction):
        scale = np.maximum(1.0 + self.load_gain * np.abs(load_fraction), 0.0)
        return scale * ke.fourier_kinematic_error(
            wg_angle, output_angle, (1, 2, 4), (self.a1, self.a2, self.a4), (self.p1, self.p2, self.p4),
            (1,), (self.a_out,), (self.p_out,))

    def displacement_and_partials(self, wg_angle, output_angle, load_fraction):
        wg, out, gain = self._harmonics
        # a single model's right-hand side passes Python floats: `math` there (hdsim.physics.elementary)
        base = d_w = d_o = 0.0
        for k, a, p in wg:
            arg = k * wg_angle + p
            base = base + a * sin(arg)
            d_w = d_w + a * k * cos(arg)
        for k, a, p in out:
            arg = k * output_angle + p
            base = base + a * sin(arg)
            d_o = d_o + a * k * cos(arg)
        magnitude, sign = magnitude_and_sign(load_fraction)
        raw = 1.0 + gain * magnitude
        if isinstance(raw, float):
            scale = max(raw, 0.0)
            d_f = gain * sign * base if raw > 0.0 else 0.0 * base
        else:
            scale = np.maximum(raw, 0.0)
            d_f = np.where(raw > 0.0, gain * sign, 0.0) * base
        return scale * base, scale * d_w, scale * d_o, d_f

    def linear_basis(self, wg_angle, output_angle):
        columns = []
        for k in self.wg_orders:
            columns += [np.sin(k * wg_angle), np.cos(k * wg_angle)]
        for k in self.output_orders:
            columns += [np.sin(k * output_angle), np.cos(k * output_angle)]
        return np.column_stack(columns)

    def from_linear(self, coefficients):
        pairs = np.asarray(coefficients, dtype=float).reshape(-1, 2)
        amplitudes, phases = np.hypot(pairs[:, 0], pairs[:, 1]), np.arctan2(pairs[:, 1], pairs[:, 0])
        amp_names, phase_names = (list(names) for names in zip(*self._linear_names()))
        upper = self.param_meta()["a1"]["bounds"][1]
        clipped = [name for a, name in zip(amplitudes, amp_names) if a > upper]
        if clipped:  # beyond the physical bound: the record is not a kinematic error of this size
            raise InputError(f"fitted kinematic-error amplitude {', '.join(clipped)} exceeds "
                             f"{upper:g} rad ({upper * 180 / np.pi * 60:.0f} arcmin): the angles do not "
                             "look like a kinematic-error test (check units and the ratio)")
        values = {"load_gain": 0.0}
        for a, p, an, pn in zip(amplitudes, phases, amp_names, phase_names):
            values[an] = float(a)
            values[pn] = float(p)
        return type(self)(**values), values

    def _linear_names(self) -> list[tuple[str, str]]:
        """(amplitude, phase) parameter names of each order of `linear_basis`, in its order."""
        return [(f"a{k}", f"p{k}") for k in self.wg_orders] + [("a_out", "p_out")]

    def linear_uncertainty(self, coefficients, covariance):
        """Amplitude ``a = √(s² + c²)`` [rad] and phase ``atan2(c, s)`` [rad] of each order
        from the covariance of its sine and cosine coefficients ``(s, c)``, to first order:
        ``σ_a² = g Σ gᵀ`` with ``g = (s, c)/a`` and ``σ_p² = h Σ hᵀ`` with ``h = (−c, s)/a²``
        (white noise of rms σ over n samples gives ``σ_a = σ √(2/n)`` and ``σ_p = σ_a / a``).
        A zero amplitude has no phase to speak of: infinite."""
        pairs = np.asarray(coefficients, dtype=float).reshape(-1, 2)
        cov = np.asarray(covariance, dtype=float)
        out = {}
        for i, ((s, c), (a_name, p_name)) in enumerate(zip(pairs, self._linear_names())):
            block = cov[2 * i:2 * i + 2, 2 * i:2 * i + 2]
            a = math.hypot(s, c)
            if a == 0.0:
                out[a_name], out[p_name] = math.sqrt(max(float(np.max(np.diag(block))), 0.0)), math.inf
                continue
            g, h = np.array([s, c]) / a, np.array([-c, s]) / a ** 2
            out[a_name] = math.sqrt(max(float(g @ block @ g), 0.0))
            out[p_name] = math.sqrt(max(float(h @ block @ h), 0.0))
        return out

    def free_parameters(self, context):
        return ()  # all linear: see linear_basis

    @classmethod
    def neutral(cls):
        return cls(a1=0.0, a2=0.0, a4=0.0, p1=0.0, p2=0.0, p4=0.0, a_out=0.0, p_out=0.0, load_gain=0.0)

    @classmethod
    def placeholder(cls, rated_torque, stiffness):
        return cls.neutral()
