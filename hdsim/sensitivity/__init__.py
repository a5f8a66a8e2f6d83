"""Generic Sobol' sensitivity analysis for any picklable model ``f(X) -> y``.

Modules: `hdsim.sensitivity.problem` (inputs), `hdsim.sensitivity.design` (sampling
and structure checks), `hdsim.sensitivity.evaluate` (local or any-executor
evaluation by row index), `hdsim.sensitivity.store` (resumable HDF5 studies),
`hdsim.sensitivity.analysis` (indices, both interval kinds, convergence),
`hdsim.sensitivity.checks` (consistency safeguards), `hdsim.sensitivity.functions`
(closed forms with analytic indices), `hdsim.sensitivity.study` (the whole study),
`hdsim.sensitivity.scenario_outputs` (a simulator metric as ``f(X)``),
`hdsim.sensitivity.metric_scenarios` (the built-in scenario of each metric) and
`hdsim.sensitivity.api` (`sobol`: a study of any drive object).
The figures are in `hdsim.plotting.sensitivity`; the method is described in
docs/sensitivity.md.
"""

from hdsim.sensitivity.analysis import analyse, convergence, estimates
from hdsim.sensitivity.api import sobol
from hdsim.sensitivity.checks import consistency_checks
from hdsim.sensitivity.design import DesignError, check_design, fingerprint
from hdsim.sensitivity.evaluate import Evaluation, ModelError, evaluate, open_executor
from hdsim.sensitivity.functions import FUNCTIONS, GFunction, Ishigami, Linear, get_function
from hdsim.sensitivity.problem import Problem, build_problem, uniform
from hdsim.sensitivity.resolved import resolved_indices
from hdsim.sensitivity.study import StudyResult, run_study

__all__ = [
    "analyse", "convergence", "estimates", "consistency_checks", "DesignError",
    "check_design", "fingerprint", "Evaluation", "ModelError", "evaluate", "open_executor",
    "FUNCTIONS", "GFunction", "Ishigami", "Linear", "get_function", "Problem",
    "build_problem", "uniform", "StudyResult", "run_study", "resolved_indices", "sobol",
]
