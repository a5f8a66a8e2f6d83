"""A single model's right-hand side runs on Python floats (`math`, `bisect`), a batch's on
numpy arrays: both must compute the same numbers.

The laws pick their branch by the type of their argument (`hdsim.physics.elementary`,
`hdsim.physics.smooth`), so a single model and a batch of two copies of it go through
different code. Here both are evaluated at the same states, law by law and through the
whole right-hand side of each bench, and must agree to round-off: `math` and numpy may
differ in the last bit of a transcendental function, and a difference near cancellation
(``1 − tanh²`` near 1, the dead zone's ``1 − (1 − ε)κ`` of 1e-5 in contact) shows that bit
relative to the law's scale, not to the value. A wrong branch differs by far more.
"""

import math
from dataclasses import dataclass

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model import effects as fx
from hdsim.model.catalog import load_unit
from hdsim.model.parameters import Parameters, param
from hdsim.physics import backlash as bl
from hdsim.physics import smooth
from hdsim.physics import stiffness as st
from hdsim.scenarios.driven import bench_from_scenario
from hdsim.scenarios.scenario import builtin_scenario_path, load_scenario
from hdsim.simulation.loads import opposing_load, ramped_load
from hdsim.simulation.motion import SpeedKnots
from hdsim.simulation.path import ElasticPath, locked_wave_generator
from hdsim.simulation.profiles import cosine_ramps



def _close(scalar, array, rtol=1e-13):
    """Equal within ``rtol`` of the values and of the largest of them (the law's scale)."""
    array = np.asarray(array, dtype=float)
    np.testing.assert_allclose(scalar, array, rtol=rtol, atol=rtol * float(np.max(np.abs(array))))

POINTS = np.concatenate([np.linspace(-3e-3, 3e-3, 41), [0.0, -0.0, 1e-9, -2.5e-4, 2.5e-4]])


def _both(function, *args):
    """``function`` element by element on floats, and once on the array."""
    scalar = np.array([function(float(x), *args) for x in POINTS])
    return scalar, np.asarray(function(POINTS, *args), dtype=float)


@pytest.mark.parametrize("function, args", [
    (smooth.softplus, (2e-4,)), (smooth.softplus_slope, (2e-4,)),
    (lambda x: smooth.magnitude_and_sign(x)[0], ()), (lambda x: smooth.magnitude_and_sign(x)[1], ()),
    (st.smooth_three_segment_torque, (10.0, 40.0, 3e4, 4.5e4, 7.5e4, 2e-5)),
    (st.smooth_three_segment_tangent, (10.0, 40.0, 3e4, 4.5e4, 7.5e4, 2e-5)),
    (bl.smooth_dead_zone, (1e-4, 2e-5)), (bl.smooth_contact, (1e-4, 2e-5)),
], ids=["softplus", "softplus_slope", "magnitude", "sign", "spring", "tangent", "dead_zone", "contact"])
def test_each_law_gives_floats_what_it_gives_arrays(function, args):
    scalar, array = _both(function, *args)
    assert all(isinstance(function(float(x), *args), float) for x in POINTS[:3])  # the float branch ran
    _close(scalar, array)


def test_the_sign_is_numpys_at_zero_and_nan():
    for x in (0.0, -0.0, math.nan, math.inf, -2.0):
        _, sign = smooth.magnitude_and_sign(x)
        np.testing.assert_equal(sign, np.sign(x))


def test_profiles_motion_and_brake_give_floats_what_they_give_arrays():
    times = np.linspace(0.0, 1.3, 200)
    ramp = cosine_ramps([0.0, 0.3, 0.7, 1.2], [0.0, 80.0, -80.0, 0.0])
    knots = SpeedKnots([0.0, 0.2, 0.6, 0.9], [0.0, 300.0, 300.0, -150.0])
    brake = opposing_load(20.0, knots.motion({}, "test"), smoothing_speed=3.0, ratio=100.0)
    for function in (ramp, knots.speed, knots.accel, knots.angle, brake.torque, brake.rate):
        scalar = np.array([function(float(t)) for t in times])
        _close(scalar, function(times))


