"""``hdsim sobol`` command line: contract JSON, figures, one-line errors."""

import json

import pytest

from hdsim.cli import main

CONTRACT_KEYS = {"output", "n", "evaluations", "params", "S1", "S1_conf", "ST", "ST_conf",
                 "seconds", "study"}


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_function_json_follows_contract(capsys):
    out = _json(capsys, ["sobol", "--function", "ishigami", "--n", "4096", "--workers", "1",
                         "--json"])
    assert CONTRACT_KEYS <= set(out)
    assert out["output"] == "ishigami" and out["n"] == 4096 and out["evaluations"] == 20480
    assert out["params"] == ["x1", "x2", "x3"] and out["study"] is None
    for key in ("S1", "ST"):
        assert max(abs(out[key][p] - out["analytic"][key][p]) for p in out["params"]) <= 0.02
    assert set(out["S1_conf"]) == set(out["params"]) and out["checks"]["ok"]


def test_second_order_evaluations_and_s2(capsys):
    out = _json(capsys, ["sobol", "--function", "linear", "--n", "64", "--second-order",
                         "--workers", "1", "--json"])
    assert out["evaluations"] == 64 * (2 * 4 + 2)
    assert set(out["S2"]) == {"x1", "x2", "x3"} and set(out["S2"]["x1"]) == {"x2", "x3", "x4"}


def test_out_writes_study_summary_and_figures(tmp_path, capsys, png_image):
    study = tmp_path / "g.h5"
    assert main(["sobol", "--function", "gfunction", "--n", "256", "--workers", "1", "--out", str(study),
                 "--json"]) == 0
    printed = capsys.readouterr()
    out = json.loads(printed.out)
    assert out["study"] == str(study) and study.exists()
    # it says what it wrote, as `hdsim simulate` does
    assert f"wrote {study}, {tmp_path / 'g.json'}, {tmp_path / 'g_indices.png'}" in printed.err
    summary = json.loads((tmp_path / "g.json").read_text())
    assert summary["S1"] == out["S1"]
    assert set(summary["figures"]) == {str(tmp_path / "g_indices.png"), str(tmp_path / "g_convergence.png")}
    for name in summary["figures"]:
        png_image(name)
    again = _json(capsys, ["sobol", "--function", "gfunction", "--n", "256", "--workers", "1",
                           "--out", str(study), "--resume", "--json"])
    assert again["evaluated_now"] == 0 and again["S1"] == out["S1"]
    report = tmp_path / "rep"
    main(["sobol", "--function", "ishigami", "--n", "64", "--workers", "1",
          "--report", str(report)])
    text = capsys.readouterr().out
    assert "x1" in text
    png_image(report / "sobol_indices.png")


@pytest.fixture
def quick_figures(monkeypatch):
    """The figures as a few bytes each: which files a study leaves is the point, not the plots."""
    from pathlib import Path

    from hdsim.plotting import sensitivity

    def write(path, *args, **kwargs):
        Path(path).write_bytes(b"figure")
        return Path(path)

    monkeypatch.setattr(sensitivity, "plot_indices", write)
    monkeypatch.setattr(sensitivity, "plot_convergence", write)


def test_a_study_written_again_leaves_no_figure_of_the_last_one(tmp_path, capsys, quick_figures):
    """A convergence figure of N = 64 had stayed beside the study resumed at N = 16 (which
    draws none), and beside a --report into the folder of an earlier --out study; a study of
    another stem in the folder, and a file hdsim did not write, are left alone."""
    def study(n, *where):
        assert main(["sobol", "--function", "ishigami", "--n", str(n), "--workers", "1",
                     *where]) == 0, capsys.readouterr().err

    def pngs():
        return sorted(p.name for p in tmp_path.glob("*.png"))

    study(64, "--out", str(tmp_path / "s.h5"))
    study(64, "--out", str(tmp_path / "other.h5"))
    (tmp_path / "mine_convergence.png").write_bytes(b"the user's")
    assert pngs() == ["mine_convergence.png", "other_convergence.png", "other_indices.png",
                      "s_convergence.png", "s_indices.png"]
    study(16, "--out", str(tmp_path / "s.h5"), "--resume")
    assert pngs() == ["mine_convergence.png", "other_convergence.png", "other_indices.png", "s_indices.png"]
    study(64, "--out", str(tmp_path / "sobol.h5"))
    study(16, "--report", str(tmp_path))  # the report's stem is 'sobol': the same files
    assert "sobol_convergence.png" not in pngs() and "other_convergence.png" in pngs()


def test_a_studys_files_are_listed_in_one_manifest_which_takes_them_over_from_the_other(tmp_path, capsys,
                                                                                       quick_figures):
    """A --report study had listed its files in the folder's manifest and again in its stem's;
    now the --report folder's own lists them, an --out study's stem's beside it, and each takes
    over what the other listed (removing the figure it no longer draws)."""
    def listed(manifest):
        path = tmp_path / manifest
        return path.exists() and sorted(e["name"] for e in json.loads(path.read_text())["files"])

    def study(n, *where):
        assert main(["sobol", "--function", "ishigami", "--n", str(n), "--workers", "1", *where]) == 0
        return listed(".hdsim-report.json"), listed(".hdsim-sobol-sobol.json")

    three = ["sobol.json", "sobol_convergence.png", "sobol_indices.png"]
    assert study(64, "--report", str(tmp_path)) == (three, False)
    assert study(16, "--out", str(tmp_path / "sobol.h5")) == (False, ["sobol.json", "sobol_indices.png"])
    assert not (tmp_path / "sobol_convergence.png").exists()
    assert study(64, "--report", str(tmp_path)) == (three, False)


@pytest.mark.parametrize("argv, fragment", [
    (["--function", "nope"], "unknown function 'nope'"),
    (["--function", "ishigami", "--n", "1000"], "power of 2"),
    (["--function", "ishigami", "--n", "lots"], "--n expects an integer"),
    (["--model", "hdsim.sensitivity.functions:Ishigami", "--params", "x1,x2,x3",
      "--bounds", "x1=3:1", "x2=0:1", "x3=0:1"], "lo < hi"),
    (["--model", "hdsim.sensitivity.functions:Ishigami", "--params", "x1,x2,x3",
      "--bounds", "x1=zero:1"], "LO:HI"),
    (["--model", "hdsim.sensitivity.functions:Ishigami", "--params", "x1,x2",
      "--bounds", "x9=0:1"], "unknown parameter"),
    # a misspelled drive parameter is named so, as the library does, not asked for its bounds
    (["--unit", "CSG-25-100", "--params", "h_x", "--output", "lost_motion_arcmin"], "unknown parameter 'h_x'"),
    (["--function", "ishigami", "--executor", "spark://x"], "--executor"),
    (["--function", "ishigami", "--resume"], "--resume needs --out"),
    ([], "say what to study"),
])
def test_bad_input_exits_2_with_one_line(argv, fragment, capsys):
    assert main(["sobol", *argv, "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0], captured.err


# A unit's study through the simulator: tests/test_batch.py::test_sobol_cli_on_the_simulator
# (one study of the lost-motion test checks the contract JSON, the checks and the model).
