"""Equations of motion: the elastic path and the locked-wave-generator bench as an ODE system.

(The driven bench is `hdsim.simulation.driven`; it uses the same `ElasticPath` and `ODESystem`.)

A system is a right-hand side ``rhs(t, y)`` over named states plus a function that
computes labelled output signals from a solution. It is built once per (batch)
model: parameters are flattened to floats/arrays here, not looked up per call.

Batches: with ``M`` parameter sets the state vector is laid out sample-major,
``y[m * n + i]`` = state ``i`` of sample ``m``, so the Jacobian is block diagonal
with ``n × n`` blocks: `ODESystem.block_jacobian` and `hdsim.simulation.block_radau` keep the
linear algebra O(M).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, ClassVar

import numpy as np
from scipy import sparse

from hdsim.model.drive import HarmonicDrive


@dataclass(frozen=True)
class ElasticPath:
    """Torque through the drive as a function of output-side twist, rate and path states.

    Two arrangements of the dead zone (docs/physics.md §7):

    * **ElastoBacklash** (series or parallel friction effects): the spring and damper sit
      behind the dead zone as in Modelica's ElastoBacklash; the body has no state of its
      own and the contact rule keeps the damping from pulling.
    * **Body in series with the dead zone** (body friction, or no friction): the body
      (spring ∥ damper ∥ Dahl friction) carries the torque the dead zone transmits. With a
      damper the body twist lags and keeps relaxing while the output crosses the gap, so
      the body needs a state; it is ``backlash.closure`` (:meth:`_evaluate_series_body`).
    """

    model: HarmonicDrive
    #: contact compliance of the dead zone in the body-state form, as a share of 1/K₀:
    #: it keeps the closure state's equation regular in contact (time constant c·ε/K₀)
    #: and adds ε·T/K₀ of twist, 3e-8 rad at rated torque, far below encoder resolution
    contact_compliance_share: ClassVar[float] = 1e-5

    def __post_init__(self):
        model = self.model
        c_struct, c_mesh = model.split()
        object.__setattr__(self, "c_struct", c_struct)
        object.__setattr__(self, "c_mesh", c_mesh)
        # stiffness at zero twist: the body's rest twist in the gap is −z/K₀
        object.__setattr__(self, "base_tangent", model.hardening.tangent(0.0, c_struct, c_mesh))
        object.__setattr__(self, "load_dependent_damping",
                           model.damping.id != "none" and bool(np.any(np.asarray(model.damping.stiffness_share) != 0)))
        object.__setattr__(self, "series_body", model.friction.kind in ("body", "none")
                           and model.backlash.id != "none" and model.damping.id != "none")

    @property
    def states(self) -> tuple[str, ...]:
        """Names of the path's ODE states (friction memory, then the dead-zone closure)."""
        names = tuple(f"friction.{name}" for name in self.model.friction.state_names)
        return names + (("backlash.closure",) if self.series_body else ())

    @property
    def state_units(self) -> tuple[str, ...]:
        """Unit of each of :attr:`states`, "rad" or "N·m" (sets the solver's tolerances)."""
        units = (self.model.friction.state_unit,) * len(self.model.friction.state_names)
        return units + (("rad",) if self.series_body else ())

    def spring(self, twist):
        return self.model.hardening.torque(twist, self.c_struct, self.c_mesh)

    def damping_coefficient(self, twist):
        """Damping coefficient [N·m·s/rad] of the body at spring twist ``twist``."""
        if not self.load_dependent_damping:
            return self.model.damping.coefficient
        ratio = self.model.hardening.tangent(twist, self.c_struct, self.c_mesh) / self.base_tangent
        return self.model.damping.coefficient_at(ratio)

    def evaluate(self, twist, twist_rate, states):
        """(torque [N·m], state rates, hysteretic twist [rad])."""
        model = self.model
        friction = model.friction
        if self.series_body:
            return self._evaluate_series_body(twist, twist_rate, states)
        if friction.kind == "body":
            return self._evaluate_body(twist, twist_rate, states)
        hysteretic = friction.series_twist(states) if friction.kind == "series" else 0.0
        elastic_twist = twist - hysteretic
        engaged, contact = model.backlash.engage(elastic_twist)
        spring_torque = self.spring(engaged)
        elastic_rate = twist_rate
        rates: tuple = ()
        if friction.kind == "series":
            tangent = model.hardening.tangent(engaged, self.c_struct, self.c_mesh) * contact
            rates = friction.series_rates(states, twist_rate, tangent, spring_torque)
            elastic_rate = twist_rate - sum(rates)
        damping_torque = self.damping_coefficient(engaged) * elastic_rate * contact
        torque = model.backlash.contact_torque(spring_torque, damping_torque)
        if friction.kind == "parallel":
            torque = torque + friction.parallel_torque(states, twist_rate)
            rates = friction.parallel_rates(states, twist_rate)
        return torque, rates, hysteretic

    def _evaluate_body(self, twist, twist_rate, friction_states):
        """Dahl friction z in the body behind the dead zone, without a damper behind it.

        The body twist is ``e = engage(x − s) + s`` with the shift ``s = −z/K₀``: in
        contact the dead zone takes its half gap (``e = x ∓ b/2``), and in the gap the
        body rests where its spring holds the friction torque, ``u(e) ≈ K₀ s = −z``, so
        nothing is transmitted. Differentiating, with ``ż = D ė`` and ``D`` the Dahl
        slope, gives ``ė = κ ẋ / (1 + (1 − κ) D/K₀)``: the body follows the output in
        contact (κ = 1) and stands still in the gap (κ = 0). Without backlash ``e = x``
        and the torque is ``u(x) + z + c(x) ẋ``.
        """
        model = self.model
        z = friction_states[0]
        shift = -z / self.base_tangent
        engaged, contact = model.backlash.engage(twist - shift)
        slope = model.friction.body_slope(z, twist_rate)
        body_rate = contact * twist_rate / (1.0 + (1.0 - contact) * slope / self.base_tangent)
        torque = self.spring(engaged + shift) + z + self.damping_coefficient(engaged + shift) * body_rate
        return torque, (slope * body_rate,), 0.0

    def _evaluate_series_body(self, twist, twist_rate, states):
        """Body (spring ∥ damper ∥ optional Dahl) in series with the dead zone, state ``v``.

        The dead zone transmits ``T = K₀·dz(v)``, with ``dz`` the rounded dead zone and
        ``v`` the closure state, and takes the angle ``g = v − (1 − ε)·dz(v)``, an
        increasing function of ``T`` (``ε``: :attr:`contact_compliance_share`). The body
        twist is ``e = x − g`` and obeys its own balance, ``c(e) ė = T − u(e) − z``: in
        contact it follows the output, in the gap (``T = 0``) it relaxes on its own. From
        ``ẋ = ė + g'(v) v̇``, ``v̇ = (ẋ − ė)/(1 − (1 − ε) κ)``. Quasi-statically the output
        twist is ``e + dz⁻¹(T/K₀) − T/K₀``, as in :mod:`hdsim.simulation.quasistatic`.
        """
        model = self.model
        v = states[-1]
        closed, contact = model.backlash.engage(v)
        torque = self.base_tangent * closed
        body = twist - (v - (1.0 - self.contact_compliance_share) * closed)
        # a zero coefficient in a batch: relax within a microsecond instead of dividing by 0
        c = np.maximum(self.damping_coefficient(body), 1e-6 * self.base_tangent)
        has_friction = model.friction.kind == "body"
        z = states[0] if has_friction else 0.0
        body_rate = (torque - self.spring(body) - z) / c
        rates = (model.friction.body_slope(z, body_rate) * body_rate,) if has_friction else ()
        closure_rate = (twist_rate - body_rate) / (1.0 - (1.0 - self.contact_compliance_share) * contact)
        return torque, rates + (closure_rate,), 0.0


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

    def rhs(t, y):
        x = y.reshape(M, n).T
        theta, omega = x[0], x[1]
        tau, rates, _ = path.evaluate(theta, omega, x[2:])
        dx = np.empty((n, M))
        dx[0] = omega
        dx[1] = (torque(t) - tau) / J
        for i, r in enumerate(rates):
            dx[2 + i] = r
        return dx.T.ravel()

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
