"""The kinematic error's amplitudes and phases carry an uncertainty, against the closed form.

They are solved linearly at the fitted coordinates, so the covariance of the fitted
coordinates held none of them, and `hdsim fit` printed neither them nor an uncertainty. For
a sinusoid of amplitude a in white noise of rms σ over n samples spread evenly over whole
turns, least squares gives ``σ_a = σ √(2/n)`` and ``σ_φ = σ_a / a``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hdsim
from hdsim.cli import main
from hdsim.io.measurement import make_measurement, save_measurement

N, SIGMA, A1, P1, K = 4000, 2e-6, 3e-5, 0.2, 3.1e4


@pytest.fixture(scope="module")
def record():
    t = np.linspace(0.0, 40.0, N, endpoint=False)
    wg = 2 * math.pi * 5.0 * t  # 200 whole turns
    torque = 20.0 * (1.0 + 0.5 * np.sin(2 * math.pi * t / 17.0))
    out = (wg / 100 + torque / K + A1 * np.sin(wg + P1) + 8e-5 * np.cos(2 * wg) + 1e-3
           + SIGMA * np.random.default_rng(0).standard_normal(N))
    return make_measurement("kinematic_error", t, torque, out, wg_angle=wg, ratio=100, rated_torque=87.0)


def test_the_amplitude_and_phase_uncertainties_are_the_closed_forms(record):
    fit = hdsim.fit(record, effects=["kinematic_error"])
    sigma_a = SIGMA * math.sqrt(2.0 / N)
    for order in ("a1", "a2", "a4", "a_out"):
        assert fit.uncertainty[f"kinematic_error.{order}"] == pytest.approx(sigma_a, rel=0.1)
    assert fit.uncertainty["kinematic_error.p1"] == pytest.approx(sigma_a / A1, rel=0.1)
    assert abs(fit.params["kinematic_error.a1"] - A1) < 4 * sigma_a
    assert abs(fit.params["kinematic_error.p1"] - P1) < 4 * sigma_a / A1


def test_the_command_prints_each_amplitude_in_arcsec_with_its_uncertainty(record, tmp_path, capsys):
    path = save_measurement(record, tmp_path / "ke.csv")
    assert main(["fit", str(path), "--effects", "kinematic_error", "--out", str(tmp_path / "ke.fit.toml")]) == 0
    lines = {line.split()[0]: line.split()[1:] for line in capsys.readouterr().out.splitlines()
             if line.strip().startswith("kinematic_error.")}
    value, plus, sigma, unit = lines["kinematic_error.a1"]
    assert plus == "±" and unit == "arcsec"
    assert float(value) == pytest.approx(A1 * 180 / math.pi * 3600, rel=0.01)
    assert float(sigma) == pytest.approx(SIGMA * math.sqrt(2.0 / N) * 180 / math.pi * 3600, rel=0.1)
