"""`.report(path)` of a diagnosis (a `hdsim.diagnose` result, a wrong test, the engine's own
`Diagnosis`) refuses a path that is a file in one line of the library's words, as
``hdsim diagnose --report FILE`` does in the command's (exit 2).

Before, Python raised a raw FileExistsError from deep in the report writer.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hdsim
from hdsim.errors import InputError
from hdsim.io.measurement import make_measurement

EXAMPLE = Path(__file__).parent / "data" / "stiffness_example.csv"


def _results():
    bench = hdsim.diagnose(hdsim.load_measurement(EXAMPLE), "friction", max_rounds=0)
    t = np.arange(0.0, 1.0, 1e-3)  # a "sweep" that never turns: the wrong test
    wrong = hdsim.diagnose(make_measurement("running_torque", t, np.full(t.size, 0.05), None, wg_angle=0 * t,
                                            ratio=100.0))
    assert wrong.outcome == "wrong_test"
    return {"diagnose": bench, "engine": bench.diagnosis, "wrong_test": wrong}


def test_a_report_into_a_file_is_one_input_error(tmp_path, cli):
    target = tmp_path / "notadir.txt"
    target.write_text("x")
    results = _results()
    for name, result in results.items():
        with pytest.raises(InputError, match=r"notadir.txt is a file, not a folder; give a folder for the report"):
            result.report(target)
        assert target.read_text() == "x", name
    page = tmp_path / "rep" / "index.html"
    page.mkdir(parents=True)
    with pytest.raises(InputError, match="index.html is a folder, so the report cannot be written there"):
        results["diagnose"].report(tmp_path / "rep")
    code, _, err = cli("diagnose", EXAMPLE, "--report", target)  # the command says it in its own words
    assert code == 2 and "--report" in err and "is a file, not a folder" in err
