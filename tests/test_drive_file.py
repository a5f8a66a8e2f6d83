"""Drive files (contracts §4): any drive from its datasheet, wherever a unit name is accepted.

The expected numbers are the figures written into the drive files (catalog data, or the
contract's ZXF17-50 datasheet) and the closed forms of the three-segment law and of the
elastic lost-motion span (docs/physics.md §13), never values produced by the code under test.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import catalog_entry, unit_names
from hdsim.scenarios.run import read_run, run_scenario
from hdsim.scenarios.scenario import load_scenario
from hdsim.units import arcmin_to_rad, rad_to_arcmin

from drive_file_refusal import refusal

#: the contract's example (contracts §4), verbatim
ZXF = """\
name = "ZXF17-50"
ratio = 50
rated_torque_Nm = 16.0
T1_Nm = 3.9                 # catalog three-segment stiffness curve: any subset
T2_Nm = 12.0
K1_Nm_per_rad = 1.0e4
K2_Nm_per_rad = 1.4e4
K3_Nm_per_rad = 1.6e4
lost_motion_arcmin = 1.0    # optional
hysteresis_loss_arcmin = 1.0
[flexspline]                # optional: the geometry, dotted names as in the model
h_pz = 0.5e-3
"""
ZXF_FIGURES = {"T_N": 16.0, "T1": 3.9, "T2": 12.0, "K1": 1.0e4, "K2": 1.4e4, "K3": 1.6e4,
               "lost_motion_arcmin": 1.0, "h_pz": 0.5e-3}


def three_segment_twist(T, T1, T2, K1, K2, K3):
    """The catalog law (HD LLC catalog p. 48), written out here independently [rad]."""
    if T <= T1:
        return T / K1
    if T <= T2:
        return T1 / K1 + (T - T1) / K2
    return T1 / K1 + (T2 - T1) / K2 + (T - T2) / K3


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def copy_of(name: str) -> str:
    """A drive file holding a built-in unit's catalog figures."""
    e = catalog_entry(name)
    return (f'name = "COPY-OF-{name}"\nratio = {e["ratio"]}\nrated_torque_Nm = {e["rated_torque"]}\n'
            f'T1_Nm = {e["T1"]}\nT2_Nm = {e["T2"]}\nK1_Nm_per_rad = {e["K1"]}\n'
            f'K2_Nm_per_rad = {e["K2"]}\nK3_Nm_per_rad = {e["K3"]}\n')


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("drives")
    return {"zxf": write(folder / "zxf17-50.toml", ZXF),
            "copy25": write(folder / "copy25.toml", copy_of("CSG-25-100"))}


@pytest.fixture(scope="module")
def zxf_stiffness_run(files):
    """The ±T_N stiffness test of the ZXF17-50 file's elastic path (no dead zone, no slip)."""
    return run_scenario(load_unit(files["zxf"]).without("friction", "backlash"), "stiffness")


# ------------------------------------------------------------------- (a) a copy of a catalog unit


def test_a_copy_of_a_catalog_unit_reproduces_its_catalog_stiffness(files):
    e = catalog_entry("CSG-25-100")  # the numbers written into the file
    model = load_unit(files["copy25"])
    assert model.name == "COPY-OF-CSG-25-100"
    assert float(model.base_stiffness) == pytest.approx(e["K1"], rel=1e-9)
    run = run_scenario(model.without("friction", "backlash"), "stiffness")
    for k in ("K1", "K2", "K3"):
        assert run.metric(f"{k}_Nm_per_rad") == pytest.approx(e[k], rel=0.01), k
    expected = rad_to_arcmin(three_segment_twist(e["rated_torque"], e["T1"], e["T2"], e["K1"], e["K2"], e["K3"]))
    assert run.metric("torsion_at_rated_arcmin") == pytest.approx(expected, rel=0.01)
    drive_file = model.provenance["drive_file"]
    assert drive_file["scaled"] == () and drive_file["scaled_from"] == "CSG-25-100"
    assert {k: model.provenance["catalog"][k] for k in ("T1", "T2", "K1", "K2", "K3")} == \
        pytest.approx({k: e[k] for k in ("T1", "T2", "K1", "K2", "K3")}, rel=1e-12)


