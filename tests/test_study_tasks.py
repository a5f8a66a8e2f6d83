"""How a study cuts its rows into tasks: every local worker gets work, and a task of long
runs stays within its memory bound whatever the size of the design."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from hdsim.model.catalog import load_unit
from hdsim.scenarios.driven import output_samples
from hdsim.scenarios.scenario import load_scenario
from hdsim.sensitivity.evaluate import evaluate
from hdsim.sensitivity.functions import Ishigami
from hdsim.sensitivity.scenario_outputs import BYTES_PER_SAMPLE_AND_ROW, TASK_BYTES, model_function, task_rows


class _Wide:
    """Ishigami with a task size far above the design's."""

    chunksize = 1024

    def __call__(self, X):
        return Ishigami()(X)


def test_a_small_design_reaches_every_local_worker():
    X = np.random.default_rng(0).uniform(-np.pi, np.pi, (10, 3))
    tasks = []
    out = evaluate(_Wide(), X, workers=2, progress=False, on_chunk=lambda labels, *rest: tasks.append(len(labels)))
    assert sorted(tasks) == [5, 5]
    np.testing.assert_array_equal(out.y, Ishigami()(X))


def test_a_driven_study_sends_as_many_rows_as_its_memory_bound_allows():
    unit = load_unit("CSG-25-100")
    contract = load_scenario("kinematic_error")
    samples = output_samples(unit, contract)
    assert samples > 20_000  # 26 s of output at 1 kHz
    rows = task_rows(unit, contract)
    assert rows * BYTES_PER_SAMPLE_AND_ROW * samples <= TASK_BYTES < (rows + 1) * BYTES_PER_SAMPLE_AND_ROW * samples
    assert model_function(unit, ["h_pz"], "transmission_accuracy_arcsec").chunksize == rows
    # a locked-bench test's runs are short: its tasks stay large
    assert model_function(unit, ["h_pz"], "lost_motion_arcmin").chunksize == 1024


def _bytes_per_sample_and_row(evaluator: str) -> float:
    """The growth of a task's peak memory (tracemalloc: numpy's arrays included) per added
    row and output sample, on the contract KE run shortened to 0.02 output turns each way."""
    unit = load_unit("CSG-25-100")
    scenario = load_scenario("kinematic_error").with_updates({"input.output_revolutions": 0.02,
                                                              "input.settle_revolutions": 0.01})
    samples = output_samples(unit, scenario)
    f = model_function(unit, ["h_pz"], "transmission_accuracy_arcsec", scenario=scenario, evaluator=evaluator)
    nominal = float(unit.params()["flexspline.h_pz"])
    f(np.array([[nominal], [nominal]]))  # imports and caches outside the measurement
    peaks = {}
    for rows in (2, 6):
        X = nominal * np.linspace(0.97, 1.03, rows)[:, None]
        tracemalloc.start()
        try:
            assert np.all(np.isfinite(f(X)))
            peaks[rows] = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    return (peaks[6] - peaks[2]) / (4 * samples)


@pytest.mark.parametrize("evaluator", ["quasistatic", pytest.param("dynamic", marks=pytest.mark.slow)])
def test_the_memory_bound_holds_what_a_task_really_allocates(evaluator):
    # measured: ~110 B (quasi-static) and ~220 B (dynamic, solve_ivp's states and dense
    # output) per row and sample; the bound must not be below what a task holds
    measured = _bytes_per_sample_and_row(evaluator)
    assert 0.0 < measured <= BYTES_PER_SAMPLE_AND_ROW
