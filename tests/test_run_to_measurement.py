"""A run of hdsim's own becomes a bench record, and the fit of it gives the drive back."""

from __future__ import annotations

import numpy as np
import pytest

import hdsim
from hdsim.errors import InputError


def test_a_simulated_stiffness_test_fitted_gives_the_drives_stiffness_back(tmp_path):
    drive = hdsim.load_unit("CSG-25-100").without("friction", "backlash", "damping")
    run = hdsim.run_scenario(drive, "stiffness", evaluator="quasistatic")
    record = hdsim.measurement_from_run(run, noise_rad=1e-6, seed=1)
    assert record.test == "stiffness" and len(record) == np.size(run.result.t)
    fitted = hdsim.fit(record, "hardening")
    again = hdsim.run_scenario(fitted.drive, "stiffness", evaluator="quasistatic")
    for name in ("K1_Nm_per_rad", "torsion_at_rated_arcmin"):
        assert again.metric(name) == pytest.approx(run.metric(name), rel=0.02)
    path = tmp_path / "run.h5"
    run.save(path)
    with pytest.raises(InputError, match="this is an hdsim result file"):
        hdsim.load_measurement(path)


def test_a_driven_run_is_a_kinematic_error_record_whose_error_is_the_runs(short_ke_run):
    run = short_ke_run
    record = hdsim.measurement_from_run(run)
    assert record.test == "kinematic_error" and record.ratio == pytest.approx(100.0)
    out, wg = np.ravel(run.result.signals["output_angle_rad"]), np.ravel(run.result.signals["wg_angle_rad"])
    np.testing.assert_allclose(record.kinematic_error, out - wg / 100.0, atol=1e-15)
