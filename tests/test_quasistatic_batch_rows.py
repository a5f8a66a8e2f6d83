"""A quasi-static batch gives each sample its own law: every row equals a single run.

The compiled micro-slip friction (``dahl_slip``, the default unit's) took the first
sample's slip torque and slip range for every row, so a Sobol study of either under the
quasi-static evaluator (which ``auto`` chooses for the lost-motion and kinematic-error
outputs) found them without effect (S1 = ST = 0), and a fit of them could not move.
Every effect parameter of the default unit is checked here, on the stiffness test (the
effect slots) and on the driven kinematic-error run (the friction, whose loop it shows).
"""

from __future__ import annotations

import numpy as np
import pytest

from hdsim.model.catalog import load_unit
from hdsim.scenarios.run import run_scenario

DRIVE = load_unit("CSG-25-100")
EFFECT_PARAMETERS = [name for name in DRIVE.params()
                     if name.split(".")[0] in ("hardening", "backlash", "friction", "damping")]


def _rows_and_singles(name: str, scenario: str):
    """Every metric of ``scenario``: (the batch's rows, the single runs), each (metrics, 2)."""
    values = float(DRIVE.params()[name]) * np.array([0.8, 1.15])
    batch = run_scenario(DRIVE.with_updates({name: values}), scenario, evaluator="quasistatic").metrics
    singles = [run_scenario(DRIVE.with_updates({name: v}), scenario, evaluator="quasistatic").metrics for v in values]
    names = sorted(batch)
    return (np.array([np.asarray(batch[m], dtype=float) for m in names]),
            np.array([[float(np.ravel(one[m])[0]) for one in singles] for m in names]))


@pytest.mark.parametrize("name", EFFECT_PARAMETERS)
def test_a_stiffness_batch_row_is_its_single_run(name):
    batch, singles = _rows_and_singles(name, "stiffness")
    np.testing.assert_allclose(batch, singles, rtol=1e-9)
    # it moves a metric, so a row given another sample's law would show; the damping's split
    # between the spring's two parts is the exception: at the test's slow rate it moves no figure
    moves = np.any(np.abs(singles[:, 1] - singles[:, 0]) > 1e-6 * np.abs(singles[:, 0]))
    assert moves or name == "damping.stiffness_share"


@pytest.mark.parametrize("name", ["friction.slip_torque", "friction.slip_max"])
def test_a_kinematic_error_batch_row_is_its_single_run(name):
    batch, singles = _rows_and_singles(name, "kinematic_error")
    np.testing.assert_allclose(batch, singles, rtol=1e-9, atol=1e-12)
    assert np.any(np.abs(singles[:, 1] - singles[:, 0]) > 1e-3 * np.abs(singles[:, 0]))
