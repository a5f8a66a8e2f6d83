"""Regenerate the figures of docs/tutorial-kinematic-error.md into docs/figures/.

    python docs/make_ke_figures.py        # about 40 s on 2 cores

Uses the calls shown in the tutorial (load_unit, load_scenario, run_scenario, the
hdsim.simulation.driven and hdsim.scenarios.ke_metrics functions) and prints every number the tutorial quotes.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import control  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hdsim.scenarios import ke_metrics  # noqa: E402
from hdsim.model.catalog import load_unit  # noqa: E402
from hdsim.scenarios.driven import bench_from_scenario  # noqa: E402
from hdsim.simulation.linearize import linear_model, linear_summary  # noqa: E402
from hdsim.scenarios.run import run_scenario  # noqa: E402
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario  # noqa: E402
from hdsim.units import rad_to_arcsec  # noqa: E402

FIGURES = Path(__file__).resolve().parent / "figures"


def save(fig, name: str) -> None:
    FIGURES.mkdir(exist_ok=True)
    fig.savefig(FIGURES / name, dpi=110)
    plt.close(fig)
    print(f"wrote docs/figures/{name}")


def ke_figures(unit) -> None:
    run = run_scenario(unit, load_scenario(builtin_scenario_path("kinematic_error")))
    for name, value in run.metrics.items():
        print(f"kinematic_error: {name} = {float(value[0]):.4g}")
    s, t = run.result.signals, run.result.t
    windows = run.result.metadata["windows"]
    N = float(unit.drive.ratio)

    # 1. deviation against output angle, both passes, and the KE source
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(9.0, 6.4), layout="constrained")
    for label, colour in (("forward", "C0"), ("reverse", "C3")):
        a, b = windows[label]
        m = (t >= a) & (t <= b)
        out_deg = np.rad2deg(s["wg_angle_rad"][0, m] / N)
        ax.plot(out_deg, rad_to_arcsec(s["deviation_rad"][0, m]), colour, lw=0.6,
                label=f"{label} pass: $\\theta_{{out}} - \\theta_{{WG}}/N$")
        if label == "forward":
            ke = rad_to_arcsec(s["ke_source_rad"][0, m])
            bx.plot(out_deg, rad_to_arcsec(s["deviation_rad"][0, m]) - np.mean(rad_to_arcsec(
                s["deviation_rad"][0, m])), "C0", lw=0.6, label="forward pass, mean removed")
            bx.plot(out_deg, ke - np.mean(ke), "k", lw=0.4, alpha=0.6,
                    label="kinematic-error source e (lies under it: the load is constant)")
            dev = rad_to_arcsec(s["deviation_rad"][0, m]) - np.mean(rad_to_arcsec(s["deviation_rad"][0, m]))
            for level in (dev.max(), dev.min()):
                bx.axhline(level, color="C2", lw=0.8, ls="--")
    ax.annotate("", xy=(45, rad_to_arcsec(np.mean(s["deviation_rad"][0][(t >= windows["reverse"][0])
                                                                         & (t <= windows["reverse"][1])]))),
                xytext=(45, rad_to_arcsec(np.mean(s["deviation_rad"][0][(t >= windows["forward"][0])
                                                                        & (t <= windows["forward"][1])]))),
                arrowprops=dict(arrowstyle="<->", color="C2"))
    ax.text(50, 0, f"lost motion on reversal\n{run.metric('lost_motion_on_reversal_arcsec'):.0f} arcsec",
            color="C2", va="center")
    ax.set_ylabel("deviation [arcsec]")
    ax.set_title(f"{unit.name}: one output revolution each way at 500 rpm input, 1/4 $T_N$ opposing load")
    ax.legend(loc="upper right", fontsize=8)
    bx.set_xlabel("output angle [deg]")
    bx.set_ylabel("deviation − mean [arcsec]")
    bx.set_title(f"transmission accuracy (peak to peak over one revolution) = "
                 f"{run.metric('transmission_accuracy_arcsec'):.1f} arcsec; catalog class 60 arcsec")
    bx.legend(loc="upper right", fontsize=8)
    for axis in (ax, bx):
        axis.grid(alpha=0.3)
    save(fig, "ke_vs_output_angle.png")

    # 2. order spectrum of the forward pass
    orders, amps = ke_metrics.order_spectrum(t, s["wg_angle_rad"], s["deviation_rad"], windows["forward"], N,
                                             max_order=6.0)
    ke = unit.kinematic_error
    scale = 1.0 + ke.load_gain * 0.25
    fig, ax = plt.subplots(figsize=(9.0, 3.8), layout="constrained")
    ax.vlines(orders, 0, rad_to_arcsec(amps), color="C0", lw=1.0, label="simulated, forward pass")
    configured = {1.0 / N: ke.a_out, 1.0: ke.a1, 2.0: ke.a2, 4.0: ke.a4}
    ax.plot(list(configured), [rad_to_arcsec(a * scale) for a in configured.values()], "o", mfc="none",
            color="C3", ms=9, label="configured × (1 + g·0.25)")
    for order, a in configured.items():
        label = "1/N (output)" if order < 1 else f"{order:g}×"
        ax.annotate(label, (order, rad_to_arcsec(a * scale)), textcoords="offset points", xytext=(6, 4),
                    fontsize=8)
    ax.set_xlabel("order of wave-generator rotation")
    ax.set_ylabel("amplitude [arcsec]")
    ax.set_xlim(-0.1, 6)
    ax.set_title("order spectrum of $\\theta_{out} - \\theta_{WG}/N$ (one output revolution, 100 WG turns)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    save(fig, "ke_order_spectrum.png")


def bode_figure(unit) -> None:
    scenario = load_scenario(builtin_scenario_path("frequency_sweep"))
    run = run_scenario(unit, scenario)
    for name, value in run.metrics.items():
        print(f"frequency_sweep: {name} = {float(value[0]):.4g}")
    bench = bench_from_scenario(unit, scenario)
    t, s = run.result.t, run.result.signals
    window = run.result.metadata["windows"]["sweep"]
    k0 = int(np.searchsorted(t, window[0]))
    x_op = np.array([run.result.states[n][0, k0] for n in run.result.states])
    sys = linear_model(unit, bench, bench.load.operating_point, x_op=x_op)
    summary = linear_summary(sys)
    f1 = summary["natural_frequencies_Hz"][0]
    f, H = ke_metrics.sweep_frequency_response(t, s["load_torque_Nm"][0], s["output_angle_rad"][0], window)
    U = ke_metrics.sweep_input_spectrum(t, s["load_torque_Nm"][0], window)
    keep = (np.abs(U) > 0.2 * np.max(np.abs(U))) & (f > 0)
    f_sim, H_sim = f[keep][::6], H[keep][::6]
    f_lin = np.logspace(np.log10(10.0), np.log10(2000.0), 600)
    H_lin = np.asarray(control.frequency_response(sys[0, 0], 2 * np.pi * f_lin).complex).reshape(-1)
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(8.0, 6.4), sharex=True, layout="constrained")
    ax.loglog(f_lin, rad_to_arcsec(np.abs(H_lin)), "k", lw=1.2, label="linearisation (python-control)")
    ax.loglog(f_sim, rad_to_arcsec(np.abs(H_sim)), ".", color="C3", ms=3, label="simulated sine sweep")
    bx.semilogx(f_lin, np.rad2deg(np.unwrap(np.angle(H_lin))), "k", lw=1.2)
    bx.semilogx(f_sim, np.rad2deg(np.angle(H_sim)), ".", color="C3", ms=3)
    for axis in (ax, bx):
        axis.axvline(f1, color="C0", lw=0.8, ls=":")
        axis.axvspan(1.5 * bench.load.sweep_start, 0.8 * f1, color="C2", alpha=0.08)
        axis.grid(alpha=0.3, which="both")
    ax.set_ylabel("output angle / load torque\n[arcsec/(N·m)]")
    ax.set_title(f"{unit.name}, 0.35 $T_N$ preload, WG held: resonance {f1:.0f} Hz, "
                 f"tangent stiffness {summary['tangent_stiffness']:.3g} N·m/rad", fontsize=10)
    ax.legend(fontsize=8)
    bx.set_ylabel("phase [deg]")
    bx.set_xlabel("frequency [Hz]  (shaded: compared band, 1.5 × sweep start to 0.8 × resonance)")
    save(fig, "ke_bode_sweep.png")


def cycle_figure(unit) -> None:
    run = run_scenario(unit, load_scenario(builtin_scenario_path("point_to_point")))
    for name, value in run.metrics.items():
        print(f"point_to_point: {name} = {float(value[0]):.4g}")
    t, s = run.result.t, run.result.signals
    N = float(unit.drive.ratio)
    fig, axes = plt.subplots(3, 1, figsize=(9.0, 7.0), sharex=True, layout="constrained")
    axes[0].plot(t, np.rad2deg(s["output_angle_rad"][0]), "C0", label="output")
    axes[0].plot(t, np.rad2deg(s["reference_angle_rad"][0] / N), "k--", lw=0.8, label="command / N")
    axes[0].set_ylabel("angle [deg]")
    axes[0].legend(fontsize=8)
    axes[1].plot(t, rad_to_arcsec(s["output_angle_rad"][0] - s["reference_angle_rad"][0] / N), "C3", lw=0.7,
                 label="output − command/N (following error)")
    axes[1].plot(t, rad_to_arcsec(s["deviation_rad"][0]), "C0", lw=0.7, label="output − WG/N (deviation)")
    axes[1].set_ylabel("[arcsec]")
    axes[1].legend(fontsize=8)
    axes[2].plot(t, s["drive_torque_Nm"][0], "C0", lw=0.7, label="drive torque (output side)")
    axes[2].plot(t, 100 * s["motor_torque_Nm"][0], "C1", lw=0.8, label="motor torque × N")
    axes[2].set_ylabel("[N·m]")
    axes[2].set_xlabel("time [s]")
    axes[2].legend(fontsize=8)
    for axis in axes:
        axis.grid(alpha=0.3)
    axes[0].set_title(f"{unit.name}: 90° and back, PI speed loop + position loop, 0.05 kg·m² link")
    save(fig, "ke_point_to_point.png")


def main() -> None:
    unit = load_unit("CSG-25-100")
    ke_figures(unit)
    bode_figure(unit)
    cycle_figure(unit)


if __name__ == "__main__":
    main()
