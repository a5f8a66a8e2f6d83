"""What a Python caller gives is checked as the CLI checks it, with one InputError line.

`HarmonicDrive.with_updates` refuses what is not a number by the parameter's name and the
value's type.
"""

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit

UNIT = load_unit("CSG-25-100")


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
