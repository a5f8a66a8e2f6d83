"""Metrics of the driven-wave-generator bench: the metric groups a driven scenario may list.

Each group reads the time series of a run over the profile's windows and returns
arrays of shape (M,) in the units their names carry; the pure functions are in
`hdsim.scenarios.ke_metrics` (definitions in docs/tutorial-kinematic-error.md). The
linearisation groups compare the run with the linear model of
`hdsim.simulation.linearize`.
"""

from __future__ import annotations

import numpy as np

from hdsim.errors import InputError
from hdsim.model.drive import HarmonicDrive
from hdsim.scenarios import ke_metrics
from hdsim.simulation.driven import Bench, sample_model, scalar_ratio
from hdsim.simulation.linearize import drive_tangent_stiffness, linear_model, linear_summary, natural_frequencies
from hdsim.simulation.solver import SimulationResult
from hdsim.simulation.efficiency import efficiency
from hdsim.simulation.starting_torque import starting_torque
from hdsim.units import arcsec_to_rad, rad_per_s_to_rpm, rad_to_arcsec, rpm_to_rad_per_s

TWO_PI = 2.0 * np.pi
#: the metric groups a driven scenario may list
DRIVEN_METRICS = ("transmission_accuracy", "lost_motion_on_reversal", "windup", "order_spectrum",
                  "running_torque", "running_torque_sweep", "starting_torque", "backdriving_torque", "efficiency",
                  "linearisation", "frequency_response", "tracking",
                  "settling", "load_step", "oscillation")


