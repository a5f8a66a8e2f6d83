"""Measurement files: round trips, units, column maps, HDF5, and every refusal of the contract."""

from __future__ import annotations

import dataclasses
import math
import os
from pathlib import Path

import h5py
import numpy as np
import pytest

import truth
from hdsim.errors import InputError
from hdsim.io.measurement import (
    Measurement,
    load_measurement,
    make_measurement,
    parse_column_map,
    save_measurement,
)

DATA = Path(__file__).parent / "data"
#: one unit of each angle suffix in rad, written out independently of hdsim.units:
#: π/180, π/(180·60), π/(180·3600) to 16 digits
RAD_PER = {"rad": 1.0, "deg": 0.017453292519943295, "arcmin": 2.908882086657216e-04,
           "arcsec": 4.84813681109536e-06, "rev": 6.283185307179586}


def stiffness_rows(n=12, offset=0.0):
    t = np.arange(n) * 0.01
    torque = np.linspace(0.0, 20.0, n)
    angle = offset + torque / 3.1e4
    return t, torque, angle


def fmt(*values) -> str:
    """One CSV row with the exact (shortest round-trip) text of each number."""
    return ",".join(repr(float(v)) for v in values)


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def csv_text(header="time_s,torque_Nm,angle_rad", rows=None, meta="# test: stiffness\n"):
    if rows is None:
        t, torque, angle = stiffness_rows()
        rows = [fmt(a, b, c) for a, b, c in zip(t, torque, angle)]
    return meta + header + "\n" + "\n".join(rows) + "\n"


@pytest.fixture
def stiff_meas(truth_stiffness):
    cols, _ = truth_stiffness
    return make_measurement("stiffness", cols["time_s"], cols["torque_Nm"], cols["angle_rad"],
                            rated_torque=87.0, meta={"bench": "B7"})


@pytest.fixture
def ke_meas(truth_ke):
    cols, _ = truth_ke
    return make_measurement("kinematic_error", cols["time_s"], cols["torque_Nm"],
                            cols["output_angle_rad"], wg_angle=cols["wg_angle_rad"],
                            ratio=100.0)


# --------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("suffix", [".csv", ".h5"])
def test_save_load_round_trip_is_exact(tmp_path, stiff_meas, suffix):
    path = save_measurement(stiff_meas, tmp_path / f"m{suffix}")
    back = load_measurement(path)
    assert back.test == "stiffness" and len(back) == 300
    for name in ("time", "torque", "angle"):
        np.testing.assert_array_equal(getattr(back, name), getattr(stiff_meas, name))
    assert back.rated_torque == 87.0 and back.ratio is None and back.wg_angle is None
    assert back.meta["bench"] == "B7" and back.source == str(path)


@pytest.mark.parametrize("suffix", [".csv", ".hdf5"])
def test_ke_round_trip_and_kinematic_error(tmp_path, ke_meas, suffix):
    back = load_measurement(save_measurement(ke_meas, tmp_path / f"ke{suffix}"))
    assert back.test == "kinematic_error" and back.ratio == 100.0 and len(back) == 3000
    np.testing.assert_array_equal(back.wg_angle, ke_meas.wg_angle)
    np.testing.assert_array_equal(back.output_angle, ke_meas.angle)
    np.testing.assert_allclose(back.kinematic_error, back.angle - back.wg_angle / 100.0)
    assert list(back.columns()) == ["time_s", "wg_angle_rad", "output_angle_rad", "torque_Nm"]


def test_save_is_atomic_and_leaves_no_temporaries(tmp_path, stiff_meas):
    save_measurement(stiff_meas, tmp_path / "sub" / "m.csv")
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["m.csv"]


def test_saved_csv_has_contract_layout(tmp_path, stiff_meas):
    text = save_measurement(stiff_meas, tmp_path / "m.csv").read_text().splitlines()
    assert text[0] == "# test: stiffness"
    assert text[1] == "# rated_torque_Nm: 87.0"
    assert "time_s,torque_Nm,angle_rad" in text