# ------------------------------------------------------------------- (b) the contract's ZXF17-50


def test_the_contract_example_reproduces_its_datasheet_stiffness(files, zxf_stiffness_run):
    f = ZXF_FIGURES
    model = load_unit(files["zxf"])
    assert model.name == "ZXF17-50" and float(model.drive.ratio) == 50.0
    assert float(model.geometry.h_pz) == f["h_pz"]  # the datasheet's geometry, calibrated at it
    assert float(model.base_stiffness) == pytest.approx(f["K1"], rel=1e-9)
    for k in ("K1", "K2", "K3"):
        assert zxf_stiffness_run.metric(f"{k}_Nm_per_rad") == pytest.approx(f[k], rel=0.03), k
    expected = rad_to_arcmin(three_segment_twist(f["T_N"], f["T1"], f["T2"], f["K1"], f["K2"], f["K3"]))
    assert zxf_stiffness_run.metric("torsion_at_rated_arcmin") == pytest.approx(expected, rel=0.02)
    note = model.provenance["drive_file"]
    assert set(note["given"]) == {"name", "ratio", "rated_torque_Nm", "T1_Nm", "T2_Nm", "K1_Nm_per_rad",
                                  "K2_Nm_per_rad", "K3_Nm_per_rad", "lost_motion_arcmin",
                                  "hysteresis_loss_arcmin", "flexspline.h_pz"}
    # a size-17 gearbox of ratio 50: its rating referred to ratio 100 points at size 17
    assert note["scaled_from"] == "CSG-17-100"


def test_a_run_of_a_drive_file_reads_back_without_the_file(tmp_path):
    path = write(tmp_path / "zxf.toml", ZXF)
    model = load_unit(path).without("friction").with_updates({"flexspline.h_c": np.array([0.6e-3, 0.7e-3])})
    run = run_scenario(model, load_scenario("lost_motion").with_updates({"load.cycles": 1}),
                       samples_per_segment=20)
    saved = run.save(tmp_path / "run.h5")
    path.unlink()  # the run file alone rebuilds the unit
    back = read_run(saved)
    assert back.model.name == "ZXF17-50" and back.model.provenance == model.provenance
    assert {s: e.id for s, e in back.model.effects().items()} == {s: e.id for s, e in model.effects().items()}
    for name, value in model.params().items():
        np.testing.assert_array_equal(np.asarray(back.model.params()[name]), np.asarray(value), name)
    np.testing.assert_array_equal(back.metrics["lost_motion_arcmin"], run.metrics["lost_motion_arcmin"])


# ------------------------------------------------------------------- (c) only what is required


def test_a_bare_rating_loads_and_says_what_was_scaled(tmp_path):
    lo, hi = catalog_entry("CSG-17-100"), catalog_entry("CSG-20-100")
    rated = 40.0  # between their ratings, 31 and 52 N·m
    model = load_unit(write(tmp_path / "bare.toml", f'name = "BARE-40"\nratio = 100\nrated_torque_Nm = {rated}\n'))
    note = model.provenance["drive_file"]
    assert note["given"] == ("name", "ratio", "rated_torque_Nm")
    assert set(note["scaled"]) == {"T1_Nm", "T2_Nm", "K1_Nm_per_rad", "K2_Nm_per_rad", "K3_Nm_per_rad"}
    assert note["scaled_from"] in ("CSG-17-100", "CSG-20-100")
    K1 = float(model.base_stiffness)
    assert lo["K1"] < K1 < hi["K1"]
    cat = model.provenance["catalog"]
    assert cat["K1"] <= cat["K2"] <= cat["K3"] and lo["T1"] < cat["T1"] < cat["T2"] < hi["T2"]
    assert cat["rated_torque"] == rated and cat["ratio"] == 100.0


