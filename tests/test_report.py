"""The diagnosis report reads top-down: outcome and data checks first, the residual against
time as the first figure, and no figure that cannot answer its question (a loop-vs-rate
plot of a record with one loading rate)."""

from __future__ import annotations

import numpy as np
import pytest
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
    # first a summary box, then the outcome line, the verdict and the checks, before any table of fits
    assert md[2:5] == ["| summary |  |", "|---|---|", "| outcome | cannot decide |"]
    assert "**Outcome: cannot decide; to decide, record a second loading rate**" in md[:14]
    assert "| warn | loading_rates | 1 distinct loading rate |" in md[:22]
    figures = [line for line in md if line.startswith("![")]
    assert figures[0].endswith("](residual_vs_time.png)")
    # every figure says what it shows: its alt text and caption are words, not its file name
    assert all(not line.startswith("![" + line.split("](")[1][:-1]) for line in figures)
    assert not (tmp_path / "residual_vs_rate.png").exists()
    assert all("residual_vs_rate" not in line for line in figures)
    html = (tmp_path / "index.html").read_text()
    assert html.index("Outcome: cannot decide") < html.index("Verdict:") < html.index("Before and after")
    # beside the predictions, the verdict's own judgement and ratio (this record: rms 1.3× the floor)
    verdict = next(line for line in md if line.startswith("Verdict: "))
    assert verdict.startswith("Verdict: residual not white")
    ratio = verdict.split(" rms ", 1)[1].split("×")[0]
    caveat = next(line for line in md if "The model leaves structure" in line)
    assert f"(rms {ratio}× the noise floor)" in caveat
    assert md.index("## What the fitted drive predicts") < md.index(caveat)


def test_the_page_says_how_to_reproduce_it_and_rounds_values_to_their_uncertainty(tmp_path):
    from hdsim.identification.report_page import rounded

    assert rounded(0.0512, 0.00034) == "0.05120 ± 0.00034"
    assert rounded(-0.75, 0.042) == "-0.750 ± 0.042"
    assert rounded(2.3e-5, 1.1e-6) == "(2.30 ± 0.11)e-5"
    assert rounded(6.304, None) == "6.304"
    cols, tr = truth.make_stiffness_data({"friction"}, set(), seed=7, n_rows=300)
    truth.write_csv(tmp_path / "bench.csv", cols, tr["meta"])
    from hdsim.io.measurement import load_measurement
    import hashlib

    result = diagnose(load_measurement(tmp_path / "bench.csv"), "friction", families=["hardening"], max_rounds=0)
    result.report(tmp_path / "rep")
    md = (tmp_path / "rep" / "index.md").read_text()
    assert hashlib.sha256((tmp_path / "bench.csv").read_bytes()).hexdigest() in md
    assert "| hdsim |" in md and "Fitted parameters" in md and " ± " in md
    # one noise floor on the page: the summary's (the final model's white residual) is the
    # one the baseline's and the final model's findings are read against
    from hdsim.identification.residuals import findings
    from hdsim.units import ARCSEC_PER_RAD

    cols, tr = truth.make_stiffness_data({"friction", "hardening"}, set(), seed=11, n_rows=1200)
    truth.write_csv(tmp_path / "hardening.csv", cols, tr["meta"])
    d = diagnose(load_measurement(tmp_path / "hardening.csv"), "friction", families=["hardening"]).to_json()
    assert d["added"] == ["hardening"]  # two models: the baseline's residual and the final one's
    floor = f"{d['whiteness']['noise_floor_rad'] * ARCSEC_PER_RAD:.1f} arcsec"
    assert [d["findings"]["baseline"][0].rsplit("noise floor of ", 1)[1],
            d["findings"]["final"][0].rsplit("noise floor of ", 1)[1]] == [floor, floor]
    meas = load_measurement(tmp_path / "bench.csv")
    rng = np.random.default_rng(0)
    for residual in (rng.normal(0, 1e-6, len(meas)), rng.normal(0, 5e-6, len(meas))):  # two models' residuals
        assert findings(meas, residual, floor=2e-6)[0].endswith(f"noise floor of {2e-6 * ARCSEC_PER_RAD:.1f} arcsec")


