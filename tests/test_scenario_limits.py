"""Scenario files that would exhaust memory or run for hours are refused before anything
is allocated, with the estimate and the limit in one line."""

from __future__ import annotations

import pytest

from hdsim.errors import InputError
from hdsim.scenarios.scenario import Scenario


def _locked(**load):
    base = {"amplitude": 0.04, "cycles": 2, "rate": 0.04}
    base.update(load)
    return {"name": "x", "setup": "locked_wave_generator", "metrics": ["lost_motion"], "load": base}


@pytest.mark.parametrize("data, match", [
    (_locked(cycles=10**7), "load.cycles"),
    (_locked(rate=1e-9), "bench time"),
    (dict(_locked(), output={"samples_per_segment": 10**8}), "output samples"),
    (dict(_locked(), output={"samples_per_segment": 1}), "at least 2"),
])
def test_absurd_sizes_are_refused_with_the_estimate(data, match, monkeypatch):
    import hdsim.simulation.solver as solver

    def no_solver(*args, **kwargs):  # the refusal must come before any integration
        raise AssertionError("the solver was called")

    monkeypatch.setattr(solver, "solve_ivp", no_solver)
    with pytest.raises(InputError, match=match) as info:
        Scenario(data, "big.toml")
    assert "limit" in str(info.value) or "at least" in str(info.value)
    assert "\n" not in str(info.value)


def test_a_catalog_test_is_far_inside_the_limits():
    Scenario(_locked(cycles=3, rate=0.04), "ok.toml")
