"""``hdsim compliance``: the segments of the chain as the contract prints them."""

from __future__ import annotations

import json

import pytest

from hdsim.cli import main
from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import catalog_entry

SEGMENTS = ("diaphragm", "end_radius", "cylinder", "lead_radius", "undercut")


@pytest.fixture
def coarse_rim(monkeypatch):
    """The rim FE at refinement 1 (about 1.5 % stiff, five times quicker) for CLI tests; its
    accuracy is tested in tests/test_fe_rim.py."""
    import functools

    from hdsim.model import fe_check

    monkeypatch.setattr(fe_check, "fe_rim_stiffness", functools.partial(fe_check.fe_rim_stiffness, refinement=1))


def _json(capsys, *argv):
    assert main(["compliance", "--json", *argv]) == 0
    return json.loads(capsys.readouterr().out)


def test_json_holds_the_segments_the_cup_and_the_catalog_total(capsys):
    report = _json(capsys, "--unit", "CSG-17-100")
    closed = report["closed_form"]
    assert report["unit"] == "CSG-17-100"
    assert set(closed) == set(SEGMENTS) | {"cup", "rim", "mesh_zone", "total"}
    assert closed["cup"] == pytest.approx(sum(closed[s] for s in SEGMENTS), rel=1e-12)
    # the calibrated chain reproduces the catalog K1 (the meaning of kappa_mesh)
    assert 1.0 / closed["total"] == pytest.approx(catalog_entry("CSG-17-100")["K1"], rel=1e-9)
    assert report["calibration"]["kappa_mesh"] == pytest.approx(
        load_unit("CSG-17-100").calibration.kappa_mesh, rel=1e-12)
    assert "fe" not in report


def test_a_thicker_cylinder_changes_the_cylinder_by_the_tube_law(capsys):
    g = load_unit().geometry
    base = _json(capsys)["closed_form"]
    h_c = 1.2 * g.h_c
    thicker = _json(capsys, "--set", f"flexspline.h_c={h_c!r}")["closed_form"]
    # thin tube: C ∝ 1 / (R_c³ h_c) with R_c = R_i + h_c/2 and R_i fixed
    expected = (g.R_c**3 * g.h_c) / ((g.R_i + h_c / 2) ** 3 * h_c)
    assert thicker["cylinder"] / base["cylinder"] == pytest.approx(expected, rel=1e-9)
    assert thicker["diaphragm"] != base["diaphragm"]  # the diaphragm ends where the fillet starts


def test_the_table_lists_every_segment(capsys):
    assert main(["compliance"]) == 0
    out = capsys.readouterr().out
    for label in ("diaphragm", "end radius", "cylinder", "lead radius", "undercut", "mesh zone", "total"):
        assert label in out


@pytest.mark.parametrize("argv", [["--set", "flexspline.h_c=-1"], ["--set", "flexspline.nope=1"],
                                  ["--unit", "CSG-99-100"], ["--set", "scenario.load.rate=1"]])
def test_bad_input_is_one_line_and_exit_2(capsys, argv):
    assert main(["compliance", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hdsim compliance: error:")


def test_fe_gives_the_cup_a_second_opinion(capsys, coarse_rim):
    report = _json(capsys, "--fe", "--unit", "CSG-32-100")
    fe = report["fe"]
    assert set(fe) == {"cup", "elements", "seconds", "change", "ratio", "rim_radial"}
    assert fe["ratio"] == pytest.approx(fe["cup"] / report["closed_form"]["cup"], rel=1e-12)
    assert fe["ratio"] == pytest.approx(1.0, abs=0.01) and fe["change"] < 0.005 and fe["elements"] > 100
    rim = fe["rim_radial"]
    assert rim["ratio"] == pytest.approx(rim["fe"] / rim["closed_form"], rel=1e-12)
    assert rim["ratio"] == pytest.approx(1.0, abs=0.05)  # measured 1.005 (docs/physics.md §3.7)
    assert main(["compliance", "--fe"]) == 0
    out = capsys.readouterr().out
    assert "cup by finite elements" in out and "rim on the balls" in out


def test_fe_without_scikit_fem_says_how_to_install_it(capsys, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "skfem", None)  # `import skfem` fails
    assert main(["compliance", "--fe"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pip install 'hdsim[fe]'" in err[0]


def test_fe_takes_the_set_dimensions(capsys, coarse_rim):
    """--set acts on the FE section as on the closed forms: a larger end radius and a
    thinner cylinder both soften the cup in both."""
    g = load_unit().geometry
    report = _json(capsys, "--fe", "--set", f"flexspline.R_k={1.1 * g.R_k!r}",
                   "--set", f"flexspline.h_c={0.9 * g.h_c!r}")
    base = _json(capsys, "--fe")
    assert report["fe"]["cup"] > base["fe"]["cup"] and report["closed_form"]["cup"] > base["closed_form"]["cup"]
    assert report["fe"]["ratio"] == pytest.approx(1.0, abs=0.01)


def test_the_fe_check_says_it_alone_refuses_and_never_builds_a_mesh_without_bound(monkeypatch):
    # a wall a hundred times thinner than the catalog's needed 542,072 elements and 2.2 GB; the
    # cap is lowered here so that the catalog drive meets it
    import pytest

    import hdsim
    from hdsim.errors import InputError
    from hdsim.model.fe_check import compliance_report

    pytest.importorskip("skfem")
    monkeypatch.setattr("hdsim.physics.fe_cup.MAX_ELEMENTS", 1000)
    with pytest.raises(InputError) as err:
        compliance_report(hdsim.load_unit("CSG-25-100"), fe=True)
    text = str(err.value)
    assert text.startswith("the finite-element check refuses this drive, which the closed forms accept")
    assert "elements for this section" in text and "it stops at 1,000" in text and "\n" not in text