def test_scaled_stiffness_rises_steadily_with_the_rating(tmp_path):
    ratings = [8.0, 10.0, 20.0, 31.0, 35.0, 40.0, 45.0, 52.0, 87.0, 120.0, 178.0, 250.0]
    K1 = []
    for i, rated in enumerate(ratings):
        model = load_unit(write(tmp_path / f"d{i}.toml", f'name = "D{i}"\nratio = 100\nrated_torque_Nm = {rated}\n'))
        K1.append(float(model.base_stiffness))
    assert all(b > a for a, b in zip(K1, K1[1:])), K1
    for name in unit_names():  # at a catalog rating the catalog stiffness comes back
        e = catalog_entry(name)
        assert K1[ratings.index(e["rated_torque"])] == pytest.approx(e["K1"], rel=1e-9), name


def test_a_low_ratio_rating_points_at_the_size_that_carries_it(tmp_path):
    # HD CSG-17-50 is rated 21 N·m (CSG rating table at 2000 rpm), against 31 N·m at ratio 100
    model = load_unit(write(tmp_path / "c17.toml", 'name = "C-17-50"\nratio = 50\nrated_torque_Nm = 21\n'))
    assert model.provenance["drive_file"]["scaled_from"] == "CSG-17-100"
    assert model.provenance["drive_file"]["size"] == pytest.approx(17.0, abs=1.0)


def test_given_figures_are_kept_and_missing_ones_keep_the_law_rising(tmp_path):
    model = load_unit(write(tmp_path / "k1.toml", 'name = "K1ONLY"\nratio = 100\nrated_torque_Nm = 60\n'
                                                   'K1_Nm_per_rad = 2.0e4\nT2_Nm = 30\n'))
    cat, note = model.provenance["catalog"], model.provenance["drive_file"]
    assert float(model.base_stiffness) == pytest.approx(2.0e4, rel=1e-9) and cat["T2"] == 30.0
    assert cat["K1"] < cat["K2"] < cat["K3"] and cat["T1"] < 30.0
    assert set(note["scaled"]) == {"T1_Nm", "K2_Nm_per_rad", "K3_Nm_per_rad"}


def test_flexspline_dimensions_without_stiffness_act_through_the_closed_forms(tmp_path):
    bare = 'name = "G"\nratio = 100\nrated_torque_Nm = 87\n'
    nominal = load_unit(write(tmp_path / "g0.toml", bare))
    thick = load_unit(write(tmp_path / "g1.toml", bare + "[flexspline]\nh_c = 0.8e-3\n"))
    # a thicker cylinder wall is stiffer (thin tube: K = 2π G R³ t / L)
    assert float(thick.geometry.h_c) == 0.8e-3
    assert float(thick.base_stiffness) > float(nominal.base_stiffness)
    assert thick.provenance["catalog"]["K1"] == pytest.approx(float(thick.base_stiffness), rel=1e-12)


# ------------------------------------------------------------------- (d) bad files