@pytest.mark.parametrize("shape", ["cosine", "linear"])
def test_motion_and_load_at_one_time_are_their_separate_calls(shape):
    # the right-hand side asks `Motion.at` and `Load.at` for everything at once: bit for bit
    # what the separate functions give, before, inside and after the knots
    knots = SpeedKnots([0.0, 0.2, 0.6, 0.9], [0.0, 300.0, 300.0, -150.0], shape)
    motion = knots.motion({}, "test")
    loads = (opposing_load(20.0, motion, smoothing_speed=3.0, ratio=100.0), ramped_load(12.0, 0.4))
    for t in (-0.1, 0.0, 0.05, 0.2, 0.41, 0.75, 0.9, 1.4):
        assert motion.at(t) == (motion.angle(t), motion.speed(t), motion.accel(t))
        for load in loads:
            assert load.at(t) == (load.torque(t), load.rate(t))
    times = np.linspace(0.0, 1.0, 7)[:, None]  # arrays: the three (two) calls
    for got, want in zip(motion.at(times), (motion.angle(times), motion.speed(times), motion.accel(times))):
        np.testing.assert_array_equal(got, want)
    # and what they give is a motion and a load: each rate is the derivative of its value
    # (central differences, away from the knots where a linear profile's acceleration jumps)
    h = 1e-6
    for t in (0.05, 0.13, 0.41, 0.75):
        (a0, v0, _), (a1, v1, _), (_, v, acc) = motion.at(t - h), motion.at(t + h), motion.at(t)
        assert (a1 - a0) / (2 * h) == pytest.approx(v, rel=1e-6, abs=1e-6 * 300.0)
        assert (v1 - v0) / (2 * h) == pytest.approx(acc, rel=1e-4, abs=1e-4 * 1500.0)
        for load in loads:
            (T0, _), (T1, _), (_, rate) = load.at(t - h), load.at(t + h), load.at(t)
            assert (T1 - T0) / (2 * h) == pytest.approx(rate, rel=1e-4, abs=1e-4 * 1500.0)


def test_input_friction_gives_floats_what_it_gives_arrays():
    law = load_unit().input_friction.with_updates(
        ripple_orders=(1.0, 2.0), ripple_amplitudes=(0.1, 0.05), ripple_phases=(0.3, -1.0),
        position_orders=(4.0,), position_amplitudes=(0.02,), position_phases=(0.5,), coulomb_asymmetry=0.01,
        load_coefficient=0.02)
    speed = np.linspace(-50.0, 50.0, 101)
    angle = np.linspace(0.0, 20.0, 101)
    mesh = np.linspace(-1.0, 1.0, 101)
    scalar = np.array([law.torque(float(w), float(a), float(m)) for w, a, m in zip(speed, angle, mesh)])
    _close(scalar, law.torque(speed, angle, mesh))


EFFECTS = {
    "default": {},
    "tanh-maxwell-gradual": dict(hardening=fx.TanhHardening(e_inf=2.5, T_s=30.0),
                                 friction=fx.MaxwellSlip(k_total=3e4, slip_torque_max=6.0, velocity_scale=1e-6),
                                 backlash=fx.GradualDeadZone(gap=1e-4, contact_rounding=2.0)),
    "3seg-distributed-undamped": dict(hardening=fx.ThreeSegmentHardening(T1=10.0, T2=40.0, e2=1.5, e3=2.5),
                                      friction=fx.DistributedSlip(slip_torque=8.0, slip_max=2e-4, spread=0.5),
                                      damping=fx.NO_EFFECT["damping"]),
    "dahl-coulomb": dict(friction=fx.DahlFriction(torque_max=4.0, sigma=6e4)),
}


def _single_and_pair(effects):
    """The default unit with ``effects``, and a batch of two copies of it (array parameters)."""
    model = load_unit().with_effects(**effects) if effects else load_unit()
    h_c = float(model.params()["flexspline.h_c"])
    return model, model.with_updates({"flexspline.h_c": np.array([h_c, h_c])})


def _states(system, seed):
    """States about the start, each spread over its own scale."""
    rng = np.random.default_rng(seed)
    return [system.y0 + system.state_scales * rng.normal(0.0, 3.0, system.state_scales.size) for _ in range(20)]


def _agree(single, pair, times):
    assert single.batch == 1 and pair.batch == 2
    for k, (t, y) in enumerate(zip(times, _states(single, 7))):
        one = single.rhs(float(t), y)
        two = pair.rhs(float(t), np.concatenate([y, y]))
        # the stiff rates amplify a last-bit difference by up to 1e5 (the module text)
        np.testing.assert_allclose(np.concatenate([one, one]), two, rtol=1e-9, atol=1e-300, err_msg=f"state {k}")


