"""What a Python caller gives is checked as the CLI checks it, with one InputError line.

`run_scenario` takes a unit name or a drive file's path as `hdsim.sobol` does, refuses
values that contradict each other by the model's own check (the one ``--set`` makes), and
`HarmonicDrive.with_updates` refuses what is not a number by the parameter's name and the
value's type.
"""

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit
from hdsim.scenarios.run import run_scenario

from drive_file_refusal import HEAD

UNIT = load_unit("CSG-25-100")


@pytest.mark.parametrize("evaluator", ["quasistatic", "auto"])
def test_a_unit_name_runs_as_its_drive(evaluator):
    """It stopped in an AttributeError ('str' object has no attribute 'batch_size' / 'drive')."""
    by_name = run_scenario("CSG-25-100", "lost_motion", evaluator=evaluator)
    assert by_name.model is UNIT  # load_unit's cached unit
    assert by_name.metric("lost_motion_arcmin") == run_scenario(UNIT, "lost_motion", evaluator=evaluator).metric(
        "lost_motion_arcmin")


def test_a_drive_file_path_runs_as_its_drive(tmp_path):
    path = tmp_path / "zxf.toml"
    path.write_text(HEAD)
    assert run_scenario(path, "lost_motion", evaluator="quasistatic").model.name == "ZXF17-50"


@pytest.mark.parametrize("drive, match", [
    ("CSG-99-100", "unknown unit 'CSG-99-100'"),
    (3.0, "a drive is a HarmonicDrive, a built-in unit name or a drive file's path, got float"),
])
def test_what_is_no_drive_is_one_input_error(drive, match):
    with pytest.raises(InputError, match=match) as err:
        run_scenario(drive, "lost_motion", evaluator="quasistatic")
    assert "\n" not in str(err.value)


def test_a_first_breakpoint_above_the_second_is_refused_as_the_cli_refuses_it():
    """with_updates builds it (a fit's trial models pass through such values); the run had
    given K1…K3 of a law whose knees are swapped."""
    drive = UNIT.with_updates({"hardening.T1": 60.0})
    with pytest.raises(InputError, match=r"^hardening\.T1 = 60 must be below hardening\.T2 = 48 N·m \(more"):
        run_scenario(drive, "stiffness", evaluator="quasistatic")


def test_a_batch_is_checked_sample_by_sample():
    """T1 varied against one T2: the check had indexed T2 as if it were an array (IndexError)."""
    drive = UNIT.with_updates({"hardening.T1": np.array([10.0, 60.0])})
    with pytest.raises(InputError, match=r"hardening\.T1 = 60 must be below hardening\.T2 = 48 N·m in sample 1 "):
        run_scenario(drive, "stiffness", evaluator="quasistatic")


@pytest.mark.parametrize("name, value, told", [
    ("flexspline.h_c", "0.6e-3", "str '0.6e-3'"),            # numpy's UFuncTypeError
    ("friction.slip_torque", "3", "str '3'"),                # read as 3.0
    ("flexspline.h_c", ["0.5e-3"], "list holding str '0.5e-3'"),  # read as [0.0005]
    ("flexspline.h_c", [6e-4, None], "list holding NoneType None"),
    ("backlash.gap", True, "bool True"),                     # read as 1 rad
])
def test_a_value_that_is_no_number_is_refused_by_name_and_type(name, value, told):
    with pytest.raises(InputError) as err:
        UNIT.with_updates({name: value})
    assert str(err.value) == f"{name} must be a number or a 1-D array of numbers, got {told}"


@pytest.mark.parametrize("value", [6e-4, np.float32(6e-4), [5e-4, 6e-4], np.array([5e-4, 6e-4])])
def test_numbers_and_arrays_of_numbers_still_build(value):
    assert np.allclose(UNIT.with_updates({"flexspline.h_c": value}).geometry.h_c, value)


@pytest.mark.parametrize("call, words", [
    (lambda d: d.without("frction"), "unknown effect family 'frction'; did you mean friction"),
    (lambda d: d.with_updates([("flexspline.h_c", 1e-3)]), "updates are a dict of dotted names and values"),
    (lambda d: __import__("hdsim").run_scenario(d, 42), "a scenario is a Scenario, a built-in scenario name"),
])
def test_a_call_given_the_wrong_kind_of_thing_is_one_input_error(call, words):
    """A KeyError, an AttributeError and a TypeError (an internal error to the user) had come
    from a misspelt family for without(), a list for with_updates() and a number for a scenario."""
    from hdsim.errors import InputError
    from hdsim.model.catalog import load_unit

    with pytest.raises(InputError, match=words):
        call(load_unit("CSG-25-100"))


def test_a_drive_file_given_as_the_scenario_is_named_as_one(tmp_path):
    """It said "unknown key 'ratio'; did you mean description?", pointing the wrong way."""
    import hdsim
    from hdsim.errors import InputError
    from hdsim.model.catalog import load_unit

    path = tmp_path / "zxf17-50.toml"
    path.write_text(HEAD)
    with pytest.raises(InputError, match="a drive or fit file, not a scenario: give it as the unit"):
        hdsim.run_scenario(load_unit("CSG-25-100"), path)


def test_a_quasi_static_refusal_speaks_in_python_words_from_python():
    """It named the command line's option (--evaluator dynamic or auto) to a Python caller; the
    command line still says its option (hdsim.cli translates it)."""
    import hdsim
    from hdsim.errors import InputError
    from hdsim.model.catalog import load_unit

    with pytest.raises(InputError, match=r"\(evaluator='dynamic' or 'auto'\)") as caught:
        hdsim.run_scenario(load_unit("CSG-25-100"), "reversal", evaluator="quasistatic")
    assert "--evaluator" not in str(caught.value)


def test_a_dotted_name_given_without_its_prefix_is_suggested_with_it():
    """`--set h_c=1e-3` listed every parameter the drive has instead of flexspline.h_c."""
    from hdsim.errors import unknown_name

    message = str(unknown_name("parameter", "h_c", ["flexspline.h_c", "flexspline.h_pz", "friction.slip_max"]))
    assert message == "unknown parameter 'h_c'; did you mean flexspline.h_c?"
