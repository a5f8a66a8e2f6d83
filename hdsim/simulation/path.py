"""Equations of motion: the elastic path and the locked-wave-generator bench as an ODE system.

A system is a right-hand side ``rhs(t, y)`` over named states plus a function that
computes labelled output signals from a solution. It is built once per (batch)
model: parameters are flattened to floats/arrays here, not looked up per call.

Batches: with ``M`` parameter sets the state vector is laid out sample-major,
``y[m * n + i]`` = state ``i`` of sample ``m``, so the Jacobian is block diagonal
with ``n × n`` blocks: `ODESystem.block_jacobian` and `hdsim.simulation.block_radau`
keep the linear algebra O(M).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import sparse

from hdsim.model.drive import HarmonicDrive
from hdsim.model.parameters import float_if_scalar


class _Body:
    """The flexspline body as the dead zone sees it: spring with its friction, and damper."""

    def __init__(self, path: "ElasticPath", friction_states):
        self.path = path
        self.friction_states = friction_states
        self.base_stiffness = path.base_tangent

    def static(self, body_twist):
        return self.path.model.friction.body_torque(self.path.spring_law, body_twist, self.friction_states)

    def coefficient(self, body_twist, spring_tangent):
        return self.path.damping_coefficient(spring_tangent)

    def path_tangent(self, direction, spring_torque, spring_tangent):
        return self.path.model.friction.path_tangent(self.friction_states, direction, spring_torque,
                                                     spring_tangent)


@dataclass(frozen=True)
class ElasticPath:
    """Torque through the drive as a function of output-side twist, rate and path states.

    One arrangement for every combination of effects (docs/physics.md §7)::

        output ── dead zone ── body [spring u(e − slip) + friction torque ∥ damper c(e) ė] ── mesh

    The backlash effect carries the series connection (`Backlash.transmit`), the
    friction effect the body's hysteresis (`Friction.body_torque`, `Friction.rates`),
    the hardening effect the spring law and the damping effect the coefficient; this
    class only wires them. States: the friction states, then the backlash states.
    """

    model: HarmonicDrive

    def __post_init__(self):
        model = self.model
        c_struct, c_mesh = (float_if_scalar(c) for c in model.split())
        object.__setattr__(self, "c_struct", c_struct)
        object.__setattr__(self, "c_mesh", c_mesh)
        object.__setattr__(self, "spring_law", model.hardening.spring_law(c_struct, c_mesh))
        # stiffness at zero twist: the dead zone's stiffness in contact and the damping reference
        object.__setattr__(self, "base_tangent", float_if_scalar(model.hardening.tangent(0.0, c_struct, c_mesh)))
        object.__setattr__(self, "n_friction", len(model.friction.state_names))
        # asked at every evaluation of the right-hand side; the effect does not change
        object.__setattr__(self, "damping_follows_stiffness", model.damping.follows_stiffness)

    @property
    def states(self) -> tuple[str, ...]:
        """Names of the path's ODE states (friction memory, then the backlash states)."""
        model = self.model
        return tuple(f"friction.{n}" for n in model.friction.state_names) + \
            tuple(f"backlash.{n}" for n in model.backlash.state_names)

    @property
    def state_units(self) -> tuple[str, ...]:
        """Unit of each of `states`, "rad" or "N·m" (sets the solver's tolerances)."""
        model = self.model
        return (model.friction.state_unit,) * len(model.friction.state_names) + \
            (model.backlash.state_unit,) * len(model.backlash.state_names)

    def spring(self, twist):
        """Spring torque [N·m] at body (elastic) twist ``twist`` [rad]."""
        return self.spring_law(twist)[0]

    def damping_coefficient(self, spring_tangent):
        """Damping coefficient [N·m·s/rad] of the body where the spring's tangent is ``spring_tangent``."""
        damping = self.model.damping
        if not self.damping_follows_stiffness:
            return damping.coefficient_at(1.0)
        return damping.coefficient_at(spring_tangent / self.base_tangent)

    def evaluate(self, twist, twist_rate, states):
        """(torque [N·m], state rates, series friction twist [rad]) at the output twist and rate."""
        model = self.model
        if not isinstance(states, list):  # a single model's states stay a list of floats
            states = np.asarray(states) if len(states) else np.zeros((0,) + np.shape(twist))
        friction_states, backlash_states = states[:self.n_friction], states[self.n_friction:]
        body = _Body(self, friction_states)
        torque, body_twist, body_rate, spring_torque, tangent, backlash_rates = \
            model.backlash.transmit(twist, twist_rate, backlash_states, body)
        friction_rates = model.friction.rates(friction_states, body_rate, spring_torque, tangent)
        return torque, tuple(friction_rates) + tuple(backlash_rates), model.friction.series_slip(friction_states)

    def settled(self, twist, states):
        """Path states with the backlash states in balance with the body at output twist
        ``twist`` [rad]: the initial condition of a drive that starts twisted."""
        states = np.asarray(states, dtype=float) if len(states) else np.zeros((0,) + np.shape(twist))
        friction_states = states[:self.n_friction]
        backlash_states = self.model.backlash.settle(twist, states[self.n_friction:],
                                                     _Body(self, friction_states))
        return np.concatenate([friction_states, backlash_states])

    def body_twist(self, twist, states):
        """Twist of the body behind the dead zone [rad] (the output twist without a gap)."""
        states = np.asarray(states) if len(states) else np.zeros((0,) + np.shape(twist))
        body = _Body(self, states[:self.n_friction])
        return self.model.backlash.transmit(twist, np.zeros_like(np.asarray(twist, dtype=float)),
                                            states[self.n_friction:], body)[1]

    def stored_energy(self, twist, states, nodes: int = 6, panels: int = 48):
        """Energy stored in the path [J] at output twist ``twist`` and path ``states``.

        ``V = ∫₀^ε u(x) dx`` at the spring's elastic twist ``ε = e − slip``, by composite
        Gauss–Legendre (the smoothed knees are resolved by the panels), plus what the
        dead zone's contact compliance holds; element-wise on arrays. Energy held by
        friction elements counts as dissipated.
        """
        states = np.asarray(states) if len(states) else np.zeros((0,) + np.shape(twist))
        elastic = np.asarray(self.body_twist(twist, states) - self.model.friction.series_slip(
            states[:self.n_friction]), dtype=float)
        xi, wi = np.polynomial.legendre.leggauss(nodes)
        edges = np.linspace(0.0, 1.0, panels + 1)
        s = (0.5 * (edges[:-1, None] + edges[1:, None]) + 0.5 * (edges[1:, None] - edges[:-1, None]) * xi).ravel()
        w = (0.5 * (edges[1:, None] - edges[:-1, None]) * wi).ravel()
        cs = self.c_struct[..., None] if np.ndim(self.c_struct) else self.c_struct
        cm = self.c_mesh[..., None] if np.ndim(self.c_mesh) else self.c_mesh
        torque = self.model.hardening.torque(elastic[..., None] * s, cs, cm)
        contact = self.model.backlash.stored_energy(states[self.n_friction:], self.base_tangent)
        return elastic * np.sum(torque * w, axis=-1) + contact


