"""Micro-slip distributed over the teeth: smoothed relays in series with the spring.

The friction laws of `hdsim.model.effects.friction` that act beside the spring (Dahl,
Coulomb, Maxwell-slip) are stiff just after a reversal and soften as they slide. Slip
*in series* with the spring behaves the other way round once it runs out: the teeth
that carry the load slip one after the other as the torque passes their thresholds,
and when all have slipped the body is as stiff as its spring again. A loop of that
kind is soft in a band of torque away from the reversal and stiff on both sides of
it, which a parallel law cannot draw (a diagnosis would add a hardening to make up
for it). This law is Preisach's relay model (Mayergoyz, 1991) with the interaction
set to zero: relays of switching torques ``±c_i`` spread log-normally about a median,
each carrying an equal share of the slip range; the relays are smoothed over a band of
torque so that the slip is continuously differentiable (docs/physics.md, "distributed
micro-slip").

States: each relay's slip [rad]; a drive starts with every relay at zero (demagnetised).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from statistics import NormalDist
from typing import ClassVar

import numpy as np

from hdsim.model.effects.base import FitContext, FreeParameter
from hdsim.model.effects.friction import _LAW, Friction, element_columns, element_rows
from hdsim.model.parameters import param
from hdsim.physics import friction as fr

#: relays of the quadrature: six draw a continuous log-normal Preisach loop to within 3–6 %
#: of its width for spreads 0.3–0.5 (docs/physics.md, "distributed micro-slip"), at six states
N_RELAYS = 6
#: bounds of a fit (`DistributedSlip.free_parameters`): the median switching torque over
#: the record's peak torque at least, the spread at most
MIN_SLIP_TORQUE, MAX_FITTED_SPREAD = 0.05, 1.0
#: where the relays sit on the log-normal: the mid-points of six equal shares
_QUANTILES = np.array([NormalDist().inv_cdf((i + 0.5) / N_RELAYS) for i in range(N_RELAYS)])


def band_fraction(spread):
    """Half-width of a relay's switching band over its threshold, from the spread [-].

    Wide enough that neighbouring relays overlap (they sit 0.42–0.71 ``spread`` apart in
    the log), narrow enough (< 0.9) that every relay switches at a torque of its own sign.
    """
    return np.clip(0.6 * np.asarray(spread, dtype=float), 0.05, 0.9)


@dataclass(frozen=True, eq=False)
class DistributedSlip(Friction):
    """Micro-slip of the teeth in series with the spring: relays with log-normal thresholds.

    Relay ``i`` slips from ``−a`` to ``+a`` (``a = slip_max/6``) as the torque through the
    body rises past ``c_i = slip_torque·exp(spread·z_i)`` and back as it falls past
    ``−c_i``, over a band of ``±c_i·min(0.6 spread, 0.9)``. A cycle well beyond the largest
    threshold opens a loop ``2·slip_max`` wide at zero torque; a small one stays elastic.
    """

    id: ClassVar[str] = "distributed_slip"
    #: within 0.001 arcsec of transmission accuracy on the contract kinematic-error run
    driven_quasistatic: ClassVar[bool] = True
    #: the parallel arrangement's form, for the proxy guard of a diagnosis
    other_forms: ClassVar[tuple[str, ...]] = ("dahl",)
    state_names: ClassVar[tuple[str, ...]] = tuple(f"slip_{i}" for i in range(N_RELAYS))
    slip_torque: float = param("median switching torque of the relays", "N·m", positive=True)
    slip_max: float = param("slip range to each side (half the saturated loop width)", "rad", 0.0, 0.05,
                            positive=True)
    spread: float = param("log-normal spread of the switching torques", "1", 0.0, 3.0, positive=True,
                          default=0.4)
    #: direction switch smoothing of the ODE form [rad/s]: ~1e-3 of a catalog test's twist rate
    velocity_scale: ClassVar[float] = 1e-6

    @cached_property
    def _columns(self):
        """(thresholds, band half-widths [N·m], amplitudes [rad]) of the relays, shape (6, M)."""
        spread = np.atleast_1d(np.asarray(self.spread, dtype=float))
        thresholds = np.atleast_1d(self.slip_torque) * np.exp(_QUANTILES[:, None] * spread)
        widths = thresholds * band_fraction(spread)
        amplitudes = np.ones(N_RELAYS)[:, None] * np.atleast_1d(self.slip_max) / N_RELAYS
        return tuple(np.ascontiguousarray(np.broadcast_to(c, np.broadcast_shapes(
            thresholds.shape, amplitudes.shape))) for c in (thresholds, widths, amplitudes))

    def _relays(self, states):
        """The columns shaped to broadcast against ``states`` (relay axis first)."""
        return element_columns(self._columns, states)

    # -------------------------------------------------------------- the law
    def series_slip(self, states):
        return np.sum(np.asarray(states, dtype=float), axis=0)

    def rates(self, states, body_rate, spring_torque, spring_tangent):
        states = np.asarray(states, dtype=float)
        c, w, a = self._relays(states)
        return tuple(fr.relay_slip_rates(states, body_rate, spring_tangent, spring_torque, c, w, a,
                                         self.velocity_scale))

    def quasistatic(self, states, start, end, spring):
        # the spring's twist x solves x + slip(u(x)) = e; the slip lies within ±slip_max,
        # so x is bracketed by e ∓ slip_max, and Newton steps that leave the bracket bisect
        s0 = np.asarray(states, dtype=float)
        c, w, a = self._relays(s0)
        end = np.asarray(end, dtype=float)
        direction = np.where(end - start >= 0.0, 1.0, -1.0)
        reach = np.sum(a, axis=0)
        lo, hi = end - reach, end + reach
        x = end - np.sum(s0, axis=0)

        def at(x):
            u, k = spring(x)
            slips, slopes = fr.relay_slips_on_branch(s0, u, direction, c, w, a)
            return u, k, slips, np.sum(slopes, axis=0)

        u, k, slips, slope = at(x)
        for _ in range(60):
            h = x + np.sum(slips, axis=0) - end
            if not np.any(h):  # most steps: no relay moves, the start is the root
                break
            lo = np.where(h < 0.0, np.maximum(lo, x), lo)
            hi = np.where(h > 0.0, np.minimum(hi, x), hi)
            xn = x - h / (1.0 + k * slope)
            # the root may sit on the bracket's edge (every relay at its stop)
            xn = np.where((xn < lo) | (xn > hi), 0.5 * (lo + hi), xn)
            done = np.all(np.abs(xn - x) <= 1e-15 + 1e-13 * np.abs(x))
            x = xn
            u, k, slips, slope = at(x)
            if done:
                break
        return u, k / (1.0 + k * slope), slips, u, k

    def advance(self, states, start, end, spring):
        return self.quasistatic(states, start, end, spring)[2]

    def path_tangent(self, states, direction, spring_torque, spring_tangent):
        # the relays on their curve in ``direction`` slip on. Nudging the states back by
        # 1e-4 of their range counts those that sit on it: the torque a caller passes comes
        # from the last Newton iterate, within the solver's tolerance of the states' own
        states = np.asarray(states, dtype=float)
        c, w, a = self._relays(states)
        _, slopes = fr.relay_slips_on_branch(states - direction * 1e-4 * a, spring_torque, direction, c, w, a)
        return spring_tangent / (1.0 + spring_tangent * np.sum(slopes, axis=0))

    def compiled(self, size, c_struct, c_mesh):
        if not self.keeps_law_of(DistributedSlip, _LAW + ("_columns",)):
            return None
        from hdsim.model.effects import kernels
        return (kernels.distributed_slip_step,), element_rows(self._columns, size)

    # -------------------------------------------------------------- fit protocol
    def free_parameters(self, context: FitContext):
        # relays that switch within a few per cent of the peak torque of zero hold no
        # torque: they draw a dead zone whose contact rounds off (the backlash family's
        # shape), and a fit of a gap lets them do so (a hard gap fitted as slip at 0.05 %
        # of the peak with the widest spread). So the median switching torque stays above
        # 5 % of the record's peak torque and the spread below 1 (the lowest relay then
        # switches above 1.2 % of the peak)
        t = context.max_torque
        return (FreeParameter("slip_torque", MIN_SLIP_TORQUE * t, np.inf, 0.15 * t),
                FreeParameter("slip_max", 0.0, 0.05, float(np.clip(0.5 * context.loop_width, 1e-6, 1e-2))),
                FreeParameter("spread", 0.05, MAX_FITTED_SPREAD, 0.4))

    @classmethod
    def neutral(cls):
        return cls.unchecked(slip_torque=1.0, slip_max=0.0, spread=0.4)

    @classmethod
    def placeholder(cls, rated_torque, stiffness):
        return cls(slip_torque=0.1 * rated_torque, slip_max=1e-4, spread=0.4)
