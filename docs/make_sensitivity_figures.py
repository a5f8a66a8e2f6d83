"""Regenerate the figures of docs/sensitivity.md into docs/figures/.

    python docs/make_sensitivity_figures.py            # closed forms (about 10 s)
    python docs/make_sensitivity_figures.py --unit     # plus the flexspline study

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--unit", action="store_true", help="also run the flexspline study")
    args = ap.parse_args()
    closed_forms()
    pairing()
    if args.unit:
        flexspline()
    print("figures in", FIGURES)


if __name__ == "__main__":
    main()
