"""Regenerate the figures of docs/tutorial-find-missing-effect.md.

Run from the repository root::

    python docs/make_diagnosis_figures.py

It writes ``docs/figures/tutorial_bench.csv`` (a bench file with a hidden effect, from
``tests/truth.py``), runs the diagnosis as ``hdsim diagnose`` does, and writes its report
figures as ``docs/figures/diagnosis_*.png`` plus ``docs/figures/diagnosis.json``.
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIG = ROOT / "docs" / "figures"


def main() -> None:
    sys.path.insert(0, str(ROOT / "tests"))
    import truth

    from hdsim.identification.diagnosis import diagnose
    from hdsim.io.measurement import load_measurement
    from hdsim.identification.report import FIGURES

    FIG.mkdir(parents=True, exist_ok=True)
    cols, tr = truth.make_stiffness_data({"damping"}, {"friction"}, seed=1, n_rows=2000)
    data = FIG / "tutorial_bench.csv"
    truth.write_csv(data, cols, tr["meta"])
    meas = load_measurement(data)
    result = diagnose(meas, "friction")
    with tempfile.TemporaryDirectory() as tmp:
        result.report(tmp)
        for name in FIGURES:
            shutil.copy(Path(tmp) / name, FIG / f"diagnosis_{name}")
    summary = result.to_json()
    (FIG / "diagnosis.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps({k: summary[k] for k in ("added", "ambiguous", "verdict")}, indent=1))


if __name__ == "__main__":
    main()