def driven_metrics(model: HarmonicDrive, scenario, bench: Bench, result: SimulationResult) -> dict[str, np.ndarray]:
    """The metric groups a driven scenario lists.

    Parameters
    ----------
    model : HarmonicDrive
        The model that ran (single or batch).
    scenario : hdsim.scenarios.scenario.Scenario
        The scenario as run (its ``analysis`` and ``linearise`` tables are read).
    bench : Bench
        Its bench (`hdsim.scenarios.driven.bench_from_scenario`).
    result : SimulationResult
        The run.

    Returns
    -------
    dict
        ``{name: array of shape (M,)}`` in the units the names carry (arcsec, N·m, mN·m,
        Hz, s, rpm, deg; docs/tutorial-kinematic-error.md lists them).

    Raises
    ------
    InputError
        If a metric needs a window the profile does not have.
    """
    s = result.signals
    t = result.t
    windows = bench.motion.windows
    M = result.batch
    N = scalar_ratio(model)
    data = scenario.data
    analysis = data.get("analysis", {})
    out: dict[str, np.ndarray] = {}
    q = s["deviation_rad"]
    wg = s["wg_angle_rad"]

    def need(*names):
        missing = [w for w in names if w not in windows]
        if missing:
            raise InputError(f"{scenario.source}: these metrics need a profile with window(s) "
                             f"{', '.join(missing)} (have: {', '.join(windows) or 'none'})")
        return [windows[w] for w in names]

    def passes():
        if "forward" in windows:
            return [windows["forward"], windows["reverse"]]
        if "constant" in windows:
            return [windows["constant"]]
        raise InputError(f"{scenario.source}: this metric needs a constant or reversal profile")

    for group in bench.metrics:
        if group == "transmission_accuracy":
            values = [ke_metrics.transmission_accuracy(t, wg, q, w, N) for w in passes()]
            out["transmission_accuracy_arcsec"] = rad_to_arcsec(np.max(values, axis=0))
            if len(values) == 2:
                out["transmission_accuracy_forward_arcsec"] = rad_to_arcsec(values[0])
                out["transmission_accuracy_reverse_arcsec"] = rad_to_arcsec(values[1])
        elif group == "lost_motion_on_reversal":
            fwd, rev = need("forward", "reverse")
            out["lost_motion_on_reversal_arcsec"] = rad_to_arcsec(
                ke_metrics.lost_motion_on_reversal(t, wg, q, fwd, rev))
        elif group == "windup":
            values = [ke_metrics.window_mean(t, s["twist_rad"], w) for w in passes()]
            out["windup_arcsec"] = rad_to_arcsec(np.mean(np.abs(values), axis=0))
            out["windup_load_Nm"] = np.mean([np.abs(ke_metrics.window_mean(t, s["load_torque_Nm"], w))
                                             for w in passes()], axis=0)
        elif group == "order_spectrum":
            window = passes()[0]
            orders = [float(o) for o in analysis.get("orders", [1, 2, 4])]
            amps = ke_metrics.order_amplitudes(t, wg, q, window, N, orders + [1.0 / N])
            for o, a in zip(orders, amps[:-1]):
                out[f"ke_order_{ke_metrics.order_label(o)}_arcsec"] = rad_to_arcsec(a)
            out["ke_output_order_1_arcsec"] = rad_to_arcsec(amps[-1])
        elif group == "running_torque":
            (window,) = need("constant")
            out["running_torque_mNm"] = 1e3 * ke_metrics.window_mean(t, s["motor_torque_Nm"], window)
            out["running_speed_rpm"] = np.full(M, rad_per_s_to_rpm(bench.motion.max_speed))
        elif group == "running_torque_sweep":
            out.update(_sweep_metrics(t, s["motor_torque_Nm"], windows, data))
        elif group == "starting_torque":
            out["starting_torque_mNm"] = 1e3 * _starting_torque(model, bench.input_friction)
        elif group == "backdriving_torque":
            # the output torque that starts the unloaded input turning: N F_break / (1 − μ), the mesh
            # term μ|τ|/N of the input friction growing with the torque that backdrives it
            start = out.get("starting_torque_mNm", 1e3 * _starting_torque(model, bench.input_friction)) / 1e3
            out["backdriving_torque_Nm"] = abs(N) * start / (1.0 - bench.input_friction.load_coefficient)
        elif group == "efficiency":
            table = data.get("efficiency", {})
            speed = rpm_to_rad_per_s(float(table.get("speed_rpm", 2000.0)))
            out["efficiency_percent"] = 100.0 * efficiency(model, bench.input_friction, speed,
                                                           float(table.get("load", 1.0)),
                                                           float(table.get("revolutions", 4.0)))
            out["efficiency_speed_rpm"] = np.full(M, rad_per_s_to_rpm(speed))
        elif group in ("linearisation", "frequency_response"):
            _linear_metrics(model, scenario, bench, result, group, out)
        elif group == "tracking":
            ref = bench.motion.angle(t)[None, :] / N
            error = s["output_angle_rad"] - ref
            out["max_following_error_arcsec"] = rad_to_arcsec(np.max(np.abs(error), axis=1))
            out["final_error_arcsec"] = rad_to_arcsec(np.abs(error[:, -1]))
            out["max_wg_tracking_error_deg"] = np.rad2deg(np.max(np.abs(wg - bench.motion.angle(t)[None, :]), axis=1))
            out["peak_motor_torque_Nm"] = np.max(np.abs(s["motor_torque_Nm"]), axis=1)
        elif group == "settling":
            (window,) = need("dwell")
            band = arcsec_to_rad(float(analysis.get("settle_band_arcsec", 1.0)))
            ref = bench.motion.angle(t)[None, :] / N
            settle, residual = ke_metrics.settling(t, s["output_angle_rad"] - ref, window, band)
            out["settling_time_s"] = settle
            out["dwell_error_p2p_arcsec"] = rad_to_arcsec(residual)
        elif group == "load_step":
            before, after = need("before_step", "after_step")
            band = arcsec_to_rad(float(analysis.get("settle_band_arcsec", 1.0)))
            ref = bench.motion.angle(t)[None, :] / N
            err = s["output_angle_rad"] - ref
            step = ke_metrics.load_step(t, err, before, after, band)
            out["load_step_deflection_arcsec"] = rad_to_arcsec(step["deflection"])
            out["load_step_peak_arcsec"] = rad_to_arcsec(step["peak"])
            out["load_step_settling_time_s"] = step["settling_time"]
            out["load_step_twist_arcsec"] = rad_to_arcsec(
                ke_metrics.window_mean(t, s["twist_rad"], (after[1] - 0.1 * (after[1] - after[0]), after[1]))
                - ke_metrics.window_mean(t, s["twist_rad"], before))
        elif group == "oscillation":
            (window,) = need("oscillation")
            ref = bench.motion.angle(t) / N
            gain, phase, p2p = ke_metrics.oscillation(t, ref, s["output_angle_rad"], window,
                                                      float(data["input"].get("frequency_Hz", 1.0)))
            out["oscillation_gain"] = gain
            out["oscillation_phase_deg"] = np.rad2deg(phase)
            out["oscillation_deviation_p2p_arcsec"] = rad_to_arcsec(p2p)
    return out


def _starting_torque(model: HarmonicDrive, friction) -> np.ndarray:
    """Starting torque [N·m] per sample, shape (M,).

    The torque ramp is sized by the breakaway level, so a batch of friction laws (a study
    of ``input_friction.*``) breaks away one law at a time; one law serves a whole batch.
    """
    if friction.batch_size == 1:
        return starting_torque(model, friction)
    return np.concatenate([starting_torque(sample_model(model, m), friction.sample(m))
                           for m in range(friction.batch_size)])


