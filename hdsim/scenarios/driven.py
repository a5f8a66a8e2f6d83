"""The driven-wave-generator bench (set-up ``driven_wave_generator``): scenario → bench → run.

A driven scenario's tables (`hdsim.scenarios.driven_schema`, every key in
docs/tutorial-kinematic-error.md) become a `hdsim.simulation.driven.Bench`: WG motion,
load, speed loop, WG-shaft friction (the drive's ``input_friction`` with the scenario's
``[input_friction]`` table applied on top, `hdsim.model.input_friction.for_unit`) and
output sampling, in SI. The runner integrates
it in segments (`hdsim.simulation.solver.step_schedule`) and computes the metric groups
the scenario lists (`hdsim.scenarios.driven_metrics`). Switches are the strings
``"yes"`` and ``"no"``; rpm, degrees and arcsec appear only in the scenario tables
and in metric names.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.model.drive import HarmonicDrive
from hdsim.model.input_friction import for_unit
from hdsim.scenarios.driven_metrics import DRIVEN_METRICS, driven_metrics
from hdsim.scenarios.driven_schema import DRIVEN_REQUIRED, DRIVEN_SCHEMA
from hdsim.scenarios.limits import refuse_if_too_large
from hdsim.scenarios.profile_csv import read_profile_csv
from hdsim.scenarios.setups import Setup
from hdsim.simulation.controller import PIController
from hdsim.simulation.driven import SETUP, Bench, scalar_ratio
from hdsim.simulation.driven_quasistatic import QUASISTATIC_GROUPS, criterion, driven_signals
from hdsim.simulation.loads import NO_LOAD, csv_load, opposing_load, ramped_load, step_load, sweep_load
from hdsim.simulation.motion import (constant_speed_motion, csv_motion, hold_motion, reversal_motion, sine_motion,
                                     sweep_motion, trapezoid_motion)
from hdsim.simulation.solver import SimulationResult, SolverOptions, integrate_segments, step_schedule
from hdsim.units import rpm_to_rad_per_s

TWO_PI = 2.0 * np.pi

_PROFILES = ("hold", "constant", "reversal", "trapezoid", "sine", "sweep", "csv")
_LOADS = ("none", "constant", "opposing", "step", "sweep", "csv")


def _positive(table, key, default, where, allow_zero=False):
    value = float(table.get(key, default))
    if not np.isfinite(value) or value < 0.0 or (value == 0.0 and not allow_zero):
        raise InputError(f"{where}: {key} must be {'>= 0' if allow_zero else '> 0'}, got {value:g}")
    return value


def _refuse_non_finite(data: dict, src) -> None:
    """Every number of the scenario's tables, in lists too, is finite: a NaN speed or load went
    on to the solver and failed there as the program's error. A list (orders, speeds, ripple
    amplitudes) holds numbers only."""
    for table, values in data.items():
        if not isinstance(values, dict):
            continue
        for key, value in values.items():
            items = value if isinstance(value, list) else [value]
            if isinstance(value, list) and not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                   for v in items):
                raise InputError(f"{src}: {table}.{key} must be a list of numbers, got {value!r}")
            if any(isinstance(v, float) and not np.isfinite(v) for v in items):
                raise InputError(f"{src}: {table}.{key} must be a finite number, got {value!r}")


def _check_tables(data: dict, src) -> None:
    """The ranges the runs' formulas need: an efficiency measured at a speed and a load (its
    ratio divides by both), at least one output sample per WG turn."""
    efficiency = data.get("efficiency", {})
    _positive(efficiency, "speed_rpm", 2000.0, f"{src}: efficiency")
    _positive(efficiency, "load", 1.0, f"{src}: efficiency")
    _positive(efficiency, "revolutions", 4.0, f"{src}: efficiency")
    if int(data.get("output", {}).get("samples_per_wg_rev", 64)) < 1:
        raise InputError(f"{src}: output.samples_per_wg_rev must be 1 or more")
    lin = data.get("linearise", {})
    if abs(float(lin.get("load", 0.0))) > 5.0:  # the same range as a load
        raise InputError(f"{src}: linearise.load is a fraction of T_N and must be within ±5")
    _positive(lin, "f_min_Hz", 1.0, f"{src}: linearise")
    compare = float(lin.get("compare_below", 0.8))
    if not 0.0 < compare <= 1.0:  # a share of the first resonance, below it
        raise InputError(f"{src}: linearise.compare_below is a share of the first resonance, in (0, 1]; "
                         f"got {compare:g}")
    load = data.get("load", {})
    if load.get("profile") == "opposing" and float(load.get("torque", 0.0)) < 0.0:
        raise InputError(f"{src}: an opposing load's torque is its size, a fraction of T_N > 0 (its sign "
                         f"follows the motion); got {float(load['torque']):g}")


def _refuse_contradictions(ctl: dict, position_loop: bool, src) -> None:
    """A controller table whose keys say two things: a position gain without the loop (it ran
    anyway) or the loop with a zero gain (it ran as none). (``kp`` and ``ki`` beside
    ``bandwidth_Hz`` are no contradiction: they replace the gains it tunes, so that a built-in
    scenario's loop can be retuned with ``--set``.)"""
    gain = ctl.get("position_gain_per_s")
    if gain is not None and not position_loop:
        raise InputError(f"{src}: controller.position_gain_per_s is the gain of the position loop, and "
                         "controller.position_loop is \"no\"; set it to \"yes\" or leave the gain out")
    if gain is not None and float(gain) == 0.0:
        raise InputError(f"{src}: controller.position_loop = \"yes\" with position_gain_per_s = 0 is no loop; "
                         "give a gain, or set position_loop = \"no\"")


def _yes(value, key, where) -> bool:
    if value not in ("yes", "no"):
        raise InputError(f"{where}: {key} must be \"yes\" or \"no\", got {value!r}")
    return value == "yes"


def _sweep_speeds(inp: dict, src) -> list[float]:
    """``input.speeds_rpm`` of a sweep, in rad/s: a non-empty list of finite non-zero numbers."""
    speeds = inp.get("speeds_rpm")
    if not speeds or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in speeds):
        raise InputError(f"{src}: input.speeds_rpm must be a non-empty list of WG speeds in rpm for a sweep")
    values = [float(v) for v in speeds]
    if not all(np.isfinite(v) and v != 0.0 for v in values):
        raise InputError(f"{src}: input.speeds_rpm must be finite and non-zero")
    return [rpm_to_rad_per_s(abs(v)) for v in values]


