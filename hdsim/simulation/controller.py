"""The motor's speed loop of the driven bench (input mode ``pi``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class PIController:
    """PI speed loop on the WG: ``T_m = k_p (ω_ref − ω_w) + k_i ∫(ω_ref − ω_w) dt + J_ff α_ref``.

    The integral of the speed error is the WG angle error, so the loop also holds
    position (a position stiffness ``k_i``).

    Attributes
    ----------
    kp : float
        Gain on the WG speed error [N·m·s/rad].
    ki : float
        Gain on the integral of the WG speed error [N·m/rad].
    feedforward_inertia : float
        J_ff [kg·m²] of the acceleration feedforward (0: none).
    position_gain : float
        Gain of an optional outer position loop [1/s]: the speed command becomes
        ``ω_ref + k_pos (θ_ref − θ_w)``, so the integrator removes the position error a
        holding torque (friction, load) leaves with the speed loop alone (0: speed loop only).
    """

    kp: float
    ki: float
    feedforward_inertia: float = 0.0
    position_gain: float = 0.0

    @classmethod
    def tuned(cls, inertia: float, bandwidth_Hz: float, feedforward: bool = True,
              position_loop: bool = False) -> "PIController":
        """A loop tuned on the rigid inertia.

        Crossover at ``bandwidth_Hz``, the PI zero a quarter below it; with
        ``position_loop`` a position gain of a sixth of the crossover (about 55° phase margin).

        Parameters
        ----------
        inertia : float
            Rigid inertia seen by the motor [kg·m²].
        bandwidth_Hz : float
            Speed-loop crossover [Hz].
        feedforward : bool
            Add the acceleration feedforward ``inertia · α_ref``.
        position_loop : bool
            Add the outer position loop.
        """
        wc = TWO_PI * bandwidth_Hz
        kp = inertia * wc
        return cls(kp=kp, ki=kp * wc / 4.0, feedforward_inertia=inertia if feedforward else 0.0,
                   position_gain=wc / 6.0 if position_loop else 0.0)

    def command(self, w_ref, th_ref, th_w):
        """Speed command [rad/s] of the inner loop from the reference speed [rad/s],
        reference angle [rad] and WG angle [rad]."""
        return w_ref + self.position_gain * (th_ref - th_w) if self.position_gain else w_ref