def _linear_metrics(model, scenario, bench, result, group, out):
    lin = scenario.data.get("linearise", {})
    M = result.batch
    load_fraction = float(lin.get("load", bench.load.operating_point or 0.0))
    keys = ["natural_frequency_1_Hz", "damping_ratio_1", "tangent_stiffness_Nm_per_rad"]
    if bench.mode != "prescribed":  # motor loop and drive: two modes
        keys += ["natural_frequency_2_Hz", "damping_ratio_2"]
    if group == "frequency_response":
        keys += ["bode_magnitude_error_pct", "bode_phase_error_deg", "bode_compared_up_to_Hz"]
    values = {k: np.full(M, np.nan) for k in keys}
    for m in range(M):
        single = sample_model(model, m)
        x_op = None
        if group == "frequency_response":
            window = bench.motion.windows.get("sweep")
            if window is None:
                raise InputError(f"{scenario.source}: frequency_response needs load.profile = \"sweep\"")
            k0 = int(np.searchsorted(result.t, window[0]))
            x_op = np.array([result.states[nm][m, k0] for nm in result.states])
            load_fraction = float(bench.load.operating_point or 0.0)
        sys = linear_model(single, bench, load_fraction, x_op=x_op)
        summary = linear_summary(sys)
        if len(summary["natural_frequencies_Hz"]):
            values["natural_frequency_1_Hz"][m] = summary["natural_frequencies_Hz"][0]
            values["damping_ratio_1"][m] = summary["damping_ratios"][0]
        if "natural_frequency_2_Hz" in values and len(summary["natural_frequencies_Hz"]) > 1:
            values["natural_frequency_2_Hz"][m] = summary["natural_frequencies_Hz"][1]
            values["damping_ratio_2"][m] = summary["damping_ratios"][1]
        values["tangent_stiffness_Nm_per_rad"][m] = (summary["tangent_stiffness"] if bench.mode == "prescribed"
                                                     else drive_tangent_stiffness(single, bench, load_fraction))
        if group == "frequency_response":
            f, _, _, err = frequency_response_check(
                result.t, result.signals["load_torque_Nm"][m], result.signals["output_angle_rad"][m], sys,
                window, float(lin.get("compare_below", 0.8)), lin.get("f_min_Hz", 1.5 * bench.load.sweep_start))
            if f.size:
                values["bode_magnitude_error_pct"][m] = 100.0 * np.max(err["magnitude"])
                values["bode_phase_error_deg"][m] = np.rad2deg(np.max(err["phase"]))
                values["bode_compared_up_to_Hz"][m] = f[-1]
    out.update(values)


def frequency_response_check(t, load_torque, output_angle, sys, window, band_fraction=0.8, f_min=None):
    """Simulated sine-sweep response of one sample against the linear model.

    H is the ratio of the Fourier transforms of the output angle and load torque
    deviations over ``window`` (starting at rest at the operating point, ending after
    the response has decayed), compared on the bins where the sweep has energy, up to
    ``band_fraction`` of the first natural frequency.

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Uniform sample times [s].
    load_torque, output_angle : numpy.ndarray, shape (nt,)
        Load torque [N·m] and output angle [rad] of one sample.
    sys : control.StateSpace
        The linear model (`hdsim.simulation.linearize.linear_model`).
    window : tuple
        (start, end) [s] of the sweep record.
    band_fraction : float
        Compare up to this fraction of the first natural frequency.
    f_min : float, optional
        Compare from this frequency [Hz] up.

    Returns
    -------
    tuple
        ``(f [Hz], H_sim, H_lin, errors)``; ``errors`` holds ``magnitude`` (relative),
        ``phase`` [rad] and ``complex`` (relative) per bin, and ``f1_Hz``.
    """
    import control  # on first use: it imports matplotlib.pyplot (see hdsim.simulation.linearize)

    wn, _ = natural_frequencies(sys)
    f1 = wn[0] / TWO_PI if len(wn) else np.inf
    f, H = ke_metrics.sweep_frequency_response(t, load_torque, output_angle, window)
    U = ke_metrics.sweep_input_spectrum(t, load_torque, window)
    strong = np.abs(U) > 0.2 * np.max(np.abs(U))
    keep = strong & (f <= band_fraction * f1) & (f > 0) & (f >= (f_min or 0.0))
    fk = f[keep]
    H_lin = np.asarray(control.frequency_response(sys[0, 0], TWO_PI * fk).complex).reshape(-1)
    H_sim = H[keep]
    mag_err = np.abs(np.abs(H_sim) / np.abs(H_lin) - 1.0)
    phase_err = np.abs(np.angle(H_sim / H_lin))
    return fk, H_sim, H_lin, {"magnitude": mag_err, "phase": phase_err, "f1_Hz": f1,
                              "complex": np.abs(H_sim / H_lin - 1.0)}


def _sweep_metrics(t, motor_torque, windows, data) -> dict:
    """Running torque per speed of a sweep: the mean motor torque over whole WG turns of each cruise.

    ``running_torque_{rpm}rpm_mNm`` is the mean of the forward and reverse magnitudes;
    ``running_torque_forward_Nm`` / ``_reverse_Nm`` the mean magnitude over every cruise of
    one direction, as a running-torque fit reports them.
    """
    speeds = [float(v) for v in data["input"]["speeds_rpm"]]
    out, by_direction = {}, {"forward": [], "reverse": []}
    for i, rpm in enumerate(speeds):
        levels = []
        for name in ("forward", "reverse"):
            level = np.abs(ke_metrics.window_mean(t, motor_torque, windows[f"sweep_{i}_{name}"]))
            levels.append(level)
            by_direction[name].append(level)
        out[f"running_torque_{abs(rpm):g}rpm_mNm"] = 1e3 * 0.5 * (levels[0] + levels[1])
    out["running_torque_forward_Nm"] = np.mean(by_direction["forward"], axis=0)
    out["running_torque_reverse_Nm"] = np.mean(by_direction["reverse"], axis=0)
    return out