BASE = 'name = "X"\nratio = 100\nrated_torque_Nm = 50\n'
BAD = [
    ("malformed", 'name = "X"\nratio = \n', "not valid TOML"),
    ("unknown_key", BASE + "ratoi = 100\n", "did you mean ratio"),
    ("unknown_dimension", BASE + "[flexspline]\nh_zp = 1e-3\n", "unknown flexspline dimension 'h_zp'; did you mean"),
    ("missing", 'name = "X"\nratio = 100\n', "missing key 'rated_torque_Nm'"),
    ("string_number", 'name = "X"\nratio = "100"\nrated_torque_Nm = 50\n', "ratio must be a number"),
    ("bool_number", 'name = "X"\nratio = true\nrated_torque_Nm = 50\n', "ratio must be a number"),
    ("name_type", 'name = 5\nratio = 100\nrated_torque_Nm = 50\n', "name must be a non-empty one-line string"),
    ("zero", 'name = "X"\nratio = 100\nrated_torque_Nm = 0\n', "rated_torque_Nm must be a positive finite"),
    ("negative", BASE + "K1_Nm_per_rad = -1e4\n", "K1_Nm_per_rad must be a positive finite"),
    ("infinite", BASE + "K3_Nm_per_rad = inf\n", "K3_Nm_per_rad must be a positive finite"),
    ("nan", BASE + "lost_motion_arcmin = nan\n", "lost_motion_arcmin must be a positive finite"),
    ("negative_dimension", BASE + "[flexspline]\nh_pz = -1e-3\n", "flexspline.h_pz must be a positive"),
    ("T1_above_T2", BASE + "T1_Nm = 20\nT2_Nm = 10\n", "T1_Nm = 20 must be below T2_Nm = 10"),
    ("K1_above_K2", BASE + "K1_Nm_per_rad = 2e4\nK2_Nm_per_rad = 1e4\n", "K1_Nm_per_rad = 20000 exceeds"),
    ("K2_above_K3", BASE + "K2_Nm_per_rad = 3e4\nK3_Nm_per_rad = 2e4\n", "K2_Nm_per_rad = 30000 exceeds"),
    ("lost_motion_too_small", BASE + "K1_Nm_per_rad = 1e4\nlost_motion_arcmin = 0.1\n", "below the elastic span"),
    ("impossible_geometry", BASE + "[flexspline]\nh_p = 5e-3\n", "flexspline geometry"),
    ("fit_file", 'format = "hdsim-fit-1"\nunit = "CSG-25-100"\n', "an hdsim fit file"),
    ("too_small", 'name = "X"\nratio = 100\nrated_torque_Nm = 1e-3\n', "outside the sizes"),
]