def bench_from_scenario(model: HarmonicDrive, scenario) -> Bench:
    """Read a driven scenario's tables into motion, load, controller and friction, in SI.

    Parameters
    ----------
    model : HarmonicDrive
        A single or batch model (one transmission ratio for the batch).
    scenario : hdsim.scenarios.scenario.Scenario
        A ``driven_wave_generator`` scenario; an ``input.csv`` path is relative to its file.

    Returns
    -------
    Bench
        The bench, its motion's windows holding the load's windows too.

    Raises
    ------
    InputError
        On an unknown metric, mode or profile, a value out of range, or a bad profile file.
    """
    src = scenario.source
    data = scenario.data
    _refuse_non_finite(data, src)
    _check_tables(data, src)
    for name in scenario.metrics:
        if name not in DRIVEN_METRICS:
            raise unknown_name(f"metric in scenario {scenario.name}", name, DRIVEN_METRICS)
    N = scalar_ratio(model)
    TN = np.asarray(model.drive.rated_torque, dtype=float)
    inp, ld = data.get("input", {}), data.get("load", {})
    mode = inp["mode"]
    if mode not in ("prescribed", "pi"):
        raise unknown_name(f"input.mode in {src}", mode, ("prescribed", "pi"))
    profile = inp["profile"]
    if profile not in _PROFILES:
        raise unknown_name(f"input.profile in {src}", profile, _PROFILES)
    load_kind = ld.get("profile", "none")
    if load_kind not in _LOADS:
        raise unknown_name(f"load.profile in {src}", load_kind, _LOADS)

    csv_data = None
    if profile == "csv" or load_kind == "csv":
        if "csv" not in inp:
            raise InputError(f"{src}: input.csv (the measured profile file) is required for a csv profile")
        csv_path = Path(inp["csv"])
        if not csv_path.is_absolute() and src != "<dict>":
            csv_path = Path(src).resolve().parent / csv_path
        csv_data = read_profile_csv(csv_path)
        if load_kind == "csv" and "torque" not in csv_data:
            raise InputError(f"{csv_path}: load.profile = \"csv\" needs a torque_Nm column")

    # ---------------------------------------------------------------- motion
    speed = rpm_to_rad_per_s(float(inp.get("speed_rpm", 0.0)))
    ramp = _positive(inp, "ramp_s", 0.2, src)
    if profile in ("constant", "reversal", "trapezoid") and speed == 0.0:
        raise InputError(f"{src}: input.speed_rpm must be non-zero for a {profile} profile")
    if profile == "constant":
        motion = constant_speed_motion(speed, N, ramp, _positive(inp, "output_revolutions", 1.0, src),
                                       _positive(inp, "settle_revolutions", 0.05, src, allow_zero=True))
    elif profile == "reversal":
        travel = _positive(inp, "output_revolutions", 1.0, src)
        settle = _positive(inp, "settle_revolutions", 0.05, src, allow_zero=True)
        if settle >= travel:  # the passes are measured over the travel less the settling: nothing in common
            raise InputError(f"{src}: input.settle_revolutions ({settle:g}) must be less than "
                             f"input.output_revolutions ({travel:g}): the two passes would share no angle")
        motion = reversal_motion(speed, N, ramp, travel, settle, _positive(inp, "dwell_s", 0.1, src, allow_zero=True))
    elif profile == "trapezoid":
        back = _yes(inp.get("return", "yes"), "input.return", src)
        move = np.deg2rad(float(inp.get("move_deg", 90.0)))
        if move == 0.0:
            raise InputError(f"{src}: input.move_deg must be non-zero")
        motion = trapezoid_motion(speed, N, move, ramp, _positive(inp, "dwell_s", 0.2, src), back)
    elif profile == "sine":
        motion = sine_motion(np.deg2rad(_positive(inp, "amplitude_deg", 1.0, src)) * N,
                             _positive(inp, "frequency_Hz", 1.0, src), _positive(inp, "cycles", 3.0, src),
                             _positive(inp, "dwell_s", 0.0, src, allow_zero=True))
    elif profile == "sweep":
        motion = sweep_motion(_sweep_speeds(inp, src), ramp, _positive(inp, "revolutions", 4.0, src),
                              _positive(inp, "settle_revolutions", 1.0, src, allow_zero=True),
                              _positive(inp, "dwell_s", 0.05, src, allow_zero=True))
    elif profile == "csv":
        motion = csv_motion(csv_data)
    else:
        motion = hold_motion(_positive(inp, "hold_s", 0.5, src))

    # ---------------------------------------------------------------- load
    torque = float(ld.get("torque", 0.0))
    if abs(torque) > 5.0:
        raise InputError(f"{src}: load.torque is a fraction of T_N and must be within ±5")
    load_ramp = _positive(ld, "ramp_s", 0.05, src)
    if load_kind == "none":
        load = NO_LOAD
    elif load_kind == "constant":
        load = ramped_load(torque * TN, load_ramp)
    elif load_kind == "opposing":
        cruise = motion.max_speed
        if cruise == 0.0:
            raise InputError(f"{src}: an opposing load needs a moving input profile")
        load = opposing_load(abs(torque) * TN, motion, _positive(ld, "smoothing", 0.05, src) * cruise, N)
    elif load_kind == "step":
        step_time = _positive(ld, "step_time_s", 0.2, src)
        load = step_load(torque * TN, float(ld.get("step_to", 0.5)) * TN, load_ramp, step_time,
                         _positive(ld, "rise_s", 0.002, src))
        if step_time <= load_ramp:
            raise InputError(f"{src}: load.step_time_s must come after the load ramp (load.ramp_s)")
    elif load_kind == "sweep":
        f0, f1 = _positive(ld, "f_start_Hz", 20.0, src), _positive(ld, "f_stop_Hz", 1500.0, src)
        if f1 <= f0:
            raise InputError(f"{src}: load.f_stop_Hz must exceed load.f_start_Hz")
        load = sweep_load(torque * TN, _positive(ld, "sweep_amplitude", 0.01, src) * TN, f0, f1, load_ramp,
                          _positive(ld, "settle_s", 0.1, src), _positive(ld, "sweep_s", 1.0, src),
                          _positive(ld, "tail_s", 0.2, src))
        t_s, t_e = load.windows["sweep"][0], load.t_end
        sweep_s = float(ld.get("sweep_s", 1.0))
        octaves = max(int(np.ceil(np.log2(f1 / f0))), 1)
        edges = t_s + sweep_s * np.arange(octaves + 1) / octaves
        schedule = [(0.0, t_s, 1.0 / load_ramp)]
        schedule += [(a, b, f0 * (f1 / f0) ** ((b - t_s) / sweep_s)) for a, b in zip(edges[:-1], edges[1:])]
        schedule.append((t_s + sweep_s, t_e, f1))
        load = replace(load, operating_point=torque, sweep_start=f0, frequency_schedule=schedule)
    else:
        load = csv_load(csv_data)
    load_inertia = _positive(ld, "inertia", 0.0, src, allow_zero=True)

    # ---------------------------------------------------------------- controller, friction
    controller = None
    ctl = data.get("controller", {})
    if mode == "pi":
        J_total = float(np.max(model.drive.J_in)) + (float(np.max(model.drive.J_out)) + load_inertia) / N**2
        position_loop = _yes(ctl.get("position_loop", "no"), "controller.position_loop", src)
        _refuse_contradictions(ctl, position_loop, src)
        base = PIController.tuned(J_total, _positive(ctl, "bandwidth_Hz", 30.0, src),
                                  _yes(ctl.get("feedforward", "yes"), "controller.feedforward", src), position_loop)
        controller = PIController(kp=_positive(ctl, "kp", base.kp, src), ki=_positive(ctl, "ki", base.ki, src,
                                                                                      allow_zero=True),
                                  feedforward_inertia=base.feedforward_inertia,
                                  position_gain=_positive(ctl, "position_gain_per_s", base.position_gain, src,
                                                          allow_zero=True))
    elif ctl:
        raise InputError(f"{src}: [controller] applies to input.mode = \"pi\" only")
    # the drive's own law (a fitted one included), the scenario's [input_friction] table on top
    friction = for_unit(model, data.get("input_friction"))

    t_end = max(motion.t_end, load.t_end)
    if load_kind == "csv" and load.t_end < motion.t_end - 1e-9:  # it would be held at its last value
        raise InputError(f"{src}: the measured load ends at {load.t_end:.4g} s, before the input profile "
                         f"({motion.t_end:.4g} s): a measured load is not extrapolated; give a file that covers "
                         "the run, or a shorter input profile")
    if load_kind == "step" and step_time >= t_end:
        raise InputError(f"{src}: load.step_time_s ({step_time:g} s) must come before the end of the "
                         f"input profile ({t_end:g} s)")
    if profile == "hold" and load.t_end and "hold_s" not in inp:
        motion = hold_motion(t_end)
    windows = {**motion.windows, **{k: (a, min(b, t_end)) for k, (a, b) in load.windows.items()}}
    motion = replace(motion, windows=windows)
    out = data.get("output", {})
    per_rev = int(out.get("samples_per_wg_rev", 64))
    rate = max(_positive(out, "sample_rate_Hz", 1000.0, src), per_rev * motion.max_speed / TWO_PI)
    return Bench(motion, load, mode, controller, friction, load_inertia, t_end, rate, scenario.metrics)