def test_measurement_is_frozen_and_read_only(stiff_meas):
    with pytest.raises(dataclasses.FrozenInstanceError):
        stiff_meas.test = "kinematic_error"
    with pytest.raises(ValueError):
        stiff_meas.angle[0] = 1.0
    assert stiff_meas.kinematic_error is None and stiff_meas.output_angle is None
    assert "rows=300" in repr(stiff_meas)


def test_negative_ratio_kinematic_error(tmp_path):
    t = np.arange(12) * 0.1
    wg = -100.0 * 0.05 * t
    out = 0.05 * t + 1e-5
    meas = make_measurement("kinematic_error", t, 0 * t, out, wg_angle=wg, ratio=-100)
    np.testing.assert_allclose(meas.kinematic_error, 1e-5, atol=1e-15)


# --------------------------------------------------------------------------- units, maps, offset


@pytest.mark.parametrize("unit", ["rad", "deg", "arcmin", "arcsec"])
def test_angle_suffix_is_converted_to_rad(tmp_path, unit):
    t, torque, angle = stiffness_rows()
    in_unit = angle / RAD_PER[unit]
    rows = [fmt(a, b, c) for a, b, c in zip(t, torque, in_unit)]
    meas = load_measurement(write(tmp_path / "m.csv", csv_text(f"time_s,torque_Nm,angle_{unit}",
                                                                rows)))
    np.testing.assert_allclose(meas.angle, angle, rtol=1e-14, atol=0)


def test_unit_factors():
    from hdsim.io.measurement import ANGLE_UNITS

    assert set(ANGLE_UNITS) == set(RAD_PER)
    for unit, rad in RAD_PER.items():
        assert ANGLE_UNITS[unit] == pytest.approx(rad, rel=1e-15), unit
    assert 1 / RAD_PER["arcmin"] == pytest.approx(3437.7467707849, rel=1e-12)  # arcmin per rad
    assert RAD_PER["deg"] == pytest.approx(math.pi / 180, rel=1e-15)
    assert RAD_PER["arcsec"] * 648000 == pytest.approx(math.pi, rel=1e-15)


def test_ke_columns_in_mixed_units(tmp_path):
    t = np.arange(12) * 0.1
    wg = 100.0 * 0.2 * t
    out = 0.2 * t + 3e-4
    rows = [fmt(a, math.degrees(b), math.degrees(c) * 3600.0, -5.0)
            for a, b, c in zip(t, wg, out)]
    text = csv_text("time_s,wg_angle_deg,output_angle_arcsec,torque_Nm", rows,
                    "# test: kinematic_error\n# ratio: 100\n")
    meas = load_measurement(write(tmp_path / "ke.csv", text))
    np.testing.assert_allclose(meas.wg_angle, wg, rtol=1e-14)
    np.testing.assert_allclose(meas.kinematic_error, 3e-4, atol=1e-12)


def test_large_offset_is_preserved_exactly(tmp_path):
    offset = 2.718281828459045
    t, torque, angle = stiffness_rows(offset=offset)
    meas = load_measurement(write(tmp_path / "m.csv", csv_text(
        rows=[fmt(a, b, c) for a, b, c in zip(t, torque, angle)])))
    np.testing.assert_array_equal(meas.angle, angle)
    assert meas.angle[0] == offset


def test_column_map_dict_and_cli_form(tmp_path):
    t, torque, angle = stiffness_rows()
    rows = [fmt(a, b, math.degrees(c), 21.5) for a, b, c in zip(t, torque, angle)]
    path = write(tmp_path / "bench.csv", csv_text("t,T_out,pos,temp_C", rows))
    text_map = "time_s=t,torque_Nm=T_out,angle_deg=pos"
    assert parse_column_map(text_map) == {"time_s": "t", "torque_Nm": "T_out",
                                          "angle_deg": "pos"}
    meas = load_measurement(path, columns=parse_column_map(text_map))
    np.testing.assert_allclose(meas.angle, angle, rtol=1e-14)
    np.testing.assert_array_equal(meas.torque, torque)


