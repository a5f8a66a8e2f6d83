"""Regenerate the figures of docs/tutorial-first-simulation.md into docs/figures/.

    python docs/make_first_simulation_figures.py        # about 10 s

The script uses only the public API shown in the tutorial (load_unit, with_updates,
load_scenario, run_scenario, plot_loop, plot_time, Run.save, read_run) and
prints the numbers the tutorial quotes.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from hdsim.model.catalog import load_unit  # noqa: E402
from hdsim.plotting.locked import plot_loop, plot_time  # noqa: E402
from hdsim.scenarios.run import read_run, run_scenario  # noqa: E402
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario  # noqa: E402
from hdsim.units import rad_to_arcmin  # noqa: E402

FIGURES = Path(__file__).resolve().parent / "figures"
WALLS_MM = (0.5, 0.635, 0.8)  # h_c values compared in the tutorial, nominal in the middle


def save(fig, name: str) -> None:
    FIGURES.mkdir(exist_ok=True)
    fig.savefig(FIGURES / name, dpi=110)
    plt.close(fig)
    print(f"wrote docs/figures/{name}")


def main() -> None:
    unit = load_unit("CSG-25-100")
    lost_motion = load_scenario(builtin_scenario_path("lost_motion"))
    stiffness = load_scenario(builtin_scenario_path("stiffness"))

    # 1. the two catalog tests on the default unit
    lm_run = run_scenario(unit, lost_motion)
    st_run = run_scenario(unit, stiffness)
    print(f"lost motion {lm_run.metric('lost_motion_arcmin'):.4f} arcmin, "
          f"K1 {st_run.metric('K1_Nm_per_rad'):.5g} N·m/rad")
    save(plot_loop(lm_run), "first_sim_lost_motion_loop.png")
    save(plot_loop(st_run), "first_sim_stiffness_loop.png")
    save(plot_time(lm_run), "first_sim_lost_motion_time.png")

    # 2. the cylinder wall thickness h_c: three models, one figure
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10.5, 4.2), layout="constrained")
    for h_c, colour in zip(WALLS_MM, ("C3", "C0", "C2")):
        model = unit.with_updates({"flexspline.h_c": h_c * 1e-3})
        run_st = run_scenario(model, stiffness)
        run_lm = run_scenario(model, lost_motion)
        K1 = run_st.metric("K1_Nm_per_rad")
        lm = run_lm.metric("lost_motion_arcmin")
        print(f"h_c = {h_c} mm: K1 {K1:.5g} N·m/rad, K3 {run_st.metric('K3_Nm_per_rad'):.5g}, "
              f"torsion at T_N {run_st.metric('torsion_at_rated_arcmin'):.4f} arcmin, "
              f"lost motion {lm:.4f} arcmin, base stiffness {float(model.base_stiffness):.5g}")
        label = f"h_c = {h_c} mm"
        ax.plot(rad_to_arcmin(run_st.result.signal("twist_rad")), run_st.result.signal("torque_Nm"),
                color=colour, lw=1.1, label=f"{label}: K1 = {K1:.4g} N·m/rad")
        bx.plot(rad_to_arcmin(run_lm.result.signal("twist_rad")), run_lm.result.signal("torque_Nm"),
                color=colour, lw=1.1, label=f"{label}: {lm:.3f} arcmin")
    ax.set(xlabel="twist [arcmin]", ylabel="output torque [N·m]", title="stiffness test, ±T_N")
    bx.set(xlabel="twist [arcmin]", ylabel="output torque [N·m]", title="lost-motion test, ±4 % T_N")
    for a in (ax, bx):
        a.grid(alpha=0.3)
        a.legend(fontsize="small", loc="upper left")
    save(fig, "first_sim_h_c.png")

    # 3. write the result to HDF5 and read it back
    with tempfile.TemporaryDirectory() as tmp:
        path = lm_run.save(Path(tmp) / "lost_motion.h5")
        stored = read_run(path)
    print("metrics from file:", {k: float(v[0]) for k, v in stored.metrics.items()})
    print("effects from file:", {k: e.id for k, e in stored.model.effects().items()})
    t = stored.result.t
    fig, ax = plt.subplots(figsize=(6.4, 3.6), layout="constrained")
    ax.plot(t, rad_to_arcmin(stored.result.signal("twist_rad")), label="twist (total)")
    ax.plot(t, rad_to_arcmin(stored.result.signal("friction.slip")), label="micro-slip state friction.slip")
    ax.set(xlabel="time [s]", ylabel="[arcmin]",
           title=f"read back from HDF5: {stored.scenario.name} on {stored.model.name}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    save(fig, "first_sim_readback.png")


if __name__ == "__main__":
    main()