def run_driven(model: HarmonicDrive, scenario, *, samples_per_segment: int | None = None,
               options: SolverOptions | None = None):
    """Run a driven scenario (the runner of `DRIVEN`).

    Parameters
    ----------
    model : HarmonicDrive
        A single or batch model.
    scenario : hdsim.scenarios.scenario.Scenario
        A ``driven_wave_generator`` scenario.
    samples_per_segment : int, optional
        Overrides ``output.samples_per_wg_rev`` (the returned scenario carries it).
    options : SolverOptions, optional
        Solver options (the scenario's ``[solver]`` table applied); without ``max_step``
        the step is bounded per segment by `hdsim.simulation.solver.step_schedule`.

    Returns
    -------
    tuple
        (scenario as run, `hdsim.simulation.solver.SimulationResult` whose metadata holds
        the ``windows``, ``input_mode`` and ``profile``, metrics ``{name: (M,)}``).
    """
    if samples_per_segment:
        scenario = scenario.with_updates({"output.samples_per_wg_rev": int(samples_per_segment)})
    bench = bench_from_scenario(model, scenario)
    schedule = step_schedule(bench, options or SolverOptions())
    refuse_if_too_large(scenario.source, samples=np.ceil(bench.t_end * bench.sample_rate) + 1, duration=bench.t_end,
                        batch=model.batch_size, min_steps=sum((b - a) / o.max_step for a, b, o in schedule),
                        set_by="the input and load durations (revolutions, speeds, dwell, hold and sweep "
                               "times) and the output sampling")
    system = bench.system(model)
    t_eval = bench.sample_times()
    result = _with_bench_metadata(integrate_segments(system, schedule, t_eval), bench)
    metrics = driven_metrics(model, scenario, bench, result)
    return scenario, result, metrics


