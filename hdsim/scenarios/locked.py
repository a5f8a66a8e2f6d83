"""The locked-wave-generator bench (set-up ``locked_wave_generator``): stiffness and lost-motion tests.

The WG is held and a torque cycle 0 → +A → −A → … → 0 is applied to the output
(`hdsim.scenarios.scenario.Scenario.levels`, cosine ramps at a mean rate); the metrics
are read from the torque–twist loop (`hdsim.scenarios.locked_metrics`, docs/physics.md,
"Test definitions").
"""

from __future__ import annotations

import warnings

import numpy as np

from hdsim.errors import InputError, SlowRunWarning
from hdsim.model.drive import HarmonicDrive
from hdsim.scenarios.limits import refuse_if_too_large
from hdsim.scenarios.locked_metrics import METRIC_GROUPS, locked_metrics, stiffness_fit_unreachable
from hdsim.scenarios.setups import Setup
from hdsim.simulation.driven import sample_model
from hdsim.simulation.path import locked_wave_generator
from hdsim.simulation.quasistatic import first_mode_period, locked_twist, sticking_tangent
from hdsim.simulation.solver import SimulationResult, SolverOptions, integrate

LOCKED_SETUP = "locked_wave_generator"

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
    _refuse_if_too_large(source, load, samples_per_segment)