def test_column_map_may_cover_only_some_columns(tmp_path):
    t, torque, angle = stiffness_rows()
    rows = [fmt(a, b, c) for a, b, c in zip(t, torque, angle)]
    path = write(tmp_path / "bench.csv", csv_text("t,torque_Nm,angle_rad", rows))
    meas = load_measurement(path, columns={"time_s": "t"})
    np.testing.assert_array_equal(meas.time, t)


def test_example_files_in_tests_data():
    stiff = load_measurement(DATA / "stiffness_example.csv")
    assert stiff.test == "stiffness" and len(stiff) >= 100 and stiff.rated_torque == 87.0
    h5 = load_measurement(DATA / "stiffness_example.h5")
    np.testing.assert_array_equal(h5.angle, stiff.angle)
    ke = load_measurement(DATA / "ke_example.csv")
    assert ke.test == "kinematic_error" and ke.ratio == 100.0
    bench = load_measurement(DATA / "foreign_bench.csv",
                             columns=parse_column_map("time_s=t,torque_Nm=T_out,angle_deg=pos"))
    np.testing.assert_allclose(bench.angle, stiff.angle[: len(bench)], rtol=1e-13)


def test_hdf5_with_column_map_and_groups(tmp_path):
    t, torque, angle = stiffness_rows()
    path = tmp_path / "bench.h5"
    with h5py.File(path, "w") as handle:
        handle.attrs["test"] = b"stiffness"
        handle.attrs["ratio"] = np.float64(100.0)
        handle.create_dataset("t", data=t)
        handle.create_dataset("T_out", data=torque)
        handle.create_dataset("pos_arcmin", data=np.degrees(angle) * 60.0)
        handle.create_group("provenance")
    meas = load_measurement(path, columns={"time_s": "t", "torque_Nm": "T_out",
                                           "angle_arcmin": "pos_arcmin"})
    np.testing.assert_allclose(meas.angle, angle, rtol=1e-14)
    assert meas.ratio == 100.0 and meas.meta["test"] == "stiffness"


def test_blank_lines_bom_crlf_and_spacer_comment_are_tolerated(tmp_path):
    body = csv_text(meta="#\n# test: stiffness\n# note: a: b\n\n").replace("\n", "\r\n")
    path = tmp_path / "m.csv"
    path.write_bytes(b"\xef\xbb\xbf" + body.encode() + b"\r\n\r\n")
    meas = load_measurement(path)
    assert len(meas) == 12 and meas.meta["note"] == "a: b"


def test_twenty_thousand_rows_load_exactly(tmp_path):
    """A long record loads whole and exact (its speed is a benchmark's business)."""
    cols, tr = truth.make_stiffness_data((), (), seed=0, n_rows=20000, quarter_s=(1.0,))
    path = truth.write_csv(tmp_path / "big.csv", cols, tr["meta"])
    meas = load_measurement(path)
    assert len(meas) == 20000
    np.testing.assert_array_equal(meas.angle, cols["angle_rad"])
    np.testing.assert_array_equal(meas.time, cols["time_s"])


# --------------------------------------------------------------------------- refusals


def good_rows(n=12):
    t, torque, angle = stiffness_rows(n)
    return [fmt(a, b, c) for a, b, c in zip(t, torque, angle)]


def with_row(i, row, n=12):
    rows = good_rows(n)
    rows[i] = row
    return rows


