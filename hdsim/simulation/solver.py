"""Integrate an `hdsim.simulation.path.ODESystem` with ``solve_ivp``; raise on failure.

Returns a `SimulationResult` with labelled arrays: states and output
signals of shape ``(M, nt)`` for a batch of ``M`` parameter sets (``(nt,)`` views
via `SimulationResult.signal` for a single model).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from threadpoolctl import threadpool_limits

from hdsim.simulation.block_radau import BlockDiagonalRadau
from hdsim.simulation.path import ODESystem
from hdsim.errors import SolverError


@dataclass(frozen=True)
class SolverOptions:
    """Options passed to ``solve_ivp``.

    Radau is the default: the drive is a lightly damped mode at hundreds of hertz
    inside a test lasting seconds; Radau is L-stable, while the higher-order BDF
    formulas inside LSODA and BDF lose stability near the imaginary axis. Batches use
    the block-diagonal variant (`hdsim.simulation.block_radau`). Measured figures are in
    docs/physics.md, "Numerics" (`python docs/make_physics_figures.py --solvers`);
    kinks in the laws cost far more than the choice of method.
    """

    method: str = "Radau"
    rtol: float = 1e-6
    atol_scale: float = 1e-6  # absolute tolerance = this × each state's typical magnitude
    max_step: float = np.inf

    def replace(self, **kw) -> "SolverOptions":
        from dataclasses import replace

        return replace(self, **kw)


@dataclass
class SimulationResult:
    """Time series of one run (or a batch of runs) with its provenance."""

    t: np.ndarray
    states: dict[str, np.ndarray]
    signals: dict[str, np.ndarray]
    setup: str
    solver: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)

    @property
    def batch(self) -> int:
        return next(iter(self.states.values())).shape[0]

    def signal(self, name: str, sample: int = 0) -> np.ndarray:
        """One time series of sample ``sample`` (state or output signal)."""
        source = self.signals if name in self.signals else self.states
        return np.asarray(source[name])[sample]


def integrate(system: ODESystem, t_span, t_eval=None, options: SolverOptions | None = None) -> SimulationResult:
    """Run ``solve_ivp`` on ``system``; raise `SolverError` unless it succeeds."""
    options = options or SolverOptions()
    n, M = system.n_states, system.batch
    atol = np.tile(options.atol_scale * system.state_scales, M)
    kwargs = dict(method=options.method, rtol=options.rtol, atol=atol, max_step=options.max_step)
    if M > 1 and options.method == "LSODA":
        kwargs.update(lband=n - 1, uband=n - 1)
    elif M > 1 and options.method == "Radau":
        kwargs.update(method=BlockDiagonalRadau, block_size=n, jac=system.block_jacobian)
    elif M > 1 and options.method == "BDF":
        kwargs.update(jac=system.block_jacobian)
    # BLAS threads buy nothing on these small vectors and, with several study processes on
    # a shared machine, spin-waiting OpenBLAS threads made steps 30x slower (measured).
    with threadpool_limits(limits=1, user_api="blas"), np.errstate(all="ignore"):
        # overflow in a diverging trial step is handled by the solver itself
        sol = solve_ivp(system.rhs, t_span, system.y0, t_eval=t_eval, **kwargs)
    if not sol.success or not np.all(np.isfinite(sol.y)):
        raise SolverError(f"{system.setup}: solve_ivp ({options.method}) stopped at "
                          f"t = {sol.t[-1] if sol.t.size else t_span[0]:.6g} s of {t_span[1]:.6g} s: "
                          f"{sol.message}")
    states = system.unpack(sol.y)
    signals = system.outputs(sol.t, states)
    solver = {"method": options.method, "rtol": options.rtol, "nfev": int(sol.nfev),
              "njev": int(sol.njev), "nlu": int(sol.nlu), "message": str(sol.message)}
    return SimulationResult(t=sol.t, states=states, signals=signals, setup=system.setup, solver=solver)
