"""The locked-wave-generator bench (set-up ``locked_wave_generator``): stiffness and lost-motion tests.

The WG is held and a torque cycle 0 → +A → −A → … → 0 is applied to the output
(`hdsim.scenarios.scenario.Scenario.levels`, cosine ramps at a mean rate); the metrics
are read from the torque–twist loop (`hdsim.scenarios.locked_metrics`, docs/physics.md,
"Test definitions").
"""

from __future__ import annotations

import numpy as np

from hdsim.errors import InputError
from hdsim.model.drive import HarmonicDrive
from hdsim.scenarios.limits import refuse_if_too_large
from hdsim.scenarios.locked_metrics import METRIC_GROUPS, locked_metrics
from hdsim.scenarios.setups import Setup
from hdsim.simulation.path import locked_wave_generator
from hdsim.simulation.solver import SolverOptions, integrate

#: the scenario tables of this bench: the torque cycle, in fractions of the rated torque T_N
SCHEMA = {"load": {"amplitude": float, "cycles": int, "rate": float}}
REQUIRED = {"load": ("amplitude", "cycles", "rate")}


def check(data: dict, source: str) -> None:
    """Refuse a torque cycle out of range.

    Parameters
    ----------
    data : dict
        The scenario table, types already checked.
    source : str
        Where it came from, for the message.

    Raises
    ------
    InputError
        Amplitude outside (0, 5] × T_N, fewer than one cycle or a rate not above 0.
    """
    load = data["load"]
    if not 0.0 < load["amplitude"] <= 5.0:
        raise InputError(f"{source}: load.amplitude must be in (0, 5] (fraction of T_N)")
    if load["cycles"] < 1 or not 0.0 < load["rate"] < np.inf:  # NaN and inf fail too (a 0 s cycle)
        raise InputError(f"{source}: load.cycles must be >= 1 and load.rate a finite number > 0")
    _check_size(load, int(data.get("output", {}).get("samples_per_segment", 100)), source)
    if "lost_motion_centre_line" in data.get("metrics", []) and load["amplitude"] <= 0.04:
        raise InputError(f"{source}: lost_motion_centre_line reads the loop between ±4 % T_N and needs "
                         f"load.amplitude above 0.04 (it is {load['amplitude']:g})")


def breakpoints(model: HarmonicDrive):
    """The breakpoints (T1, T2) [N·m] at which the stiffness metrics split the loading branch.

    The hardening law's own breakpoints when it has them (so a changed ``hardening.T1``
    moves the metric with it), else the catalog values of a catalog unit.

    Raises
    ------
    InputError
        If neither is known.
    """
    hardening = model.hardening
    if hasattr(hardening, "T1") and hasattr(hardening, "T2"):
        return hardening.T1, hardening.T2
    catalog = model.provenance.get("catalog")
    if catalog:
        return catalog["T1"], catalog["T2"]
    raise InputError("stiffness metrics need breakpoints T1, T2: use a catalog unit or "
                     "a three_segment hardening effect")


#: more cycles than anyone measures; each crosses the dead zone twice at ~100 solver steps
#: (the other size limits are shared with the driven bench, `hdsim.scenarios.limits`)
MAX_CYCLES = 1_000


def _check_size(load: dict, samples_per_segment: int, source: str) -> None:
    """Refuse a torque cycle too large to run, with the estimate and the limit."""
    cycles = load["cycles"]
    if samples_per_segment < 2:
        raise InputError(f"{source}: output.samples_per_segment must be at least 2, got {samples_per_segment}")
    if cycles > MAX_CYCLES:
        raise InputError(f"{source}: load.cycles = {cycles} (limit {MAX_CYCLES}): each cycle crosses the "
                         "dead zone twice and costs the solver ~100 steps")
    refuse_if_too_large(source, samples=_samples(cycles, samples_per_segment), duration=_duration(load),
                        set_by="load.cycles, load.rate and output.samples_per_segment")


def _samples(cycles: int, samples_per_segment: int) -> int:
    return (2 * cycles + 1) * samples_per_segment + 1


def _duration(load: dict) -> float:
    return 4.0 * load["amplitude"] * load["cycles"] / load["rate"]  # |ΔL| sums to 4·A·cycles [s]


#: steps per torque ramp that bound the solver's step when the options set no ``max_step``.
#: Radau controls its error at the step ends; between them the metrics read its dense
#: output, a cubic, which over a 0.7 s step of a 2 s cosine ramp was 0.3 % off at the
#: turning points (a batch of two linear units, whose larger steps made it visible).
#: Four steps per shortest ramp bring it to the closed form within 1e-6 at the same cost.
STEPS_PER_RAMP = 4


def ramp_step_bound(scenario, options: SolverOptions | None) -> SolverOptions:
    """``options`` with ``max_step`` bounded to a quarter of the shortest ramp, unless set."""
    options = options or SolverOptions()
    if np.isfinite(options.max_step):
        return options
    return options.replace(max_step=float(np.min(np.diff(scenario.times()))) / STEPS_PER_RAMP)


def run_locked(model: HarmonicDrive, scenario, *, samples_per_segment: int | None = None,
               options: SolverOptions | None = None):
    """Run a locked-WG scenario (the runner of `LOCKED`).

    Parameters
    ----------
    model : HarmonicDrive
        A single or batch model.
    scenario : hdsim.scenarios.scenario.Scenario
        A ``locked_wave_generator`` scenario.
    samples_per_segment : int, optional
        Output samples per ramp; overrides ``output.samples_per_segment``.
    options : SolverOptions, optional
        Solver options (the scenario's ``[solver]`` table applied); without ``max_step``
        the step is bounded by `ramp_step_bound`.

    Returns
    -------
    tuple
        (scenario, `hdsim.simulation.solver.SimulationResult`, metrics ``{name: (M,)}``).
    """
    n = samples_per_segment or scenario.samples_per_segment
    options = ramp_step_bound(scenario, options)
    duration = _duration(scenario.data["load"])
    refuse_if_too_large(scenario.source, samples=_samples(scenario.data["load"]["cycles"], n), duration=duration,
                        batch=model.batch_size, min_steps=duration / options.max_step,
                        set_by="load.cycles, load.rate and output.samples_per_segment")
    rated = model.drive.rated_torque
    system = locked_wave_generator(model, scenario.torque_profile(rated))
    t_eval = scenario.sample_times(n)
    result = integrate(system, (t_eval[0], t_eval[-1]), t_eval, options)
    T1, T2 = breakpoints(model) if "stiffness" in scenario.metrics else (np.nan, np.nan)
    metrics = locked_metrics(scenario.metrics, result.signals["torque_Nm"], result.signals["twist_rad"],
                             scenario.levels(), n, T1, T2, rated)
    return scenario, result, metrics


LOCKED = Setup(name="locked_wave_generator", schema=SCHEMA, required=REQUIRED, runner=run_locked,
               metrics=METRIC_GROUPS, check=check)