def test_a_decision_says_how_an_error_changed_in_words():
    from hdsim.identification.selection import _change

    assert _change("rms error", 0.0, 0.05) == "rms error does not change (5 % fall needed)"
    assert _change("rms error", -2.498, 0.05) == "rms error rises by 250 % (5 % fall needed)"
    assert _change("hold-out error", 0.032, 0.05) == "hold-out error falls by only 3.2 % (5 % fall needed)"


def test_fit_report_writes_one_self_contained_page(tmp_path, cli):
    cols, tr = truth.make_stiffness_data({"friction"}, set(), seed=7, n_rows=300)
    truth.write_csv(tmp_path / "bench.csv", cols, tr["meta"])
    code, out, err = cli("fit", "bench.csv", "--effects", "friction", "--report", "page", "--json", cwd=tmp_path)
    assert code == 0, err
    import json

    assert json.loads(out)["report"] == "page/index.html"
    html = (tmp_path / "page" / "index.html").read_text()
    md = (tmp_path / "page" / "index.md").read_text()
    # every figure of the Markdown page is embedded in the HTML one, which fetches nothing
    assert html.count('src="data:image/png;base64,') == md.count("![") >= 2
    assert html.count("src=") == md.count("![")
    assert "Fitted parameters" in md and "SHA-256" in md and "| effects | friction |" in md


def test_the_parameter_table_gives_each_parameter_its_unit():
    from hdsim.identification.breakaway import BreakawayTest
    from hdsim.identification.diagnosis import StiffnessTest
    from hdsim.identification.running_diagnosis import RunningTorqueTest
    from hdsim.model.catalog import load_unit

    class Fitted:  # what the twist kinds read of a fit: its model
        model = load_unit()

    assert StiffnessTest().parameter_unit(Fitted, "friction.slip_torque") == "N·m"
    assert StiffnessTest().parameter_unit(Fitted, "damping.coefficient") == "N·m·s/rad"
    assert StiffnessTest().parameter_unit(Fitted, "no.such") == ""
    sweep = RunningTorqueTest()
    assert [sweep.parameter_unit(None, n) for n in ("base.coulomb_torque", "damping.viscous", "base.inertia",
                                                    "ripple.ripple_cos_2", "friction.stribeck_speed")] == [
        "N·m", "N·m·s/rad", "kg·m²", "N·m", "rad/s"]
    assert BreakawayTest().parameter_unit(None, "viscous") == "N·m·s/rad"
    assert "file's shaft" in BreakawayTest.parameters_heading and "wave-generator" in sweep.parameters_heading


def test_a_sweeps_law_is_shown_to_four_digits_with_its_ripple_in_newton_metres():
    from hdsim.identification.running_report import law_rows

    table = {"starting_torque_Nm": 0.07695981543068439, "coulomb_share": 0.5231135802718493,
             "stribeck_speed_rpm": 42.080978193589985, "viscous_Nms": 0.0, "coulomb_asymmetry_Nm": 2.2688e-05,
             "ripple_orders": [1.0, 2.0], "ripple_amplitudes_of_level": [0.022396766274298555, 0.1122728892558],
             "ripple_phases": [-0.863330381759471, 1.3053499705680724], "position_torque_orders": [],
             "position_torque_amplitudes_Nm": [], "position_torque_phases": []}
    rows = {name: (value, unit) for name, value, unit in law_rows(table)}
    level = 0.07695981543068439 * 0.5231135802718493
    assert rows["Coulomb level F_c"] == (f"{level:.4g}", "N·m")
    assert rows["ripple amplitudes"] == (f"{level * 0.022396766274298555:.4g}, {level * 0.1122728892558:.4g}", "N·m")
    assert rows["starting torque F_s"][0] == "0.07696" and rows["position torque orders"][0] == "none"


