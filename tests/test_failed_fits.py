"""A fit that fails (here: a kinematic-error amplitude beyond what a drive can have, from a
record read with the wrong ratio) rejects its candidate with the reason and never ends the
diagnosis; the baseline's own failure is a refusal that names the record (contracts §3)."""

from __future__ import annotations

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.identification.diagnosis import diagnose
from hdsim.io.measurement import make_measurement


@pytest.fixture(scope="module")
def wrong_ratio():
    """A kinematic-error pass over 1.5 output turns at ratio 100, read with 101: 5° of drift,
    which the once-per-output-turn order takes up to far beyond its 0.01 rad bound."""
    t = np.linspace(0.0, 10.0, 600)
    out_nominal = 3.0 * np.pi * t / t[-1]
    torque = 20.0 * np.sin(2 * np.pi * t / 5.0)
    angle = out_nominal + torque / 3.1e4 + np.random.default_rng(0).normal(0.0, 1e-6, t.size)
    return make_measurement("kinematic_error", t, torque, angle, 100.0 * out_nominal, ratio=101.0,
                            source="ke_bench.csv")


def test_a_candidate_whose_fit_fails_is_rejected_with_its_reason(wrong_ratio):
    said = []
    d = diagnose(wrong_ratio, families=["kinematic_error"], max_rounds=1, log=said.append)
    entry = next(c for c in d.to_json()["ranking"] if c["family"] == "kinematic_error")
    assert entry["passes"] is False and "exceeds 0.01 rad" in entry["why"]
    assert d.added == []
    assert "round 1: kinematic_error failed" in said  # the round log, not "kinematic_error inf"


def test_the_baselines_own_failure_names_the_record(wrong_ratio):
    with pytest.raises(InputError, match=r"^ke_bench.csv: the baseline \(kinematic_error\) cannot be fitted.*"
                                         "exceeds 0.01 rad"):
        diagnose(wrong_ratio, "kinematic_error")