def run_driven_quasistatic(model: HarmonicDrive, scenario, *, samples_per_segment: int | None = None,
                           options: SolverOptions | None = None):
    """Run a driven scenario with the twist's inertia dropped (`Setup.quasistatic_runner`).

    The signals come from `hdsim.simulation.driven_quasistatic.driven_signals` at the output
    samples; ``options`` (the ``solve_ivp`` tolerances) do not apply. Arguments and return
    as `run_driven`; the result has no ODE states.
    """
    if samples_per_segment:
        scenario = scenario.with_updates({"output.samples_per_wg_rev": int(samples_per_segment)})
    bench = bench_from_scenario(model, scenario)
    if bench.mode != "prescribed":  # it would hold the motor on its reference: no following error at all
        raise InputError(f"{scenario.source}: the quasi-static evaluator moves the wave generator as "
                         f"prescribed; input.mode = \"{bench.mode}\" (a motor loop that yields) needs the "
                         "dynamic model (evaluator='dynamic' or 'auto')")
    # forced, it may run where its time scales do not hold; never for metrics it has no signals for
    # (a linearisation needs the states; a running torque, the input's dynamics)
    others = [g for g in bench.metrics if g not in QUASISTATIC_GROUPS]
    if others:
        raise InputError(f"{scenario.source}: the quasi-static evaluator does not compute the metric groups "
                         f"{', '.join(others)}; they need the dynamic model (evaluator='dynamic' or 'auto')")
    t_eval = bench.sample_times()
    refuse_if_too_large(scenario.source, samples=t_eval.size, duration=bench.t_end, batch=model.batch_size,
                        min_steps=t_eval.size, set_by="the input and load durations and the output sampling")
    result = _with_bench_metadata(SimulationResult(t=t_eval, states={}, signals=driven_signals(model, bench, t_eval),
                                                   setup=SETUP, solver={"method": "quasistatic"}), bench)
    return scenario, result, driven_metrics(model, scenario, bench, result)


def _with_bench_metadata(result: SimulationResult, bench) -> SimulationResult:
    """``result`` with the bench's metric windows, input mode and profile name in its metadata
    (both evaluators' runs carry them)."""
    result.metadata.update(windows={k: [float(a), float(b)] for k, (a, b) in bench.motion.windows.items()},
                           input_mode=bench.mode, profile=bench.motion.description)
    return result


def quasistatic_criterion(model: HarmonicDrive, scenario):
    """`hdsim.simulation.driven_quasistatic.criterion` on the scenario's bench (`Setup.quasistatic_criterion`)."""
    return criterion(model, bench_from_scenario(model, scenario))


def output_samples(model: HarmonicDrive, scenario) -> int:
    """Output samples of one run of the scenario (`Setup.output_samples`)."""
    return int(bench_from_scenario(model, scenario).sample_times().size)


DRIVEN = Setup(name=SETUP, schema=DRIVEN_SCHEMA, required=DRIVEN_REQUIRED, runner=run_driven,
               metrics=DRIVEN_METRICS, quasistatic_runner=run_driven_quasistatic,
               quasistatic_criterion=quasistatic_criterion, output_samples=output_samples)