@pytest.mark.parametrize("text, fragment", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_drive_files_are_refused_with_one_line_naming_the_file(tmp_path, text, fragment):
    message = refusal(tmp_path, text)  # one line, naming the file
    assert fragment in message, message


def test_a_missing_drive_file_is_one_line(tmp_path):
    with pytest.raises(InputError, match="drive file not found"):
        load_unit(str(tmp_path / "absent.toml"))


def test_the_cli_refuses_a_bad_drive_file_with_exit_2(tmp_path, cli):
    path = write(tmp_path / "bad.toml", BASE + "K1_Nm_per_rad = 2e4\nK2_Nm_per_rad = 1e4\n")
    code, out, err = cli("simulate", "lost_motion", "--unit", path, "--json", cwd=tmp_path)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and "bad.toml" in err
    assert not (tmp_path / "hdsim-out").exists()


# ------------------------------------------------------------------- (e) the command line


def test_cli_simulate_with_a_drive_file_meets_its_lost_motion(files, tmp_path, cli):
    code, out, err = cli("simulate", "lost_motion", "--unit", files["zxf"], "--no-figures", "--json",
                         cwd=tmp_path)
    assert code == 0, err
    summary = json.loads(out)
    assert summary["unit"] == "ZXF17-50"
    # the datasheet's lost motion, to within the micro-slip's pre-sliding share
    assert summary["metrics"]["lost_motion_arcmin"] == pytest.approx(ZXF_FIGURES["lost_motion_arcmin"], rel=0.02)
    elastic = rad_to_arcmin(0.08 * ZXF_FIGURES["T_N"] / ZXF_FIGURES["K1"])
    assert summary["metrics"]["lost_motion_arcmin"] > elastic


def test_cli_fit_and_diagnose_with_a_drive_file(files, zxf_stiffness_run, tmp_path, cli):
    from hdsim.io.measurement import make_measurement, save_measurement

    every = slice(None, None, 10)  # 121 rows of the simulated ±T_N test
    signals = zxf_stiffness_run.result.signals
    meas = make_measurement("stiffness", zxf_stiffness_run.result.t[every], signals["torque_Nm"][0][every],
                            signals["twist_rad"][0][every], ratio=50, rated_torque=16)
    data = save_measurement(meas, tmp_path / "zxf_stiffness.csv")
    code, out, err = cli("fit", data, "--unit", files["zxf"], "--json", cwd=tmp_path)
    assert code == 0, err
    fitted = json.loads(out)
    assert fitted["unit"] == "ZXF17-50" and fitted["rows"] == len(meas)
    from hdsim.identification.fit import load_fitted  # the fitted file rebuilds the drive, not a built-in

    again = load_fitted(fitted["parameters_file"] if Path(fitted["parameters_file"]).is_absolute()
                        else tmp_path / fitted["parameters_file"])
    assert again.name == "ZXF17-50" and float(again.drive.rated_torque) == 16.0
    code, out, err = cli("diagnose", data, "--unit", files["zxf"], "--json", cwd=tmp_path)
    assert code == 0, err
    found = json.loads(out)
    assert "hardening" in found["added"]  # the datasheet's K1 < K2 < K3 is in the data


def test_cli_sobol_with_a_drive_file_resumes_and_refuses_another_drive(files, tmp_path, cli):
    drive = write(tmp_path / "zxf.toml", ZXF)
    study = tmp_path / "study.h5"
    args = ["sobol", "--unit", drive, "--params", "h_pz,h_c", "--range", "10%", "--output",
            "lost_motion_arcmin", "--n", "8", "--replicates", "2", "--workers", "1", "--out", study, "--json"]
    code, out, err = cli(*args, cwd=tmp_path)
    assert code == 0, err
    first = json.loads(out)
    assert first["params"] == ["h_pz", "h_c"] and first["model"]["unit"] == "ZXF17-50"
    code, out, err = cli(*args, "--resume", cwd=tmp_path)
    assert code == 0, err
    again = json.loads(out)
    assert again["evaluated_now"] == 0 and again["ST"] == first["ST"]
    write(drive, ZXF.replace("K1_Nm_per_rad = 1.0e4", "K1_Nm_per_rad = 1.1e4"))
    code, out, err = cli(*args, "--resume", cwd=tmp_path)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err


def test_units_template_saved_to_a_file_loads(tmp_path, cli):
    code, out, err = cli("units", "--template")
    assert code == 0, err
    model = load_unit(write(tmp_path / "mine.toml", out))
    assert model.name == "MY-DRIVE-25-100"
    for key in ("T1_Nm", "T2_Nm", "K1_Nm_per_rad", "K2_Nm_per_rad", "K3_Nm_per_rad", "lost_motion_arcmin",
                "hysteresis_loss_arcmin", "[flexspline]", "h_pz", "REQUIRED", "N·m/rad", "arcmin"):
        assert key in out, key
    # every optional key, uncommented, still loads
    full = "\n".join(line[2:] if line.startswith("# ") and " = " in line or line == "# [flexspline]" else line
                     for line in out.splitlines())
    model = load_unit(write(tmp_path / "full.toml", full))
    assert model.provenance["drive_file"]["scaled"] == ()
    assert rad_to_arcmin(float(model.backlash.gap)) > 0.0 and model.friction.slip_max == pytest.approx(
        arcmin_to_rad(0.5))
    code, out, _ = cli("units", "--json")
    assert code == 0 and set(json.loads(out)) == {"default", "units"}


@pytest.mark.parametrize("line, key", [
    ("hysteresis_loss_arcmin = 1e6", "hysteresis_loss_arcmin = 1e+06"),
    ("lost_motion_arcmin = 1e6", "lost_motion_arcmin = 1e+06"),
    ("K1_Nm_per_rad = 1e-3", "K1_Nm_per_rad = 0.001"),
])
def test_a_refused_value_names_the_key_of_the_file_that_set_it(line, key, tmp_path):
    """The user wrote the file's key, not the model parameter it sets: a refusal of the
    parameter (friction.slip_max, backlash.gap, calibration.kappa_mesh) names both."""
    path = tmp_path / "d.toml"
    path.write_text(f'name = "X"\nratio = 100\nrated_torque_Nm = 87\n{line}\n')
    with pytest.raises(InputError, match=rf"is outside .*\(set by the file's .*{re.escape(key)}"):
        load_unit(path)
