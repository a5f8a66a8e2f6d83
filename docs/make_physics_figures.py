"""Regenerate the figures of docs/physics.md into docs/figures/ and print its numbers.

    python docs/make_physics_figures.py             # figures + tables (about 15 s)
    python docs/make_physics_figures.py --solvers   # also the solver comparison (about 1 min)

Every number quoted on the physics page that does not come from ``hdsim demo --json``
or ``hdsim simulate ... --json`` is printed by this script.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hdsim.model.catalog import load_unit  # noqa: E402
from hdsim.model.datasheet import catalog_entry, unit_names  # noqa: E402
from hdsim.model.drive import compliance_chain, radial_support  # noqa: E402
from hdsim.physics import backlash as bl  # noqa: E402
from hdsim.physics import compliance as cc  # noqa: E402
from hdsim.physics import stiffness as st  # noqa: E402
from hdsim.scenarios.run import run_scenario  # noqa: E402
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario  # noqa: E402
from hdsim.simulation.solver import SolverOptions  # noqa: E402
from hdsim.units import rad_to_arcmin  # noqa: E402

FIGURES = Path(__file__).resolve().parent / "figures"
CHAIN = ("diaphragm", "end_radius", "cylinder", "lead_radius", "undercut", "rim", "mesh_zone")
LABELS = {"diaphragm": "diaphragm", "end_radius": "end radius $R_k$", "cylinder": "cylinder $h_c$",
          "lead_radius": "lead radius $R_v$", "undercut": "undercut $h_p$", "rim": "rim $h_{pz}$",
          "mesh_zone": "mesh zone (calibrated)"}
COLOURS = dict(zip(CHAIN, ("C0", "C1", "C2", "C3", "C4", "C5", "0.55")))


def _save(fig, name):
    FIGURES.mkdir(exist_ok=True)
    fig.savefig(FIGURES / name, dpi=110)
    plt.close(fig)
    print(f"wrote docs/figures/{name}")


def scenario(name):
    return load_scenario(builtin_scenario_path(name))


# ----------------------------------------------------------------------------- tables
def chain_tables():
    print("\n== compliance chain at the nominal geometry (calibrated, kappa applied)")
    print(f"{'unit':<11} {'kappa':>6} {'e2':>6} {'e3':>6} | " + " ".join(f"{c[:9]:>9}" for c in CHAIN))
    rows = {}
    for name in unit_names():
        m = load_unit(name)
        chain = {k: float(v) for k, v in m.compliance().as_dict().items()}
        total = sum(chain.values())
        cal = m.provenance["calibration"]
        raw = compliance_chain(m.geometry, m.wave_generator, 1.0)
        rows[name] = dict(chain=chain, total=total, cal=cal, raw_total=float(raw.total),
                          raw_mesh=float(raw.mesh_zone), structure=float(raw.structure),
                          K1=catalog_entry(name)["K1"])
        print(f"{name:<11} {cal['kappa_mesh']:6.3f} {cal['e2']:6.3f} {cal['e3']:6.3f} | "
              + " ".join(f"{100 * chain[c] / total:8.1f}%" for c in CHAIN))
    print("\n== stiffness of parts of the chain against the catalog K1 [N·m/rad]")
    print(f"{'unit':<11} {'tube':>9} {'tube/K1':>8} {'shell':>9} {'shell/K1':>8} {'raw chain':>9} "
          f"{'raw/K1':>7} {'K1':>8}")
    for name, r in rows.items():
        tube = 1.0 / r["chain"]["cylinder"]
        shell = 1.0 / r["structure"]
        raw = 1.0 / r["raw_total"]
        print(f"{name:<11} {tube:9.3g} {tube / r['K1']:8.2f} {shell:9.3g} {shell / r['K1']:8.2f} "
              f"{raw:9.3g} {raw / r['K1']:7.2f} {r['K1']:8.3g}")
    m = load_unit()
    g, wg = m.geometry, m.wave_generator
    support = radial_support(g, wg)
    k_r = float(support.total)
    print(f"\n== radial support of {m.name}: arc {support.zone_arc * 1e3:.2f} mm, ball pitch "
          f"{support.ball_pitch * 1e3:.2f} mm, k_rim {support.rim:.3g}, k_cup {support.cup:.3g}, "
          f"k_bearing {support.bearing:.3g}, k_r {k_r:.3g} N/m, C_mesh(kappa=1) "
          f"{cc.mesh_zone(k_r, g.pitch_radius, g.pressure_angle):.4g} rad/(N·m)")
    print("ball pitch [mm]: " + ", ".join(
        f"{n} {radial_support(load_unit(n).geometry, load_unit(n).wave_generator).ball_pitch * 1e3:.2f}"
        for n in unit_names()))
    print("\n== closed-form checks")
    print(f"thin tube R=20 mm, t=0.4 mm, L=30 mm, G=76.9 GPa: K = {1 / cc.thin_tube(0.03, 0.02, 0.4e-3, 76.9e9):.4g}"
          " N·m/rad (reference §4: about 5.2e4)")
    print(f"fillet with R_k -> 0 vs tube of length pi R_k/2: "
          f"{cc.toroidal_fillet(1e-6, 0.03, 1e-3, 80e9) / cc.thin_tube(np.pi / 2 * 1e-6, 0.03, 1e-3, 80e9):.6f}")
    print(f"transition with equal walls vs tube: "
          f"{cc.wall_transition(2e-3, 0.03, 1e-3, 1e-3, 80e9) / cc.thin_tube(2e-3, 0.0305, 1e-3, 80e9):.6f}")
    print("pitch radii [mm]: " + ", ".join(
        f"{n} {load_unit(n).geometry.pitch_radius * 1e3:.2f}" for n in unit_names()))
    return rows


# ----------------------------------------------------------------------------- figures
def figure_section():
    """Half-section of the nominal CSG-25-100 cup and the wall thickness along its meridian."""
    m = load_unit()
    g = m.geometry
    chain = {k: float(v) for k, v in m.compliance().as_dict().items()}
    total = sum(chain.values())
    mm = 1e3
    Ri, Rc, Rk, Rv = g.R_i * mm, g.R_c * mm, g.R_k * mm, g.R_v * mm
    hc, hpz, hp, td = g.h_c * mm, g.h_pz * mm, g.h_p * mm, g.t_d * mm
    wu, b, L, rhub = g.undercut_width * mm, g.face_width * mm, g.cup_length * mm, g.r_hub * mm
    Lcyl = float(g.cylinder_length) * mm
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.4), layout="constrained",
                                 gridspec_kw={"width_ratios": [1.0, 1.25]})
    # (a) half section: mid-surface to scale, wall thickness exaggerated X times
    X = 4.0
    z = Rk
    zz = np.linspace(0, 1, 30)
    ax.fill_between([z, z + Lcyl], Ri, Ri + X * hc, color=COLOURS["cylinder"], lw=0,
                    label=f"cylinder, L = {Lcyl:.1f} mm")
    z += Lcyl
    tt = hc + (hpz - hc) * (1 - np.cos(0.5 * np.pi * zz))
    ax.fill_between(z + Rv * zz, Ri, Ri + X * tt, color=COLOURS["lead_radius"], lw=0,
                    label=f"lead radius R_v = {Rv:.2f} mm")
    z += Rv
    ax.fill_between([z, z + wu], Ri, Ri + X * (hpz - hp), color=COLOURS["undercut"], lw=0,
                    label=f"undercut, h_pz - h_p = {hpz - hp:.2f} mm")
    z += wu
    ax.fill_between([z, z + b], Ri, Ri + X * hpz, color=COLOURS["rim"], lw=0,
                    label=f"toothed rim, h_pz = {hpz:.2f} mm")
    ax.fill_between([z, z + b], Ri + X * hpz, Ri + X * (hpz + 2 * g.module * mm), color="0.8", lw=0,
                    hatch="////", edgecolor="0.6", label="teeth (schematic)")
    ax.fill_between([-0.5 * X * td, 0.5 * X * td], rhub, Rc - Rk, color=COLOURS["diaphragm"], lw=0,
                    label=f"diaphragm, t_d = {td:.2f} mm")
    ax.fill_between([-0.5 * X * td - 3, -0.5 * X * td], 0, rhub, color="0.35", lw=0, label="hub (rigid)")
    beta = np.linspace(0, 0.5 * np.pi, 40)
    tf = 0.5 * (td + hc) * X
    zm, rm = Rk * (1 - np.cos(beta)), Rc - Rk + Rk * np.sin(beta)
    nz, nr = -np.cos(beta), np.sin(beta)
    ax.fill(np.r_[zm + 0.5 * tf * nz, (zm - 0.5 * tf * nz)[::-1]],
            np.r_[rm + 0.5 * tf * nr, (rm - 0.5 * tf * nr)[::-1]], color=COLOURS["end_radius"], lw=0,
            label=f"end radius R_k = {Rk:.2f} mm")
    ax.axhline(0, color="k", lw=0.8, ls="-.")
    ax.set_xlim(-0.5 * X * td - 3, L + 1)
    ax.set_ylim(0, g.pitch_radius * mm + 12)
    ax.set_xlabel("axial position z [mm] (diaphragm mid-plane at 0)")
    ax.set_ylabel("radius r [mm]")
    ax.set_title(f"(a) {m.name} nominal cup, half section (walls x{X:g})")
    ax.legend(loc="lower right", fontsize="x-small", ncol=2)
    # (b) the chain as bars of compliance share
    names = list(CHAIN)
    shares = [100 * chain[n] / total for n in names]
    bars = bx.barh([LABELS[n] for n in names], shares, color=[COLOURS[n] for n in names])
    for bar, n, s in zip(bars, names, shares):
        bx.text(bar.get_width() + 0.8, bar.get_y() + bar.get_height() / 2,
                f"{s:.1f} %  (K = {1 / chain[n]:.3g} N·m/rad)", va="center", fontsize="small")
    bx.invert_yaxis()
    bx.set_xlim(0, 118)
    bx.set_xlabel("share of the low-torque compliance 1/K1 [%]")
    bx.set_title(f"(b) series chain, total K = {1 / total:.4g} N·m/rad")
    _save(fig, "physics_flexspline_chain.png")


def figure_calibration(rows):
    names = list(rows)
    x = np.arange(len(names))
    fig, ax = plt.subplots(figsize=(7.5, 4.2), layout="constrained")
    series = [("cylinder tube alone", [1 / r["chain"]["cylinder"] for r in rows.values()], "C2"),
              ("all shell terms (no mesh zone)", [1 / r["structure"] for r in rows.values()], "C0"),
              ("closed-form chain, kappa = 1", [1 / r["raw_total"] for r in rows.values()], "C3"),
              ("catalog K1", [r["K1"] for r in rows.values()], "k")]
    width = 0.2
    for i, (label, values, colour) in enumerate(series):
        ax.bar(x + (i - 1.5) * width, values, width, label=label, color=colour)
    ax.set_yscale("log")
    ax.set_xticks(x, names)
    ax.set_ylabel("torsional stiffness [N·m/rad]")
    ax.set_title("Closed forms against the catalog: why the mesh zone is calibrated")
    ax.legend(fontsize="small")
    ax.grid(axis="y", which="both", alpha=0.3)
    _save(fig, "physics_calibration.png")


def figure_hardening():
    m = load_unit()
    cat = catalog_entry(m.name)
    c_s, c_m = m.split()
    K = m.hardening.stiffnesses(c_s, c_m)
    T1, T2 = cat["T1"], cat["T2"]
    w = m.hardening.knee_rounding * T1 / K[0]
    phi = np.linspace(0, st.three_segment_twist(cat["rated_torque"], T1, T2, *K), 600)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
    ax.plot(rad_to_arcmin(phi), st.three_segment_torque(phi, T1, T2, *K), "k--", lw=1, label="three-segment law")
    ax.plot(rad_to_arcmin(phi), st.smooth_three_segment_torque(phi, T1, T2, *K, w), "C0",
            label="smooth form used by the solver")
    for T in (T1, T2):
        ax.axhline(T, color="0.7", lw=0.6)
    ax.set_xlabel("twist [arcmin]")
    ax.set_ylabel("torque [N·m]")
    ax.set_title(f"{m.name}: T1 = {T1:g}, T2 = {T2:g} N·m")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    zoom = np.linspace(0.6, 1.4, 400) * T1 / K[0]
    bx.plot(rad_to_arcmin(zoom), st.three_segment_tangent(zoom, T1, T2, *K), "k--", lw=1, label="sharp knee")
    bx.plot(rad_to_arcmin(zoom), st.smooth_three_segment_tangent(zoom, T1, T2, *K, w), "C0",
            label=f"rounded over {rad_to_arcmin(w):.3f} arcmin")
    bx.set_xlabel("twist [arcmin]")
    bx.set_ylabel("tangent stiffness [N·m/rad]")
    bx.set_title("tangent stiffness around the first knee")
    bx.legend(fontsize="small")
    bx.grid(alpha=0.3)
    _save(fig, "physics_hardening.png")


def figure_backlash():
    gap = 1.0
    half = 0.5 * gap
    d = np.linspace(-1.5, 1.5, 601)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
    ax.plot(d, bl.dead_zone(d, half), "k--", lw=1, label="dead zone, seed paper eq. (2)")
    ax.plot(d, bl.smooth_dead_zone(d, half, 0.2 * gap), "C0", label="smooth form (rounding 0.2 b)")
    ax.plot(d, bl.smooth_contact(d, half, 0.2 * gap), "C1", lw=1, label="contact factor")
    ax.set_xlabel(r"twist across the gap $\delta / b$ [-]")
    ax.set_ylabel(r"engaged twist $/ b$ [-], contact factor [-]")
    ax.set_title("dead zone of total width b")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    tau_c = 1.0
    tau_d = np.linspace(-3, 3, 601)
    bx.plot(tau_d, bl.elasto_backlash_torque(tau_c, tau_d), "k--", lw=1, label="ElastoBacklash (Modelica)")
    bx.plot(tau_d, bl.smooth_elasto_backlash_torque(tau_c, tau_d), "C0", label="smooth form used")
    bx.plot(tau_d, tau_c + tau_d, "0.6", lw=0.8, label=r"plain $\tau_c + \tau_d$")
    bx.set_xlabel(r"damping torque $\tau_d / \tau_c$ [-]")
    bx.set_ylabel(r"contact torque $\tau / \tau_c$ [-]")
    bx.set_title(r"contact torque at spring torque $\tau_c > 0$")
    bx.set_ylim(-1.5, 3.5)
    bx.legend(fontsize="small")
    bx.grid(alpha=0.3)
    _save(fig, "physics_backlash.png")


def lost_motion_variants():
    base = load_unit()
    variants = [("elastic only (friction, backlash off)", base.without("friction", "backlash")),
                ("+ backlash", base.without("friction")),
                ("+ micro-slip", base.without("backlash")),
                ("default: backlash + micro-slip", base)]
    lm = scenario("lost_motion")
    runs = [(label, run_scenario(model, lm)) for label, model in variants]
    print("\n== ±4 % T_N lost motion, CSG-25-100 [arcmin]")
    for label, run in runs:
        print(f"  {label:<40} {run.metric('lost_motion_arcmin'):.4f}")
    return runs


def figure_lost_motion(runs):
    fig, ax = plt.subplots(figsize=(7, 4.4), layout="constrained")
    for (label, run), colour in zip(runs, ("0.5", "C1", "C2", "C0")):
        n = run.scenario.samples_per_segment
        sl = slice(3 * n, 5 * n + 1)  # the last cycle: -A -> +A -> -A
        torque = run.result.signal("torque_Nm")[sl]
        twist = rad_to_arcmin(run.result.signal("twist_rad"))[sl]
        ax.plot(twist, torque, color=colour, lw=1.3,
                label=f"{label}: {run.metric('lost_motion_arcmin'):.4f} arcmin")
    ax.set_xlabel("twist [arcmin]")
    ax.set_ylabel("output torque [N·m]")
    ax.set_title("CSG-25-100, ±4 % T_N (last cycle), lost motion = full span")
    ax.legend(fontsize="small", loc="upper left")
    ax.grid(alpha=0.3)
    _save(fig, "physics_lost_motion.png")


def figure_stiffness():
    m = load_unit()
    run = run_scenario(m, scenario("stiffness"))
    n = run.scenario.samples_per_segment
    T = run.result.signal("torque_Nm")
    phi = run.result.signal("twist_rad")
    slip = run.result.signal("friction.slip")
    cat = catalog_entry(m.name)
    K = [run.metric(k) for k in ("K1_Nm_per_rad", "K2_Nm_per_rad", "K3_Nm_per_rad")]
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.4), layout="constrained")
    ax.plot(rad_to_arcmin(phi), T, "C0", lw=1.2, label="simulated loop 0 → +T_N → −T_N → 0")
    down = slice(n, 2 * n + 1)
    keep = -T[down] >= 0.5 * cat["T1"]
    ax.plot(rad_to_arcmin(phi[down][keep]), T[down][keep], "C3", lw=2.5, alpha=0.6,
            label="samples used for the K fit")
    grid = np.linspace(0, cat["rated_torque"], 200)
    ax.plot(-rad_to_arcmin(st.three_segment_twist(grid, cat["T1"], cat["T2"], *K)), -grid, "k--", lw=1,
            label="fitted three-segment law (no offset)")
    ax.set_xlabel("twist [arcmin]")
    ax.set_ylabel("output torque [N·m]")
    ax.set_title(f"{m.name}: hysteresis loss {run.metric('hysteresis_loss_arcmin'):.3f} arcmin")
    ax.legend(fontsize="small", loc="upper left")
    ax.grid(alpha=0.3)
    lm = run_scenario(m, scenario("lost_motion"))
    bx.plot(T, rad_to_arcmin(slip), "C0", label="±T_N stiffness test")
    bx.plot(lm.result.signal("torque_Nm"), rad_to_arcmin(lm.result.signal("friction.slip")), "C2", lw=2,
            label="±4 % T_N lost-motion test")
    s_max = rad_to_arcmin(m.friction.slip_max)
    for s in (-s_max, s_max):
        bx.axhline(s, color="0.6", lw=0.8, ls="--")
    bx.axvline(m.friction.slip_torque, color="C1", lw=0.8, ls=":")
    bx.axvline(-m.friction.slip_torque, color="C1", lw=0.8, ls=":", label=f"± slip torque F = {m.friction.slip_torque / m.drive.rated_torque:.2f} T_N")
    bx.set_xlabel("output torque [N·m]")
    bx.set_ylabel("micro-slip s [arcmin]")
    bx.set_title("dahl_slip state: stops at ±s_max")
    bx.legend(fontsize="small", loc="upper left")
    bx.grid(alpha=0.3)
    _save(fig, "physics_stiffness_loop.png")


# ----------------------------------------------------------------------------- solvers
def solver_table():
    print("\n== solvers on CSG-25-100 (solve_ivp nfev, wall time)")
    base = load_unit()
    rng = np.random.default_rng(0)
    p = base.params()
    designs = ("h_pz", "h_c", "R_v", "R_k", "h_p")

    def batch(M):
        return base.with_updates({f"flexspline.{k}": p[f"flexspline.{k}"] * rng.uniform(0.9, 1.1, M)
                                  for k in designs})

    cases = [("lost_motion", base, None, None), ("stiffness", base, None, None),
             ("lost_motion", batch(64), None, None), ("stiffness", batch(64), None, None),
             ("lost_motion", batch(512), 1, dict(rtol=1e-5, atol_scale=1e-5))]
    for name, model, samples, opts in cases:
        for method in ("Radau", "BDF", "LSODA"):
            if model.batch_size == 512 and method == "BDF":
                continue
            options = SolverOptions(method=method, **(opts or {}))
            t0 = time.perf_counter()
            run = run_scenario(model, scenario(name), options=options, samples_per_segment=samples)
            dt = time.perf_counter() - t0
            print(f"  {name:<12} M={model.batch_size:<4} {method:<6} nfev {run.result.solver['nfev']:>6} "
                  f"njev {run.result.solver['njev']:>5} {dt:6.2f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--solvers", action="store_true", help="also time Radau, BDF and LSODA")
    args = parser.parse_args()
    plt.rcParams.update({"figure.dpi": 110, "font.size": 9})
    rows = chain_tables()
    figure_section()
    figure_calibration(rows)
    figure_hardening()
    figure_backlash()
    figure_lost_motion(lost_motion_variants())
    figure_stiffness()
    if args.solvers:
        solver_table()


if __name__ == "__main__":
    main()