def test_a_loop_that_widens_with_the_loading_rate_is_found_when_most_rows_load_slowly():
    """Two slow cycles and two fast ones, sampled alike, so three rows in four load slowly:
    a residual loop whose half-width grows with the rate (a ``−a·dT/dt`` lag, as damping
    leaves) is told as one ``2a(R_fast − R_slow)`` wider at the fast rate."""
    import re

    from hdsim.identification.residuals import findings
    from hdsim.io.measurement import make_measurement
    from hdsim.units import ARCSEC_PER_RAD

    amplitude, slow, fast, fs = 80.0, 80.0, 320.0, 400.0
    legs = [(slow, 1.0 if k % 2 == 0 else -1.0) for k in range(8)] + [(fast, 1.0 if k % 2 == 0 else -1.0)
                                                                        for k in range(8)]
    torque, rate = [0.0], []
    for speed, sign in legs:  # each leg from one peak to the other (the first from zero)
        target = sign * amplitude
        n = int(round(abs(target - torque[-1]) / speed * fs))
        torque += list(np.linspace(torque[-1], target, n + 1)[1:])
        rate += [sign * speed] * n
    torque, rate = np.array(torque[1:]), np.array(rate)
    time = np.arange(torque.size) / fs
    a = 1e-7  # rad per N·m/s
    meas = make_measurement("stiffness", time, torque, torque / 3e4, rated_torque=87.0)
    said = [s for s in findings(meas, -a * rate, floor=1e-7) if "at the fast loading rate" in s]
    assert len(said) == 1 and "wider" in said[0], said
    width = float(re.search(r"loop is ([\d.]+) arcsec", said[0]).group(1))
    assert width == pytest.approx(2 * a * (fast - slow) * ARCSEC_PER_RAD, rel=0.1)


def test_an_empty_table_or_list_is_left_out_whatever_iterable_holds_it():
    from hdsim.identification.report_page import Page

    page = Page("t").table(("a",), (r for r in [])).bullets(x for x in []).table(("a",), iter([("1",)]))
    assert page.blocks == [("table", (("a",), [("1",)]))]


def test_the_summary_never_says_none_needed_beside_an_open_question():
    # a near tie decided by its score keeps the measurement that would settle it, and a
    # result that is not a success says "—", not "none needed" (the page had said both)
    from hdsim.identification.outcome import assess
    from hdsim.identification.report_page import Page, _summary_box
    from hdsim.identification.test_kinds import test_kind

    kind = test_kind("stiffness")
    tie = {"families": ["friction", "hardening"], "scores": [-0.44, -0.40], "round": 1, "added": True,
           "measurement": "unloading from several peak torques"}
    found = {"success": True, "added": ["friction"], "ranking": [], "ambiguous": [tie]}
    assert assess(found, {"rows": 300}, kind) == ("found", "unloading from several peak torques")

    def box(outcome, next_measurement):
        page = Page("t")
        _summary_box(page, {"outcome": outcome, "added": ["damping"], "next_measurement": next_measurement,
                            "whiteness": {"noise_floor_rad": 1e-6}, "baseline": {"rmse_rad": 2e-5},
                            "final": {"rmse_rad": 3e-6}}, kind)
        return page.markdown()

    assert "| next measurement | — |" in box("improved", "")
    assert "| next measurement | none needed |" in box("found", "")


def test_a_kinematic_error_fit_is_drawn_against_the_output_angle(tmp_path, png_image):
    # it was drawn against the torque, a cloud for a driven record, captioned "loading and unloading"
    from pathlib import Path

    import hdsim
    from hdsim.identification.report import twist_fit_figure

    result = hdsim.fit(Path(__file__).parent / "data" / "ke_example.csv", "kinematic_error")
    path, caption = twist_fit_figure(result, tmp_path)
    png_image(path)
    assert caption.startswith("Measured kinematic error against the output angle")