@dataclass
class ODESystem:
    """A right-hand side with named states, initial state and output signals."""

    setup: str
    state_names: tuple[str, ...]
    batch: int
    rhs: Callable
    y0: np.ndarray
    outputs: Callable  # (t, states dict of (M, nt)) -> dict of signals
    state_scales: np.ndarray  # typical magnitude of each state, for atol

    @property
    def n_states(self) -> int:
        return len(self.state_names)

    def block_jacobian(self, t, y):
        """Sparse block-diagonal Jacobian by forward differences, one column per state.

        Samples are independent, so perturbing state ``i`` of every sample at once
        gives column ``i`` of every block: ``n`` right-hand-side calls for any batch
        size, and the sparse matrix is assembled directly (scipy's generic sparse
        finite differences spend most of their time searching the matrix).
        """
        n, M = self.n_states, self.batch
        f0 = self.rhs(t, y)
        x = y.reshape(M, n)
        step = 1.49e-8 * np.maximum(np.abs(x), self.state_scales)
        blocks = np.empty((M, n, n))
        for i in range(n):
            xp = x.copy()
            xp[:, i] += step[:, i]
            blocks[:, :, i] = (self.rhs(t, xp.ravel()) - f0).reshape(M, n) / step[:, i:i + 1]
        rows = (np.arange(M)[:, None, None] * n + np.arange(n)[None, :, None]).repeat(n, axis=2)
        cols = (np.arange(M)[:, None, None] * n + np.arange(n)[None, None, :]).repeat(n, axis=1)
        return sparse.csc_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(n * M, n * M))

    def unpack(self, Y: np.ndarray) -> dict[str, np.ndarray]:
        """Solver output (n·M, nt) to {state name: (M, nt)}."""
        Y = Y.reshape(self.batch, self.n_states, -1)
        return {name: Y[:, i, :] for i, name in enumerate(self.state_names)}


