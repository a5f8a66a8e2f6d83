"""The diagnosis report reads top-down: outcome and data checks first, the residual against
time as the first figure, and no figure that cannot answer its question (a loop-vs-rate
plot of a record with one loading rate)."""

from __future__ import annotations

import truth
from hdsim.identification.diagnosis import diagnose
from hdsim.io.measurement import make_measurement


def test_outcome_and_checks_on_top_and_no_rate_plot_for_one_rate(tmp_path):
    cols, _ = truth.make_stiffness_data({"friction"}, set(), seed=7, n_rows=300, quarter_s=(1.0,))
    meas = make_measurement("stiffness", cols["time_s"], cols["torque_Nm"], cols["angle_rad"], rated_torque=87.0)
    result = diagnose(meas, "friction", families=["hardening"], max_rounds=0)
    assessment = {"outcome": "cannot_decide", "next_measurement": "a second loading rate",
                  "checks": [{"check": "loading_rates", "status": "warn", "message": "1 distinct loading rate"}]}
    result.report(tmp_path, assessment)
    md = (tmp_path / "index.md").read_text().splitlines()
    assert md[2] == "**Outcome: cannot decide; to decide, record a second loading rate**"
    assert "| warn | loading_rates | 1 distinct loading rate |" in md[:12]
    figures = [line for line in md if line.startswith("![")]
    assert figures[0].endswith("](residual_vs_time.png)")
    # every figure says what it shows: its alt text and caption are words, not its file name
    assert all(not line.startswith("![" + line.split("](")[1][:-1]) for line in figures)
    assert not (tmp_path / "residual_vs_rate.png").exists()
    assert all("residual_vs_rate" not in line for line in figures)
    html = (tmp_path / "index.html").read_text()
    assert html.index("Outcome: cannot decide") < html.index("Verdict:") < html.index("Before and after")
