"""Integrate an `hdsim.simulation.path.ODESystem` with ``solve_ivp``; raise on failure.

Returns a `SimulationResult` with labelled arrays: states and output
signals of shape ``(M, nt)`` for a batch of ``M`` parameter sets (``(nt,)`` views
via `SimulationResult.signal` for a single model). A driven run integrates in
segments whose step bound follows the forcing (`step_schedule`, `integrate_segments`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from scipy.integrate import solve_ivp
from threadpoolctl import threadpool_limits

from hdsim.simulation.block_radau import BlockDiagonalRadau, DenseRadau
from hdsim.simulation.path import ODESystem
from hdsim.errors import InputError, SolverError

TWO_PI = 2.0 * np.pi


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

    #: the methods that can integrate the model: the dead zone's contact and a damped body
    #: behind it give time constants of ~1e-10 s, which an explicit method (RK45, RK23,
    #: DOP853) would have to resolve step by step, for hours
    IMPLICIT: ClassVar[tuple[str, ...]] = ("Radau", "BDF", "LSODA")

    def __post_init__(self):
        if self.method not in self.IMPLICIT:
            raise InputError(f"solver method '{self.method}' is explicit or unknown: the contact of the "
                             f"dead zone is stiff (time constants of ~1e-10 s); use one of "
                             f"{', '.join(self.IMPLICIT)}")
        for name in ("rtol", "atol_scale", "max_step"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0 and value == value):
                raise InputError(f"solver {name} must be a positive number, got {value!r}")

    def replace(self, **kw) -> "SolverOptions":
        """A copy with the given fields changed."""
        return dataclasses.replace(self, **kw)


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
        """Number of runs M in the batch."""
        # a quasi-static run has signals but no ODE states
        return next(iter({**self.signals, **self.states}.values())).shape[0]

    def signal(self, name: str, sample: int = 0) -> np.ndarray:
        """One time series of sample ``sample`` (state or output signal)."""
        source = self.signals if name in self.signals else self.states
        return np.asarray(source[name])[sample]


def integrate(system: ODESystem, t_span, t_eval=None, options: SolverOptions | None = None) -> SimulationResult:
    """Integrate a system with ``solve_ivp``.

    Parameters
    ----------
    system : ODESystem
        The system (single or batch); integrated from its ``y0``.
    t_span : tuple
        (start, end) [s].
    t_eval : numpy.ndarray, optional
        Output times [s]; default the solver's own steps.
    options : SolverOptions, optional
        Method and tolerances (default `SolverOptions`).

    Returns
    -------
    SimulationResult
        States and output signals of shape (M, nt), solver statistics.

    Raises
    ------
    SolverError
        If the solver stops early or the solution is not finite.
    """
    options = options or SolverOptions()
    n, M = system.n_states, system.batch
    atol = np.tile(options.atol_scale * system.state_scales, M)
    kwargs = dict(method=options.method, rtol=options.rtol, atol=atol, max_step=options.max_step)
    if M > 1 and options.method == "LSODA":
        kwargs.update(lband=n - 1, uband=n - 1)
    elif M > 1 and options.method == "Radau":
        kwargs.update(method=BlockDiagonalRadau, block_size=n, jac=system.block_jacobian)
    elif options.method == "Radau":
        kwargs.update(method=DenseRadau)
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


# ------------------------------------------------------------------ segmented integration
#: steps per WG revolution (and per period of a load sweep's top frequency) that bound the
#: solver's step when the options set no max_step: Radau steps over the kinematic error's
#: 4× harmonic otherwise, and its dense output between steps is then off by ~0.1 arcsec;
#: with 32 steps per WG turn it is within ~0.01 arcsec
STEPS_PER_WG_REV = 32
STEPS_PER_SWEEP_PERIOD = 8


def step_schedule(bench, options: SolverOptions) -> list[tuple[float, float, SolverOptions]]:
    """Time segments of a driven run and the solver options of each.

    ``max_step`` is bounded by the WG speed and, during a load sweep, by the sweep's
    frequency in that segment (one segment per octave), unless ``options`` set
    ``max_step``: Radau's error estimate does not see a forcing it steps over.

    Parameters
    ----------
    bench : hdsim.simulation.driven.Bench
        The bench: its ``t_end`` [s], ``motion.max_speed`` [rad/s] and
        ``load.frequency_schedule`` are read.
    options : SolverOptions
        The run's options.

    Returns
    -------
    list of tuple
        ``(t_start [s], t_end [s], options)`` covering ``[0, bench.t_end]``.
    """
    if np.isfinite(options.max_step):
        return [(0.0, bench.t_end, options)]
    motion_limit = (TWO_PI / (STEPS_PER_WG_REV * bench.motion.max_speed) if bench.motion.max_speed > 0.0
                    else np.inf)
    pieces = bench.load.frequency_schedule or [(0.0, bench.t_end, 0.0)]
    out = []
    for a, b, f in pieces:
        limit = min(motion_limit, 1.0 / (STEPS_PER_SWEEP_PERIOD * f) if f > 0.0 else np.inf)
        out.append((a, b, options.replace(max_step=limit) if np.isfinite(limit) else options))
    return out


def integrate_segments(system: ODESystem, schedule, t_eval) -> SimulationResult:
    """`integrate` over consecutive segments, each with its own options, the state carried across.

    Parameters
    ----------
    system : ODESystem
        The system; its ``y0`` is restored afterwards.
    schedule : list of tuple
        ``(t_start [s], t_end [s], SolverOptions)``, consecutive (`step_schedule`).
    t_eval : numpy.ndarray
        Output times [s] over the whole schedule.

    Returns
    -------
    SimulationResult
        One result on ``t_eval``; ``solver`` sums the evaluation counts over the
        segments and gives their number as ``segments`` (if more than one).
    """
    if len(schedule) == 1:
        a, b, options = schedule[0]
        return integrate(system, (a, b), t_eval, options)
    y0 = system.y0.copy()
    times, parts, solver = [], [], {}
    try:
        for k, (a, b, options) in enumerate(schedule):
            last = k == len(schedule) - 1
            inside = t_eval[(t_eval >= a) & ((t_eval <= b) if last else (t_eval < b))]
            sub = integrate(system, (a, b), np.concatenate([inside, [b]]) if not last else inside, options)
            system.y0 = np.array([sub.states[name][:, -1] for name in system.state_names]).T.ravel()
            times.append(inside)
            parts.append({name: values[:, :inside.size] for name, values in sub.states.items()})
            for key in ("nfev", "njev", "nlu"):
                solver[key] = solver.get(key, 0) + sub.solver[key]
            solver.update(method=sub.solver["method"], rtol=sub.solver["rtol"], message=sub.solver["message"])
    finally:
        system.y0 = y0
    t = np.concatenate(times)
    states = {name: np.concatenate([p[name] for p in parts], axis=1) for name in system.state_names}
    solver["segments"] = len(schedule)
    return SimulationResult(t=t, states=states, signals=system.outputs(t, states), setup=system.setup,
                            solver=solver)