@pytest.mark.parametrize("effects", EFFECTS.values(), ids=EFFECTS.keys())
def test_the_locked_bench_of_a_single_model_is_that_of_a_batch(effects):
    model, pair = _single_and_pair(effects)
    profile = cosine_ramps([0.0, 1.0, 2.0], [0.0, 80.0, -80.0])
    _agree(locked_wave_generator(model, profile), locked_wave_generator(pair, lambda t: profile(t) * np.ones(2)),
           np.linspace(0.05, 1.9, 20))


@pytest.mark.parametrize("scenario", ["kinematic_error", "running_torque", "reversal"])
@pytest.mark.parametrize("effects", EFFECTS.values(), ids=EFFECTS.keys())
def test_the_driven_bench_of_a_single_model_is_that_of_a_batch(scenario, effects):
    model, pair = _single_and_pair(effects)
    bench = bench_from_scenario(model, load_scenario(builtin_scenario_path(scenario)))
    _agree(bench.system(model), bench.system(pair), np.linspace(0.1, 0.9 * bench.t_end, 20))


@pytest.mark.parametrize("bench", ["locked", "kinematic_error", "reversal"])
def test_a_batch_of_one_row_runs_as_its_single_model(bench):
    # a study's task of one row: parameters as (1,) arrays, one sample, numpy inside
    model = load_unit()
    one = model.with_updates({"flexspline.h_c": np.array([float(model.params()["flexspline.h_c"])])})
    assert one.batch_size == 1 and isinstance(one.params()["flexspline.h_c"], np.ndarray)
    if bench == "locked":
        profile = cosine_ramps([0.0, 1.0, 2.0], [0.0, 80.0, -80.0])
        single, row, times = (locked_wave_generator(model, profile), locked_wave_generator(one, profile),
                              np.linspace(0.05, 1.9, 20))
    else:
        setup = bench_from_scenario(model, load_scenario(builtin_scenario_path(bench)))
        single, row, times = setup.system(model), setup.system(one), np.linspace(0.1, 0.9 * setup.t_end, 20)
    for k, (t, y) in enumerate(zip(times, _states(single, 3))):
        np.testing.assert_allclose(row.rhs(float(t), y), single.rhs(float(t), y), rtol=1e-9, atol=1e-300,
                                   err_msg=f"state {k}")


@pytest.mark.parametrize("effects", EFFECTS.values(), ids=EFFECTS.keys())
def test_a_single_models_elastic_path_computes_in_python_floats(effects):
    # numpy's scalars pass `isinstance(x, float)` but cost ~3x a float per operation: the
    # parameters, the structure's split and the states must reach the laws as floats
    model, _ = _single_and_pair(effects)
    path = ElasticPath(model)
    states = [float(v) for v in path.settled(1e-4, np.zeros(len(path.states)))]
    torque, _, _ = path.evaluate(1e-4, 1e-3, states)
    assert type(torque) is float  # a law with an element axis (distributed slip) keeps numpy inside


def test_numpy_scalars_become_floats_and_arrays_stay_arrays():
    model = load_unit().with_updates({"damping.coefficient": np.float64(2.5),
                                      "friction.slip_torque": np.array(3.0)})
    assert type(model.damping.coefficient) is float and model.damping.coefficient == 2.5
    assert type(model.friction.slip_torque) is float and model.friction.slip_torque == 3.0
    batch = load_unit().with_updates({"damping.coefficient": np.array([2.0, 3.0])})
    assert isinstance(batch.damping.coefficient, np.ndarray) and batch.damping.coefficient.shape == (2,)


@dataclass(frozen=True)
class _Holder(Parameters):
    prefix = "holder"
    bounded: float = param("a value in [0, 10]", "-", 0.0, 10.0)
    positive: float = param("a value in (0, inf)", "-", positive=True, default=1.0)


@pytest.mark.parametrize("field_name, value, refused", [
    ("bounded", 5.0, False), ("bounded", 0.0, False), ("bounded", 10.0, False), ("bounded", -1e-12, True),
    ("bounded", 10.5, True), ("bounded", math.nan, True), ("positive", math.inf, True), ("positive", 0.0, True),
    ("positive", -0.0, True), ("positive", 1e-300, False)])
def test_a_float_is_checked_against_its_bounds_as_an_array_is(field_name, value, refused):
    """The float path of the bound check (no numpy) refuses what the array path refuses."""
    base = {"bounded": 1.0, "positive": 1.0}
    for given in (value, np.array([1.0, value])):
        kwargs = {**base, field_name: given}
        if refused:
            with pytest.raises(InputError, match=f"holder.{field_name} = .* is outside"):
                _Holder(**kwargs)
        else:
            assert np.all(getattr(_Holder(**kwargs), field_name) == given)
