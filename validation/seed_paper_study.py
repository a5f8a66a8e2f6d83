"""The seed paper's study re-run through the simulator: five flexspline dimensions, ±10 %.

Lost motion at ±4 % T_N of the default CSG-25-100, N = 1024 base points with second
order (12,288 simulations), indices beside the paper's Table 1, a figure, and the
share of compliance each dimension acts on (to explain the ranking).

The study runs on the closed-form chain. Its cup (diaphragm to undercut) stands in for
the finite-element cup (`hdsim compliance --fe`): the script checks that at the 32
corners of the ±10 % box and records the largest difference (needs scikit-fem).

    python validation/seed_paper_study.py [--n 1024]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hdsim.sensitivity.scenario_outputs import model_function, nominal_values  # noqa: E402
from hdsim.model.catalog import load_unit  # noqa: E402
from hdsim.sensitivity.problem import build_problem  # noqa: E402
from hdsim.sensitivity.study import run_study  # noqa: E402

NAMES = ["h_pz", "h_c", "R_v", "R_k", "h_p"]
TABLE_S1 = [0.07715, 0.08594, 0.005284, 0.002737, 0.0001973]
TABLE_ST = [0.6969, 0.5974, 0.1497, 0.2385, 0.2825]
HERE = Path(__file__).resolve().parent


def elasticities(unit="CSG-25-100"):
    """d ln K / d ln x for each dimension at nominal (central differences, ±1 %)."""
    model = load_unit(unit)
    out = {}
    for name in NAMES:
        key = f"flexspline.{name}"
        x = model.params()[key]
        up = model.with_updates({key: 1.01 * x}).base_stiffness
        down = model.with_updates({key: 0.99 * x}).base_stiffness
        out[name] = float(np.log(up / down) / np.log(1.01 / 0.99))
    return out


def fe_cup_check(unit="CSG-25-100"):
    """FE cup over closed-form cup at the nominal shape and the 32 corners of the box."""
    from hdsim.model.fe_check import corner_shapes, fe_cup_check

    model = load_unit(unit)
    ratios = [fe_cup_check(shape)["ratio"] for shape in [model, *corner_shapes(model, NAMES)]]
    return {"shapes": len(ratios), "nominal": ratios[0], "min": min(ratios), "max": max(ratios)}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--n", type=int, default=1024)
    args = parser.parse_args()
    func = model_function("CSG-25-100", NAMES, "lost_motion_arcmin")
    problem = build_problem(NAMES, nominal_values("CSG-25-100", NAMES), 0.10, None, None)
    study = run_study(func, problem, args.n, second_order=True, seed=0, progress=True)
    a = study.analysis
    chain = {k: float(v) for k, v in load_unit().compliance().as_dict().items()}
    total = sum(chain.values())
    result = {
        "n": args.n, "evaluations": study.evaluations, "seconds": study.seconds,
        "S1": dict(zip(NAMES, np.round(a["S1"], 4).tolist())),
        "S1_conf_replicates": dict(zip(NAMES, np.round(a["S1_conf_replicates"], 4).tolist())),
        "ST": dict(zip(NAMES, np.round(a["ST"], 4).tolist())),
        "ST_conf_replicates": dict(zip(NAMES, np.round(a["ST_conf_replicates"], 4).tolist())),
        "sum_S1": float(np.sum(a["S1"])), "sum_ST": float(np.sum(a["ST"])),
        "table1": {"S1": dict(zip(NAMES, TABLE_S1)), "ST": dict(zip(NAMES, TABLE_ST))},
        "stiffness_elasticity": elasticities(),
        "fe_cup_over_closed_form": fe_cup_check(),
        "compliance_share": {k: v / total for k, v in chain.items()},
        "checks_ok": study.checks["ok"],
    }
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "seed_paper_study.json").write_text(json.dumps(result, indent=2))

    x, w = np.arange(len(NAMES)), 0.2
    fig, ax = plt.subplots(figsize=(7.5, 3.8), layout="constrained")
    ax.bar(x - 1.5 * w, a["S1"], w, yerr=a["S1_conf_replicates"], label="hdsim S1", color="tab:blue")
    ax.bar(x - 0.5 * w, a["ST"], w, yerr=a["ST_conf_replicates"], label="hdsim ST", color="tab:orange")
    ax.bar(x + 0.5 * w, TABLE_S1, w, label="paper Table 1 S1", color="tab:blue", alpha=0.35, hatch="//")
    ax.bar(x + 1.5 * w, TABLE_ST, w, label="paper Table 1 ST", color="tab:orange", alpha=0.35, hatch="//")
    ax.set_xticks(x, NAMES)
    ax.set_ylabel("Sobol' index [-]")
    ax.set_title(f"lost motion at ±4 % T_N, CSG-25-100, ±10 % dimensions "
                 f"(N = {args.n}, {study.evaluations} simulations)", fontsize=9)
    ax.legend(fontsize=8, ncol=2, frameon=False)
    fig.savefig(HERE / "figures" / "seed_paper_indices.png", dpi=120)
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
