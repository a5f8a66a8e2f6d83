"""A study says why its rows failed: the simulator's refused geometry or solver failure is
the row's failure message (it had been "non-finite output (nan)" for both), counted per
reason in the JSON and shown by the command (docs/sensitivity.md §6). Hand-built rows; no
row here reaches the solver."""

from __future__ import annotations

import numpy as np

from hdsim.errors import SolverError
from hdsim.sensitivity import scenario_outputs
from hdsim.sensitivity.evaluate import run_chunk
from hdsim.sensitivity.problem import uniform
from hdsim.sensitivity.study import run_study

UNDERCUT = ("flexspline.h_p", "flexspline.h_pz")


def test_a_refused_geometry_is_the_rows_failure_message():
    metric = scenario_outputs.ScenarioMetric("CSG-25-100", UNDERCUT, "lost_motion_arcmin", "lost_motion")
    y, _, errors, _ = run_chunk(metric, np.array([[2e-3, 1e-3], [3e-3, 1e-3]]))
    assert np.isnan(y).all() and sorted(errors) == [0, 1]
    assert errors[0] == ("refused: flexspline geometry: undercut depth h_p = 2 mm must be less than the "
                         "thickness under the teeth h_pz = 1 mm")  # the row's values, not "(sample 0)"
    assert errors[1].startswith("refused: flexspline geometry: undercut depth h_p = 3 mm")


def test_a_solver_failure_is_the_failing_rows_message_and_its_neighbours_keep_their_values(monkeypatch):
    """The chunk is halved down to the row the solver cannot run; the message is the solver's."""

    class Run:
        def __init__(self, n):
            self.metrics = {"lost_motion_arcmin": np.arange(n, dtype=float)}

    def study_run(model, scenario, evaluator):
        h_p = np.atleast_1d(model.geometry.h_p)
        if np.any(h_p > 0.5e-3):
            raise SolverError("solve_ivp: step size below the minimum at t = 0.3 s")
        return Run(h_p.size)

    monkeypatch.setattr(scenario_outputs, "_study_run", study_run)
    metric = scenario_outputs.ScenarioMetric("CSG-25-100", UNDERCUT, "lost_motion_arcmin", "lost_motion")
    X = np.array([[0.3e-3, 1e-3], [0.6e-3, 1e-3], [0.3e-3, 1e-3], [0.3e-3, 1e-3]])
    y, _, errors, _ = run_chunk(metric, X)
    assert errors == {1: "solver failed: solve_ivp: step size below the minimum at t = 0.3 s"}
    assert np.isfinite(y[[0, 2, 3]]).all()


class Linear:
    """a + b, NaN where a > 0.9; ``explained`` says why when ``says`` (module level: pickles)."""

    def __init__(self, says: bool):
        self.says = says

    def __call__(self, X):
        X = np.asarray(X)
        return np.where(X[:, 0] > 0.9, np.nan, X[:, 0] + X[:, 1])

    def explained(self, X):
        y = self(X)
        return y, ({int(i): "refused: a above 0.9" for i in np.flatnonzero(np.isnan(y))} if self.says else {})


def test_the_reasons_reach_the_json_and_the_table_and_leave_every_index_as_it_was(capsys):
    from hdsim.cli.sobol import _print_table

    problem = uniform(("a", "b"), ((0.0, 1.0), (0.0, 1.0)))
    said, silent = (run_study(Linear(says), problem, 16, workers=1, progress=False, log=lambda line: None)
                    for says in (True, False))
    for key in ("S1", "ST", "S1_conf_replicates", "ST_conf_replicates"):
        np.testing.assert_array_equal(said.analysis[key], silent.analysis[key])
    summary = said.to_json("y")
    failed = [f["row"] for f in summary["failures"]]
    assert failed and summary["failure_reasons"] == [
        {"reason": "refused: a above 0.9", "rows": len(failed), "first_row": failed[0]}]
    assert silent.to_json("y")["failure_reasons"][0]["reason"] == "non-finite output (nan)"  # a model that says nothing
    _print_table(summary)
    assert (f"failed rows: {len(failed)}, blocks dropped: {summary['blocks_dropped']}; first (sample {failed[0]}): "
            "refused: a above 0.9") in capsys.readouterr().out.splitlines()


def test_refusals_that_differ_only_in_the_rows_values_are_one_reason():
    from hdsim.sensitivity.study import failure_reasons

    failures = [{"row": 2, "message": "refused: undercut depth h_p = 2 mm must be less than h_pz = 1 mm"},
                {"row": 5, "message": "refused: undercut depth h_p = 3.5 mm must be less than h_pz = 1.2e-3 mm"},
                {"row": 9, "message": "solver failed: step size below the minimum at t = 0.3 s"},
                {"row": 11, "message": "refused: hardening.e3 = 0.75 is outside [1, 100]"},
                {"row": 12, "message": "refused: hardening.e2 = 0.5 is outside [1, 100]"},
                {"row": 14, "message": "refused: hardening.e3 = -2 is outside [1, 100]"}]
    assert failure_reasons(failures) == [  # the digit of a name is no number of the row's
        {"reason": failures[0]["message"], "rows": 2, "first_row": 2},
        {"reason": failures[2]["message"], "rows": 1, "first_row": 9},
        {"reason": failures[3]["message"], "rows": 2, "first_row": 11},
        {"reason": failures[4]["message"], "rows": 1, "first_row": 12}]