def _refuse_if_too_large(source: str, load: dict, samples_per_segment: int, batch: int = 1,
                         max_step: float | None = None) -> None:
    """`refuse_if_too_large` for a torque cycle (``max_step``: the solver's bound, for its step count)."""
    duration = _duration(load)
    refuse_if_too_large(source, samples=_samples(load["cycles"], samples_per_segment), duration=duration,
                        batch=batch, min_steps=0.0 if max_step is None else duration / max_step,
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


#: a torque ramp shorter than this many periods of the output's first mode is no static
#: test: the inertial torque of a cosine ramp of duration D is ``(T_n / 2D)² / 2`` of the
#: elastic one, 1.3e-3 at D = 10 T_n, and the loop's metrics (K1, lost motion) would read
#: the drive's vibration (a rate of 1e3 T_N/s gave a negative lost motion)
MIN_PERIODS_PER_RAMP_RUN = 10.0


def refuse_if_no_stiffness_fit(model: HarmonicDrive, scenario) -> None:
    """Refuse, before the run, stiffness metrics that the cycle cannot give
    (`stiffness_fit_unreachable`: the ±4 % cycle never loads to T1/2, where the fit starts)."""
    if "stiffness" not in scenario.metrics:
        return
    T1, T2 = (np.broadcast_to(v, (model.batch_size,)) for v in breakpoints(model))
    rated = np.broadcast_to(np.asarray(model.drive.rated_torque, dtype=float), (model.batch_size,))
    amplitude = float(scenario.data["load"]["amplitude"])
    short = amplitude * rated <= 0.5 * T1  # the rule of `stiffness_fit_unreachable`, for every sample at once
    if np.any(short):
        m = int(np.argmax(short))
        reason = stiffness_fit_unreachable(amplitude, T1[m], T2[m], rated[m])
        raise InputError(f"{scenario.source}: {reason}" + (f" (sample {m} of the batch)" if model.batch_size > 1
                                                           else ""))


def refuse_if_not_static(model: HarmonicDrive, scenario) -> None:
    """Refuse a torque cycle loaded so fast that the test is no longer static (`InputError`,
    with the ramp, the mode's period and the fastest rate that stays static)."""
    load = scenario.data["load"]
    period = first_period(model, load["amplitude"])
    ramp = float(np.min(np.diff(scenario.times())))
    if ramp < MIN_PERIODS_PER_RAMP_RUN * period:
        fastest = load["rate"] * ramp / (MIN_PERIODS_PER_RAMP_RUN * period)
        raise InputError(f"{scenario.source}: load.rate = {load['rate']:g} T_N/s makes a torque ramp of "
                         f"{ramp:.3g} s, {ramp / period:.2g} periods of the drive's first mode ({period:.3g} s): "
                         f"the test would read the drive's vibration, not its stiffness; a static test needs "
                         f"load.rate <= {fastest:.3g}")


# ------------------------------------------------------------------ why a dynamic run is slow
#: A friction law that sticks much stiffer than the spring (a Dahl law fitted to a stiffness
#: record whose loop shows no presliding: sigma 1.3e8 N·m/rad on a 2e4 N·m/rad spring) puts
#: the output inertia on a stiff mode (40 kHz there, 57 kHz against a reversal). Its stiffness
#: is one-sided, 2σ against the reversal and ~0 with it, and only the friction's own loss,
#: which vanishes at small amplitude, takes energy out. Without damping the mode rings after
#: each reversal, and while its swing in speed exceeds the ramp's own slow speed the speed
#: changes sign on every swing: the solver follows each switch of the friction's direction
#: step by step. That is the model's physics, not the solver's setup (at 510×: rtol 1e-4
#: 67,000 evaluations a cycle, 1e-8 1.6 million, LSODA 480,000; BDF 48,000, but Radau is the
#: default for the lightly damped mode, `SolverOptions`), and the dynamic run pays for it.
#: Measured on the ±4 % test, per torque cycle (rhs evaluations): 164,000 sticking at 510×
#: the spring undamped, 1.1 million at 6600× (2–3 min for the test); at 6600× a damping
#: ratio of the stick mode of 1e-4 brings it to 91,000, of 3e-5 only to 580,000. An undamped
#: mode is slow however soft the sticking: the default unit without damping took 38 s for
#: the whole ±4 % test (211,000 evaluations, 1.2 s with its damping) and 3.5 min for the
#: stiffness test, a Dahl law at 250× undamped 29 s. A run whose mode is damped below
#: `SLOW_DAMPING_RATIO` says so before it starts (`SlowRunWarning`); above
#: `SLOW_STICKING_RATIO` the message names the sticking friction as the cause.
SLOW_STICKING_RATIO = 300.0
SLOW_DAMPING_RATIO = 5e-5


def sticking_mode(model: HarmonicDrive) -> dict[str, float]:
    """The output on its sticking friction: the friction's path tangent at rest over the
    spring's stiffness, the mode's frequency [Hz] and its damping ratio. Of a batch, the
    sample that will be slowest: the one of largest ratio among those damped below
    `SLOW_DAMPING_RATIO` (a stiffer sample may be damped enough while a softer one rings),
    else the one of largest ratio."""
    # a batch may vary the geometry, the friction or the damping: each broadcast to the batch
    K, tangent = sticking_tangent(model)
    J, c = (np.broadcast_to(np.asarray(value, dtype=float), K.shape)
            for value in (model.drive.J_out, model.damping.coefficient_at(1.0)))
    ratio = tangent / K
    damping = c / (2.0 * np.sqrt(tangent * J))
    ringing = damping < SLOW_DAMPING_RATIO
    m = int(np.argmax(np.where(ringing, ratio, -np.inf))) if ringing.any() else int(np.argmax(ratio))
    return {"sticking_ratio": float(ratio[m]), "frequency_Hz": float(np.sqrt(tangent[m] / J[m]) / (2 * np.pi)),
            "damping_ratio": float(damping[m])}


def slow_run_reason(model: HarmonicDrive) -> str | None:
    """Why a dynamic run of ``model`` on this bench will be slow, or None (`SLOW_DAMPING_RATIO`)."""
    mode = sticking_mode(model)
    if mode["damping_ratio"] >= SLOW_DAMPING_RATIO:
        return None
    cause = (f"its friction sticks at {mode['sticking_ratio']:.3g} times the spring's stiffness and the output rings "
             f"on it" if mode["sticking_ratio"] > SLOW_STICKING_RATIO else "the output rings on the spring")
    return (f"solve_ivp may take minutes on this drive: {cause} at {mode['frequency_Hz'] / 1e3:.3g} kHz, damped at a "
            f"ratio of {mode['damping_ratio']:.2g}; at every torque reversal the solver follows that ringing step by "
            f"step (the model's physics: docs/sensitivity.md, 'Which evaluator'). Where the loop's metrics are "
            f"what is needed, evaluator='quasistatic' gives them in a fraction of a second, and 'auto' takes it "
            f"where the docs' criterion says it agrees with solve_ivp")


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
    _refuse_if_too_large(scenario.source, scenario.data["load"], n, model.batch_size, options.max_step)
    refuse_if_not_static(model, scenario)
    refuse_if_no_stiffness_fit(model, scenario)
    reason = slow_run_reason(model)
    if reason:
        warnings.warn(reason, SlowRunWarning, stacklevel=3)  # at the caller of run_scenario
    rated = model.drive.rated_torque
    system = locked_wave_generator(model, scenario.torque_profile(rated))
    t_eval = scenario.sample_times(n)
    result = integrate(system, (t_eval[0], t_eval[-1]), t_eval, options)
    T1, T2 = breakpoints(model) if "stiffness" in scenario.metrics else (np.nan, np.nan)
    metrics = locked_metrics(scenario.metrics, result.signals["torque_Nm"], result.signals["twist_rad"],
                             scenario.levels(), n, T1, T2, rated)
    return scenario, result, metrics


# ------------------------------------------------------------------ quasi-static evaluator
#: a ramp at least this many periods of the output's first torsional mode long is loaded
#: quasi-statically: the inertial torque of a cosine ramp of duration D is
#: ``(T_n / 2D)² / 2`` of the elastic one, 1.3e-5 at D = 100 T_n
MIN_PERIODS_PER_RAMP = 100.0

#: the metric groups the quasi-static evaluator reproduces within 1e-3 relative
#: (docs/sensitivity.md, "Which evaluator": 1.4e-4 on 1024 rows of the seed study's box).
#: The others read the twist where the torque crosses zero, inside the dead zone's
#: boundary layer that dropping the inertia removes: hysteresis loss and centre-line lost
#: motion differ by ~1 %, K1 by ~2 %, and these stay with the dynamic model under "auto".
QUASISTATIC_GROUPS = ("lost_motion",)

#: quasi-static steps per ramp at least (the output samples are a subset of them): the
#: fitted damping rate and the sub-stepped friction laws agree with the dynamic model
#: within 1.4e-4 at 4 steps, 1.3e-4 at 8 and 1.2e-4 at 16 on the seed study's box
QUASISTATIC_STEPS_PER_RAMP = 4


def first_period(model: HarmonicDrive, amplitude: float) -> float:
    """Period [s] of the output's torsional mode at its stiffest over a ±amplitude·T_N cycle
    (`hdsim.simulation.quasistatic.first_mode_period` with the output's own inertia)."""
    return first_mode_period(model, amplitude * np.asarray(model.drive.rated_torque, dtype=float),
                             np.asarray(model.drive.J_out, dtype=float))


def quasistatic_criterion(model: HarmonicDrive, scenario):
    """Whether the quasi-static evaluator reproduces the dynamic one (`Setup.quasistatic_criterion`).

    It does when every ramp lasts `MIN_PERIODS_PER_RAMP` periods of the first mode
    (`first_period`), every metric group of the scenario is in `QUASISTATIC_GROUPS`, and
    the friction law does not say otherwise for the cycle's peak torque
    (`Friction.locked_quasistatic_limit`). Every friction, damping and hardening law runs in
    the quasi-static evaluator (`hdsim.simulation.quasistatic`).
    """
    period = first_period(model, scenario.data["load"]["amplitude"])
    ramp = float(np.min(np.diff(scenario.times())))
    figures = {"first_period_s": period, "shortest_ramp_s": ramp, "periods_per_ramp": ramp / period,
               "min_periods_per_ramp": MIN_PERIODS_PER_RAMP}
    if ramp < MIN_PERIODS_PER_RAMP * period:
        return False, (f"the shortest ramp ({ramp:.3g} s) is {ramp / period:.3g} periods of the first mode "
                       f"({period:.3g} s), under {MIN_PERIODS_PER_RAMP:g}: the inertia matters"), figures
    others = [g for g in scenario.metrics if g not in QUASISTATIC_GROUPS]
    if others:
        return False, (f"metric groups {others} read the twist at zero torque, where the quasi-static "
                       f"evaluator drops the dead zone's boundary layer"), figures
    peak = scenario.data["load"]["amplitude"] * np.asarray(model.drive.rated_torque, dtype=float)
    law = model.friction.locked_quasistatic_limit(peak)
    if law:
        return False, law, figures
    return True, (f"every ramp is at least {ramp / period:.3g} periods of the first mode ({period:.3g} s) "
                  f"and the metrics are read away from zero torque"), figures


def run_locked_quasistatic(model: HarmonicDrive, scenario, *, samples_per_segment: int | None = None,
                           options: SolverOptions | None = None):
    """Run a locked-WG scenario with the inertia dropped (`Setup.quasistatic_runner`).

    The torque cycle goes through `hdsim.simulation.quasistatic.locked_twist` on at
    least `QUASISTATIC_STEPS_PER_RAMP` steps per ramp, a multiple of the output samples,
    which are read off the steps themselves. Arguments and return as `run_locked`;
    ``options`` (the ``solve_ivp`` tolerances) do not apply. The result has no states
    and the signals ``torque_Nm``, ``twist_rad`` and ``drive_torque_Nm`` (= the applied
    torque: no inertia).
    """
    n = samples_per_segment or scenario.samples_per_segment
    _refuse_if_too_large(scenario.source, scenario.data["load"], n, model.batch_size)
    refuse_if_not_static(model, scenario)
    refuse_if_no_stiffness_fit(model, scenario)
    every = int(np.ceil(QUASISTATIC_STEPS_PER_RAMP / n))
    steps = scenario.sample_times(n * every)
    shape = scenario.torque_profile(1.0)(steps)
    rated = np.broadcast_to(np.asarray(model.drive.rated_torque, dtype=float), (model.batch_size,))
    if np.all(rated == rated[0]):
        twist = locked_twist(model, steps, shape * rated[0])
    else:  # one torque cycle per rated torque
        twist = np.concatenate([locked_twist(sample_model(model, m), steps, shape * rated[m])
                                for m in range(model.batch_size)])
    t_eval, twist = steps[::every], np.ascontiguousarray(twist[:, ::every])
    torque = np.ascontiguousarray(rated[:, None] * shape[None, ::every])
    signals = {"torque_Nm": torque, "twist_rad": twist, "drive_torque_Nm": torque}
    result = SimulationResult(t=t_eval, states={}, signals=signals, setup=LOCKED_SETUP,
                              solver={"method": "quasistatic", "steps_per_ramp": n * every})
    T1, T2 = breakpoints(model) if "stiffness" in scenario.metrics else (np.nan, np.nan)
    metrics = locked_metrics(scenario.metrics, torque, twist, scenario.levels(), n, T1, T2,
                             model.drive.rated_torque)
    return scenario, result, metrics


LOCKED = Setup(name=LOCKED_SETUP, schema=SCHEMA, required=REQUIRED, runner=run_locked,
               metrics=METRIC_GROUPS, check=check, quasistatic_runner=run_locked_quasistatic,
               quasistatic_criterion=quasistatic_criterion)