# (name, file text, substrings the one-line message must hold besides the file name)
BAD_CSV = [
    ("missing_column", csv_text("time_s,torque_Nm,angle_x",
                                [r.rsplit(",", 1)[0] + ",0" for r in good_rows()]),
     ["unknown column 'angle_x'"]),
    ("missing_angle", csv_text("time_s,torque_Nm", [r.rsplit(",", 1)[0] for r in good_rows()]),
     ["missing column 'angle_rad'", "time_s, torque_Nm, angle_rad"]),
    ("unknown_column", csv_text("time_s,torque_Nm,angle_rad,temp_C",
                                [r + ",20" for r in good_rows()]),
     ["unknown column 'temp_C'", "time_s, torque_Nm, angle_rad"]),
    ("other_test_column", csv_text("time_s,torque_Nm,angle_rad,wg_angle_rad",
                                   [r + ",0" for r in good_rows()]),
     ["unknown column 'wg_angle_rad'", "test"]),
    ("duplicate_angle", csv_text("time_s,torque_Nm,angle_rad,angle_deg",
                                 [r + ",0" for r in good_rows()]),
     ["'angle_rad'", "'angle_deg'", "both give angle_rad"]),
    ("duplicate_header", csv_text("time_s,torque_Nm,torque_Nm", good_rows()),
     ["column 'torque_Nm' appears twice"]),
    ("non_numeric", csv_text(rows=with_row(4, "0.04,abc,0.0")),
     ["line 7", "column 'torque_Nm'", "'abc'", "expected a number"]),
    ("empty_cell", csv_text(rows=with_row(2, "0.02,,0.0")),
     ["line 5", "column 'torque_Nm'", "expected a number"]),
    ("nan", csv_text(rows=with_row(7, "0.07,nan,0.0")),
     ["line 10", "column 'torque_Nm'", "finite"]),
    ("inf", csv_text(rows=with_row(3, "0.03,1.0,-inf")),
     ["line 6", "column 'angle_rad'", "finite"]),
    ("time_not_increasing", csv_text(rows=with_row(5, "0.04,1.0,0.0")),
     ["line 8", "column 'time_s'", "increase strictly"]),
    ("time_repeated", csv_text(rows=with_row(11, "0.10,1.0,0.0")),
     ["line 14", "time_s", "increase strictly"]),
    ("too_few_rows", csv_text(rows=good_rows(9)), ["9 data rows", "at least 10"]),
    ("no_rows", csv_text(rows=[]), ["no data rows", "at least 10"]),
    ("short_row", csv_text(rows=with_row(0, "0.0,0.0")), ["line 3", "2 cells", "expected 3"]),
    ("long_row", csv_text(rows=with_row(1, "0.01,0.0,0.0,")), ["line 4", "4 cells"]),
    ("missing_test", csv_text(meta="# ratio: 100\n"), ["'# test:'", "stiffness"]),
    ("unknown_test", csv_text(meta="# test: stiffnes\n"),
     ["unknown test 'stiffnes'", "did you mean stiffness", "kinematic_error"]),
    ("duplicate_key", csv_text(meta="# test: stiffness\n# test: stiffness\n"),
     ["line 2", "given twice"]),
    ("hash_after_header", csv_text(rows=with_row(6, "# test: x")),
     ["line 9", "'#' line after the header"]),
    ("bad_ratio", csv_text(meta="# test: stiffness\n# ratio: hundred\n"),
     ["line 2: '# ratio:'", "'hundred'", "non-zero number"]),
    ("zero_ratio", csv_text(meta="# test: stiffness\n# ratio: 0\n"), ["'# ratio:'", "non-zero"]),
    ("bad_rated", csv_text(meta="# test: stiffness\n# rated_torque_Nm: -3\n"),
     ["rated_torque_Nm", "positive"]),
    ("semicolons", csv_text("time_s;torque_Nm;angle_rad", [r.replace(",", ";")
                                                           for r in good_rows()]),
     ["unknown column", "separator must be a comma"]),
    ("empty", "", ["empty"]),
    ("only_comments", "# test: stiffness\n", ["no header row"]),
]

BAD_KE = [
    ("ke_missing_ratio", "# test: kinematic_error\n", ["no '# ratio:'", "kinematic_error"]),
    ("ke_missing_wg", "# test: kinematic_error\n# ratio: 100\n",
     ["missing column 'wg_angle_rad'"]),
]


