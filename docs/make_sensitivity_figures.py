"""Regenerate the figures of docs/sensitivity.md into docs/figures/.

    python docs/make_sensitivity_figures.py            # closed forms (about 10 s)
    python docs/make_sensitivity_figures.py --unit     # plus the flexspline study
    python docs/make_sensitivity_figures.py --evaluators   # quasi-static against solve_ivp (~1 min)
    python docs/make_sensitivity_figures.py --driven       # the same on the driven contract run (~15 s)

The flexspline figure needs the simulator's batch interface (``hdsim.sensitivity.scenario_outputs``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from hdsim.plotting import save_figure
from hdsim.plotting.sensitivity import plot_convergence, plot_indices
from hdsim.sensitivity import Ishigami, Linear, run_study
from hdsim.sensitivity.analysis import analyse
from hdsim.sensitivity.design import replicate_seed, sample_replicate
from hdsim.sensitivity.evaluate import evaluate

FIGURES = Path(__file__).resolve().parent / "figures"


def closed_forms() -> None:
    f = Ishigami()
    res = run_study(f, f.problem(), 8192, workers=1, progress=False)
    names = list(f.problem().names)
    plot_indices(FIGURES / "sobol_ishigami_indices.png", names, res.analysis, f.analytic(),
                 title="Ishigami, N = 8192 (black ticks: analytic)")
    plot_convergence(FIGURES / "sobol_ishigami_convergence.png", names, res.convergence,
                     analytic=f.analytic())


def pairing() -> None:
    """Same linear model, outputs filed by row index vs in completion order."""
    f, R, n = Linear(), 4, 1024
    p = f.problem()
    X = np.concatenate([sample_replicate(p, n // R, replicate_seed(0, r), False)
                        for r in range(R)])
    ev = evaluate(f, X, workers=1, chunksize=100, progress=False)
    right = analyse(p, X, ev.y, second_order=False, replicates=R, key=ev.key)
    order = np.random.default_rng(0).permutation(int(np.ceil(len(X) / 100)))
    perm = np.concatenate([np.arange(c * 100, min(c * 100 + 100, len(X))) for c in order])
    wrong = analyse(p, X, ev.y[perm], second_order=False, replicates=R)  # keys withheld
    fig = Figure(figsize=(8.5, 3.2))
    axes = fig.subplots(1, 2, sharey=True)
    x = np.arange(p.num_vars)
    for ax, res, title in ((axes[0], right, "rows matched by index"),
                           (axes[1], wrong, "chunks in completion order")):
        ax.bar(x - 0.2, res["S1"], 0.4, label="S1")
        ax.bar(x + 0.2, res["ST"], 0.4, label="ST")
        ax.scatter(x, f.analytic()["S1"], marker="_", s=400, color="k", label="analytic")
        ax.set_xticks(x, p.names)
        ax.set_title(f"{title}\nΣS1 = {res['S1'].sum():.2f}, ΣST = {res['ST'].sum():.2f}",
                     fontsize=9)
    axes[0].set_ylabel("index [-]")
    axes[0].legend(fontsize=8, frameon=False)
    fig.tight_layout()
    save_figure(fig, FIGURES / "sobol_pairing.png")


def flexspline() -> None:
    from hdsim.sensitivity.models import from_unit

    names = ["h_pz", "h_c", "R_v", "R_k", "h_p"]
    func, problem, output, model, _ = from_unit("CSG-25-100", names, "lost_motion_arcmin",
                                                range_frac=0.10)
    res = run_study(func, problem, 1024, second_order=True, model=model)
    plot_indices(FIGURES / "sobol_flexspline_indices.png", names, res.analysis,
                 title="CSG-25-100 lost motion, ±10 % flexspline dimensions, N = 1024")
    plot_convergence(FIGURES / "sobol_flexspline_convergence.png", names, res.convergence)
    for key in ("S1", "ST"):
        print(f"{key}: " + ", ".join(f"{n} {v:.3f}" for n, v in zip(names, res.analysis[key])))
    print(f"{res.evaluations} simulations in {res.seconds:.1f} s")


def evaluators() -> None:
    """The seed study's box through both evaluators: row by row (1024 rows) and the indices
    (N = 1024, second order), with the wall time of each study on 2 workers."""
    import json
    import time

    import hdsim
    from hdsim.sensitivity.scenario_outputs import ScenarioMetric, nominal_values

    names = ["h_pz", "h_c", "R_v", "R_k", "h_p"]
    dotted = tuple(f"flexspline.{n}" for n in names)
    nominal = np.array(list(nominal_values("CSG-25-100", dotted).values()))
    X = nominal * (1.0 + 0.1 * (2.0 * np.random.default_rng(0).random((1024, len(names))) - 1.0))
    studies, seconds = {}, {}
    # the studies first: their pools fork from a process that has not run numba's OpenMP yet
    for ev in ("quasistatic", "dynamic"):
        t0 = time.perf_counter()
        studies[ev] = hdsim.sobol("CSG-25-100", names, "lost_motion_arcmin", n=1024, second_order=True,
                                  progress=False, evaluator=ev)
        seconds[ev] = time.perf_counter() - t0
    rows = {ev: ScenarioMetric("CSG-25-100", dotted, "lost_motion_arcmin", "lost_motion", evaluator=ev)(X)
            for ev in ("dynamic", "quasistatic")}
    relative = rows["quasistatic"] / rows["dynamic"] - 1.0
    fig = Figure(figsize=(9.0, 3.4))
    left, right = fig.subplots(1, 2)
    left.scatter(rows["dynamic"], 1e3 * relative, s=4)
    left.axhspan(-1.0, 1.0, color="0.9", zorder=0, label="±1e-3 (the agreement asked for)")
    left.set_xlabel("lost motion, solve_ivp [arcmin]")
    left.set_ylabel("quasi-static − solve_ivp [1e-3 relative]")
    left.set_title(f"1024 rows of the box: largest |difference| {np.max(np.abs(relative)):.1e}", fontsize=9)
    left.legend(fontsize=8, frameon=False)
    x = np.arange(len(names))
    for shift, ev in ((-0.2, "dynamic"), (0.2, "quasistatic")):
        right.bar(x + shift, studies[ev].analysis["ST"], 0.4, label=f"{ev}: {seconds[ev]:.1f} s")
    right.set_xticks(x, names)
    right.set_ylabel("total index ST [-]")
    gap = np.max(np.abs(studies["quasistatic"].analysis["ST"] - studies["dynamic"].analysis["ST"]))
    right.set_title(f"N = 1024, second order, 12,288 rows: largest |ΔST| {gap:.4f}", fontsize=9)
    right.legend(fontsize=8, frameon=False, title="evaluator: study time on 2 workers", title_fontsize=8)
    fig.tight_layout()
    save_figure(fig, FIGURES / "sobol_evaluator_agreement.png")
    summary = {"rows": len(X), "max_relative_difference": float(np.max(np.abs(relative))),
               "ST": {ev: dict(zip(names, np.round(studies[ev].analysis["ST"], 4).tolist())) for ev in studies},
               "max_abs_ST_difference": float(gap), "study_seconds": {k: round(v, 1) for k, v in seconds.items()}}
    (FIGURES / "sobol_evaluator_agreement.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps(summary, indent=1))


def driven() -> None:
    """The contract kinematic-error run through both evaluators: the deviation over each
    measured pass and the difference, with the metrics side by side."""
    import json
    import time

    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.run import run_scenario
    from hdsim.units import rad_to_arcsec

    unit = load_unit("CSG-25-100")
    runs, seconds = {}, {}
    for ev in ("dynamic", "quasistatic"):
        t0 = time.perf_counter()
        runs[ev] = run_scenario(unit, "kinematic_error", evaluator=ev)
        seconds[ev] = time.perf_counter() - t0
    t = runs["dynamic"].result.t
    fig = Figure(figsize=(9.0, 3.6))
    left, right = fig.subplots(1, 2)
    for name, (a, b) in runs["dynamic"].result.metadata["windows"].items():
        inside = (t >= a) & (t <= b)
        wg = np.rad2deg(runs["dynamic"].result.signals["wg_angle_rad"][0, inside] / 100.0)
        q = {ev: rad_to_arcsec(runs[ev].result.signals["deviation_rad"][0, inside]) for ev in runs}
        left.plot(wg, q["dynamic"], lw=0.8, label=f"{name}, solve_ivp")
        left.plot(wg, q["quasistatic"], lw=0.8, ls="--", label=f"{name}, quasi-static")
        right.plot(wg, q["quasistatic"] - q["dynamic"], lw=0.8, label=name)
    left.set_xlabel("output angle [deg]")
    left.set_ylabel("deviation θ_out − θ_WG/N [arcsec]")
    left.set_title(f"contract run: solve_ivp {seconds['dynamic']:.1f} s, quasi-static {seconds['quasistatic']:.2f} s",
                   fontsize=9)
    left.legend(fontsize=7, frameon=False, ncol=2)
    right.axhspan(-0.1, 0.1, color="0.9", zorder=0, label="±0.1 arcsec (the agreement asked for)")
    right.set_xlabel("output angle [deg]")
    right.set_ylabel("quasi-static − solve_ivp [arcsec]")
    names = ("transmission_accuracy_arcsec", "lost_motion_on_reversal_arcsec", "windup_arcsec")
    metrics = {n: {ev: round(float(runs[ev].metric(n)), 4) for ev in runs} for n in names}
    right.set_title("TA {0[dynamic]:.3f} / {0[quasistatic]:.3f} arcsec".format(metrics[names[0]]), fontsize=9)
    right.legend(fontsize=8, frameon=False)
    fig.tight_layout()
    save_figure(fig, FIGURES / "driven_evaluator_agreement.png")
    summary = {"metrics": metrics, "seconds": {k: round(v, 2) for k, v in seconds.items()}}
    (FIGURES / "driven_evaluator_agreement.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps(summary, indent=1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--unit", action="store_true", help="also run the flexspline study")
    ap.add_argument("--evaluators", action="store_true",
                    help="only the agreement of the quasi-static evaluator with solve_ivp")
    ap.add_argument("--driven", action="store_true",
                    help="only the agreement of the driven bench's quasi-static evaluator with solve_ivp")
    args = ap.parse_args()
    if args.evaluators or args.driven:
        if args.evaluators:
            evaluators()
        if args.driven:
            driven()
        return
    closed_forms()
    pairing()
    if args.unit:
        flexspline()
    print("figures in", FIGURES)


if __name__ == "__main__":
    main()
