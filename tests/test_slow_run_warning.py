"""A dynamic locked-bench run that will take minutes says why before it starts.

A drive fitted to a stiffness record came out with a Dahl friction sticking at 6600 times
the spring's stiffness and no damping; ``run_scenario(fit.drive, "lost_motion")`` then took
2–3 minutes (2.2 million right-hand-side evaluations: the output rings on the sticking
friction at every reversal) without a word, where the quasi-static evaluator gives the
same lost motion in 0.02 s. The stand-in integrator here stops the run at once, so the
file takes a fraction of a second.
"""

from __future__ import annotations

import warnings

import pytest

from hdsim.model.catalog import load_unit
from hdsim.model.effects import DahlFriction, NoDamping, ViscousDamping
from hdsim.scenarios import locked
from hdsim.errors import SlowRunWarning
from hdsim.scenarios.locked import slow_run_reason, sticking_mode
from hdsim.scenarios.run import run_scenario


@pytest.fixture(scope="module")
def sticking():
    """The fitted drive's friction (0.52 N·m, sigma 1.3e8 N·m/rad) without damping."""
    return load_unit("CSG-25-100").with_effects(friction=DahlFriction(torque_max=0.52, sigma=1.3e8),
                                                damping=NoDamping())


class _Stopped(Exception):
    pass


def test_a_slow_dynamic_run_warns_before_it_integrates(sticking, monkeypatch):
    def integrate(*args, **kwargs):
        raise _Stopped

    monkeypatch.setattr(locked, "integrate", integrate)
    with pytest.warns(SlowRunWarning, match=r"its friction sticks at 4\.\d+e\+03 times the spring's stiffness") as caught, \
            pytest.raises(_Stopped):
        run_scenario(sticking, "lost_motion")
    assert caught[0].filename == __file__  # pointed at the caller's run_scenario line
    assert "evaluator='quasistatic'" in str(caught[0].message)


def test_the_quasistatic_evaluator_runs_it_without_a_word(sticking):
    with warnings.catch_warnings():
        warnings.simplefilter("error", SlowRunWarning)
        assert run_scenario(sticking, "lost_motion", evaluator="auto").result.solver["method"] == "quasistatic"


def test_damping_makes_no_slow_run_and_an_undamped_mode_is_slow_however_soft_the_sticking(sticking):
    mode = sticking_mode(sticking)
    assert mode["damping_ratio"] == 0.0 and mode["frequency_Hz"] > 3e4
    assert slow_run_reason(load_unit("CSG-25-100")) is None
    # a damping ratio of 1e-4 on the stick mode took the run from 1.1 million evaluations a cycle to 91,000
    damped = sticking.with_effects(damping=ViscousDamping(coefficient=0.2))
    assert sticking_mode(damped)["damping_ratio"] > 1e-4 and slow_run_reason(damped) is None
    # undamped, however soft the sticking, the output rings: the default unit without its
    # damping took 38 s for the ±4 % test (1.2 s with it), a Dahl law at 250x 29 s
    soft = sticking.with_updates({"friction.sigma": 250 * float(sticking.base_stiffness)})
    assert "the output rings on the spring at" in slow_run_reason(soft)
    undamped = load_unit("CSG-25-100").with_effects(damping=NoDamping())
    assert sticking_mode(undamped)["sticking_ratio"] < 2 and "rings on the spring" in slow_run_reason(undamped)


def test_the_command_says_it_on_a_line_of_its_own_in_its_own_words(capsys):
    """On the command line the warning was Python's ("path.py:45: SlowRunWarning: …
    evaluator='quasistatic'"); it is a ``warn:`` line naming the command's option."""
    from hdsim.cli import hide_library_warnings

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        hide_library_warnings("simulate")
        warnings.warn("slow here; evaluator='quasistatic' is fast, and 'auto' takes it", SlowRunWarning)
    err = capsys.readouterr().err
    assert err == "hdsim simulate: warn: slow here; --evaluator quasistatic is fast, and --evaluator auto takes it\n"


def test_a_batch_over_the_friction_is_judged_sample_by_sample(sticking, monkeypatch):
    """A batch that varies only an effect's parameter (a Sobol study of ``friction.sigma``
    on the dynamic evaluator) raised a broadcasting error before it started, and of a batch
    only the stiffest sample was judged, though a damped one does not ring."""
    import numpy as np

    K = float(sticking.base_stiffness)
    batch = sticking.with_effects(friction=DahlFriction(torque_max=0.52, sigma=np.array([6600 * K, 1000 * K, 10 * K])),
                                  damping=ViscousDamping(coefficient=np.array([0.2, 0.0, 0.0])))
    mode = sticking_mode(batch)
    # the damped 6600x sample does not ring; the undamped 1000x one does (the path tangent of
    # a Dahl law at rest is sigma, plus the spring's own stiffness beside it)
    assert mode["damping_ratio"] == 0.0 and 1000 <= mode["sticking_ratio"] < 1002

    def integrate(*args, **kwargs):
        raise _Stopped

    monkeypatch.setattr(locked, "integrate", integrate)
    with pytest.warns(SlowRunWarning, match=r"sticks at 1e\+03 times"), pytest.raises(_Stopped):
        run_scenario(batch, "lost_motion")
    calm = batch.with_effects(damping=ViscousDamping(coefficient=np.array([0.2, 0.2, 0.2])))
    assert slow_run_reason(calm) is None
    assert slow_run_reason(load_unit("CSG-25-100")) is None  # the default unit is damped