@pytest.mark.parametrize("name,text,parts", BAD_CSV, ids=[c[0] for c in BAD_CSV])
def test_bad_csv_is_refused_with_one_line(tmp_path, name, text, parts):
    path = write(tmp_path / f"{name}.csv", text)
    before = sorted(os.listdir(tmp_path))
    with pytest.raises(InputError) as info:
        load_measurement(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(str(path))
    for part in parts:
        assert part in message, message
    assert sorted(os.listdir(tmp_path)) == before  # nothing written


@pytest.mark.parametrize("name,meta,parts", BAD_KE, ids=[c[0] for c in BAD_KE])
def test_bad_ke_file_is_refused(tmp_path, name, meta, parts):
    rows = [fmt(i * 0.1, i * 0.01, 0.0) for i in range(12)]
    path = write(tmp_path / f"{name}.csv",
                 csv_text("time_s,output_angle_rad,torque_Nm", rows, meta))
    with pytest.raises(InputError) as info:
        load_measurement(path)
    assert str(path) in str(info.value)
    for part in parts:
        assert part in str(info.value), str(info.value)


def test_nonexistent_file_and_directory(tmp_path):
    with pytest.raises(InputError, match="nope.csv: no such file"):
        load_measurement(tmp_path / "nope.csv")
    with pytest.raises(InputError, match="is a directory"):
        load_measurement(tmp_path)


def test_binary_file_is_refused(tmp_path):
    path = tmp_path / "blob.csv"
    path.write_bytes(b"\x00\xff\xfe" * 20)
    with pytest.raises(InputError, match="blob.csv: not a text CSV"):
        load_measurement(path)


def test_unreadable_hdf5(tmp_path):
    path = write(tmp_path / "broken.h5", csv_text())
    with pytest.raises(InputError, match="broken.h5: cannot read as HDF5"):
        load_measurement(path)
    empty = tmp_path / "empty.h5"
    empty.write_bytes(b"")
    with pytest.raises(InputError, match="empty.h5: the file is empty"):
        load_measurement(empty)


def make_h5(path, test="stiffness", **columns):
    with h5py.File(path, "w") as handle:
        if test is not None:
            handle.attrs["test"] = test
        for name, values in columns.items():
            handle.create_dataset(name, data=values)
    return path


@pytest.mark.parametrize(
    "attrs_test,columns,parts",
    [
        (None, {}, ["'# test:'"]),
        ("wobble", {}, ["unknown test 'wobble'"]),
        ("stiffness", {"time_s": np.arange(12.0), "torque_Nm": np.zeros(12)},
         ["missing dataset 'angle_rad'"]),
        ("stiffness", {"time_s": np.arange(12.0), "torque_Nm": np.zeros(12),
                       "angle_rad": np.zeros(12), "extra": np.zeros(12)},
         ["unknown dataset 'extra'"]),
        ("stiffness", {"time_s": np.arange(12.0), "torque_Nm": np.r_[np.zeros(11), np.nan],
                       "angle_rad": np.zeros(12)}, ["row 12", "dataset 'torque_Nm'", "finite"]),
        ("stiffness", {"time_s": np.r_[0.0, 2.0, 1.0, np.arange(3.0, 12.0)],
                       "torque_Nm": np.zeros(12), "angle_rad": np.zeros(12)},
         ["row 3", "dataset 'time_s'", "increase strictly"]),
        ("stiffness", {"time_s": np.arange(5.0), "torque_Nm": np.zeros(5),
                       "angle_rad": np.zeros(5)}, ["5 data rows", "at least 10"]),
        ("stiffness", {"time_s": np.arange(12.0), "torque_Nm": np.zeros(11),
                       "angle_rad": np.zeros(12)}, ["'torque_Nm' has 11 rows"]),
        ("stiffness", {"time_s": np.arange(12.0), "torque_Nm": np.zeros((12, 2)),
                       "angle_rad": np.zeros(12)}, ["'torque_Nm' has shape (12, 2)"]),
        ("stiffness", {"time_s": np.arange(12.0), "torque_Nm": np.array([b"x"] * 12),
                       "angle_rad": np.zeros(12)}, ["'torque_Nm' holds", "expected numbers"]),
    ],
)
def test_bad_hdf5_is_refused(tmp_path, attrs_test, columns, parts):
    path = make_h5(tmp_path / "bad.h5", attrs_test, **columns)
    with pytest.raises(InputError) as info:
        load_measurement(path)
    message = str(info.value)
    assert message.startswith(str(path)) and "\n" not in message
    for part in parts:
        assert part in message, message


@pytest.mark.parametrize(
    "mapping,parts",
    [
        ({"time_s": "t", "torque_Nm": "T_out", "angle_deg": "posn"}, ["'posn'", "not in the file"]),
        ({"time": "t"}, ["unknown canonical column 'time'", "time_s"]),
        ({"time_s": "t", "torque_Nm": "t"}, ["reads file column 't' twice"]),
    ],
)
def test_bad_column_map_is_refused(tmp_path, mapping, parts):
    rows = [fmt(a, b, c, b) for a, b, c in zip(*stiffness_rows())]
    path = write(tmp_path / "bench.csv", csv_text("t,T_out,pos,torque_Nm", rows))
    with pytest.raises(InputError) as info:
        load_measurement(path, columns=mapping)
    for part in parts:
        assert part in str(info.value), str(info.value)


def test_map_colliding_with_a_canonical_column_is_refused(tmp_path):
    rows = [fmt(a, b, c, b) for a, b, c in zip(*stiffness_rows())]
    path = write(tmp_path / "bench.csv", csv_text("time_s,T_out,angle_rad,torque_Nm", rows))
    with pytest.raises(InputError, match="'T_out'.*'torque_Nm'.*both give torque_Nm"):
        load_measurement(path, columns={"torque_Nm": "T_out"})


@pytest.mark.parametrize("text", ["time_s", "time_s=", "=t", "time_s=t,time_s=u", "", "foo=t"])
def test_bad_cli_column_map(text):
    with pytest.raises(InputError, match="--columns"):
        parse_column_map(text)


def test_make_measurement_checks_like_the_loader():
    t, torque, angle = stiffness_rows()
    with pytest.raises(InputError, match="needs the transmission ratio"):
        make_measurement("kinematic_error", t, torque, angle, wg_angle=angle)
    with pytest.raises(InputError, match="missing column 'wg_angle_rad'"):
        make_measurement("kinematic_error", t, torque, angle, ratio=100)
    with pytest.raises(InputError, match="row 3, column 'time_s'"):
        make_measurement("stiffness", np.r_[0.0, 1.0, 1.0, t[3:] + 9], torque, angle)
    with pytest.raises(InputError, match="differ in length"):
        make_measurement("stiffness", t, torque[:-1], angle)
    with pytest.raises(InputError, match="unknown test"):
        make_measurement("lost_motion", t, torque, angle)
    assert isinstance(make_measurement("stiffness", t, torque, angle), Measurement)


def test_save_refuses_meta_that_would_break_the_format(tmp_path, stiff_meas):
    bad = dataclasses.replace(stiff_meas, meta={"note": "two\nlines"})
    with pytest.raises(InputError, match="line break"):
        save_measurement(bad, tmp_path / "m.csv")
    assert not (tmp_path / "m.csv").exists()


def test_a_missing_test_key_names_every_test_kind(tmp_path):
    path = tmp_path / "keyless.csv"
    path.write_text("time_s,torque_Nm,angle_rad\n" + "".join(f"{i},{i},{i}\n" for i in range(12)))
    with pytest.raises(InputError) as err:
        load_measurement(path)
    assert "stiffness, kinematic_error, running_torque or breakaway" in str(err.value)


def test_a_dimensionless_parameter_out_of_range_ends_with_its_range():
    import hdsim

    with pytest.raises(InputError) as err:
        hdsim.load_unit("CSG-25-100").with_updates({"wave_generator.balls": 0})
    assert str(err.value).endswith("is outside [3, 200]")  # it ended in a stray " -"
