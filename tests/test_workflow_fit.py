"""`hdsim.fit` from Python is the workflow `hdsim fit` formats: the same checks, the same
refusal of a record that is not the test it claims, the same plausibility warnings.

Before, the Python call fitted whatever it was given: an 80° free-turning record labelled
``stiffness``, which the command refuses, came back as a drive of 3163 N·m/rad.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hdsim
from hdsim.errors import InputError

EXAMPLE = Path(__file__).parent / "data" / "stiffness_example.csv"


def _turning_freely(tmp_path) -> Path:
    """The example record with its angle spread over 80°: an output turning, not a locked twist."""
    lines = EXAMPLE.read_text().splitlines()
    angle = np.array([float(line.split(",")[2]) for line in lines[3:]])
    spread = np.radians(80.0) * (angle - angle.min()) / np.ptp(angle)
    rows = [",".join(line.split(",")[:2] + [repr(float(a))]) for line, a in zip(lines[3:], spread)]
    path = tmp_path / "turning.csv"
    path.write_text("\n".join(lines[:3] + rows) + "\n")
    return path


def test_a_record_that_is_not_its_test_is_refused_from_python_as_on_the_command_line(tmp_path, cli):
    path = _turning_freely(tmp_path)
    code, _, err = cli("fit", str(path), cwd=tmp_path)
    assert code == 2 and "this is not a stiffness test" in err
    with pytest.raises(InputError, match="this is not a stiffness test") as info:
        hdsim.fit(hdsim.load_measurement(path))
    assert str(info.value).split(": ", 1)[1] in err  # the same sentence


def test_the_checks_of_a_fit_are_the_ones_the_command_prints(tmp_path, cli):
    code, out, err = cli("fit", str(EXAMPLE), "--effects", "friction", "--json", "--out", str(tmp_path / "f.toml"),
                         cwd=tmp_path)
    assert code == 0, err
    printed = json.loads(out)
    result = hdsim.fit(str(EXAMPLE), "friction")  # a path is read as load_measurement reads it
    assert result.checks == printed["checks"] and dict(result.data) == printed["data"]
    assert {c["check"] for c in result.checks} >= {"twist_span", "torque_noise", "reversals"}


@pytest.mark.parametrize("given", [None, 3.0, np.zeros(5)])
def test_what_is_not_a_record_is_refused_in_one_line(given):
    for call in (hdsim.fit, hdsim.diagnose):
        with pytest.raises(InputError, match=r"expected a measurement \(hdsim.load_measurement\(path\)\) or a file"):
            call(given)