def pack_rates(rates: list, n: int, M: int) -> np.ndarray:
    """The state rates (one entry per state, in order: floats for a single model, (M,) arrays or
    scalars for a batch) as the solver's sample-major vector of length ``n·M``."""
    if M == 1:
        try:
            return np.array(rates, dtype=float)  # a single model's floats: one call
        except ValueError:  # a batch of one row: (1,) arrays among them, placed one by one
            pass
    dx = np.empty((n, M))
    for i, r in enumerate(rates):
        dx[i] = r
    return dx.T.ravel()


def locked_wave_generator(model: HarmonicDrive, torque: Callable) -> ODESystem:
    """Stiffness-test bench: WG locked, circular spline fixed, torque on the output.

    States: output angle θ [rad] (= the twist, since the mesh is held), output speed
    ω [rad/s], then the friction states. ``J_out ω̇ = T(t) − τ_drive(θ, ω, z)``.
    ``torque(t)`` returns the applied output torque [N·m] (scalar or per sample).
    """
    path = ElasticPath(model)
    M = model.batch_size
    names = ("theta_out", "omega_out") + path.states
    n = len(names)
    J = np.asarray(model.drive.J_out, dtype=float)
    J = float(J) if J.size == 1 else J  # a float for the scalar path

    def rhs(t, y):
        # one sample: Python floats through the laws (numpy on 1-element arrays costs ~4x),
        # as on the driven bench
        x = y.tolist() if M == 1 else y.reshape(M, n).T
        theta, omega = x[0], x[1]
        tau, rates, _ = path.evaluate(theta, omega, x[2:])
        return pack_rates([omega, (torque(t) - tau) / J, *rates], n, M)

    def outputs(t, states):
        # evaluate with time first, (nt, M), so per-sample parameters (M,) broadcast
        theta, omega = states["theta_out"].T, states["omega_out"].T
        fstates = np.array([states[s].T for s in path.states]).reshape(-1, *theta.shape)
        tau, _, hysteretic = path.evaluate(theta, omega, fstates)
        applied = np.broadcast_to(torque(t[:, None]), theta.shape)  # profiles are vectorised in t
        signals = {"torque_Nm": applied, "twist_rad": theta, "drive_torque_Nm": tau,
                   "hysteretic_twist_rad": np.broadcast_to(hysteretic, theta.shape)}
        return {name: np.ascontiguousarray(value.T) for name, value in signals.items()}

    torque_scale = np.max(np.asarray(model.drive.rated_torque)) * 1e-2
    theta_scale = np.max(torque_scale / np.asarray(model.base_stiffness))
    omega_scale = theta_scale * np.max(np.sqrt(np.asarray(model.base_stiffness) / J))
    path_scales = [torque_scale if unit == "N·m" else theta_scale for unit in path.state_units]
    scales = np.array([theta_scale, omega_scale] + path_scales)
    return ODESystem("locked_wave_generator", names, M, rhs, np.zeros(n * M), outputs, scales)
