"""Options of a Sobol' study that cannot do what they say are refused before the study, in the
caller's words (docs/sensitivity.md §1, §7, §11; docs/cli.md, ``hdsim sobol``).

Before: a forced quasi-static evaluator on the running-torque scenario failed every row and
ended in a `ModelError` advising ``resume=True, retry_failed=True`` for a study with no file;
``chunksize=0`` ran with the default chunk; ``retry_failed`` without ``resume`` was dropped
without a word; second order with one parameter ran 2D + 2 rows a point and printed S2 keys.
"""

from __future__ import annotations

import numpy as np
import pytest

import hdsim
from hdsim.errors import InputError
from hdsim.sensitivity import Ishigami, ModelError, run_study

UNIT_STUDY = ["sobol", "--unit", "CSG-25-100", "--params", "h_pz", "--range", "10%",
              "--output", "lost_motion_arcmin", "--n", "16", "--workers", "1"]


def _refusal(call) -> InputError:
    """The error ``call()`` raises: an InputError of the input, not a `ModelError` of rows."""
    with pytest.raises(InputError) as info:
        call()
    assert not isinstance(info.value, ModelError), info.value
    return info.value


def test_a_forced_quasistatic_evaluator_the_scenario_cannot_use_is_refused_before_any_row(cli):
    lines = []
    error = _refusal(lambda: hdsim.sobol("CSG-25-100", ["input_friction.load_coefficient"], "efficiency_percent",
                                         evaluator="quasistatic", n=16, workers=1, log=lines.append))
    assert "quasi-static evaluator does not compute the metric groups" in str(error) and lines == []
    code, out, err = cli("sobol", "--unit", "CSG-25-100", "--params", "input_friction.load_coefficient",
                         "--range", "10%", "--output", "efficiency_percent", "--evaluator", "quasistatic",
                         "--n", "16", "--workers", "1")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert "quasi-static evaluator does not compute" in err and "retry" not in err


def _fails_everywhere(X):
    return np.full(len(X), np.nan)


def test_a_model_failing_everywhere_is_told_to_resume_only_when_the_study_has_a_file(tmp_path):
    problem = Ishigami().problem()
    with pytest.raises(ModelError) as info:
        run_study(_fails_everywhere, problem, 16, workers=1, progress=False, log=lambda line: None)
    assert str(info.value).endswith("fix the model, then rerun") and "resume" not in str(info.value)
    with pytest.raises(ModelError, match=r"then rerun with resume=True, retry_failed=True$"):
        run_study(_fails_everywhere, problem, 16, workers=1, out=tmp_path / "s.h5", progress=False,
                  log=lambda line: None)


@pytest.mark.parametrize("options, message", [
    (dict(chunksize=0), "chunksize must be a whole number, at least 1, got 0"),
    (dict(chunksize=True), "chunksize must be a whole number"),
    (dict(retry_failed=True), "retry_failed=True reruns the failed rows of a study file continued with resume=True"),
])
def test_python_refuses_an_option_that_cannot_mean_what_it_says(options, message):
    # sobol refuses before it builds the drive; run_study, which any model reaches, the same way
    with pytest.raises(InputError, match=message):
        hdsim.sobol("CSG-25-100", ["h_pz", "h_c"], "lost_motion_arcmin", n=16, workers=1, **options)
    with pytest.raises(InputError, match=message):
        run_study(Ishigami(), Ishigami().problem(), 16, workers=1, progress=False, **options)


def test_second_order_needs_two_parameters(cli):
    with pytest.raises(InputError, match=r"second_order=True needs two parameters or more .*only h_pz"):
        hdsim.sobol("CSG-25-100", ["h_pz"], "lost_motion_arcmin", n=16, workers=1, second_order=True)
    code, out, err = cli(*UNIT_STUDY, "--second-order")
    assert code == 2 and out == "" and "--second-order needs two parameters or more" in err, err


def test_the_command_line_refuses_retry_failed_without_resume(cli, tmp_path):
    code, out, err = cli(*UNIT_STUDY, "--retry-failed", "--out", tmp_path / "s.h5")
    assert code == 2 and out == "" and "--retry-failed reruns the failed rows" in err and "add --resume" in err, err
    assert list(tmp_path.iterdir()) == []
