"""The stiffness metrics read only what the torque cycle loads the drive to.

A cycle too small for the three-segment fit (the ±4 % lost-motion cycle, whose loading
branch never reaches T1/2) is refused with one line saying which amplitude the metrics
need; the torsion "at rated" read at the tips is read at ±T_N, not at the cycle's tips,
and is absent for a cycle that never reaches T_N (docs/physics.md, "Test definitions").
"""

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit
from hdsim.scenarios import locked_metrics as lm
from hdsim.scenarios.run import run_scenario
from hdsim.scenarios.scenario import load_scenario
from hdsim.simulation.profiles import cosine_ramps

T_N, K, F, N = 87.0, 3.1e4, 2.0, 200


def coulomb_loop(amplitude):
    """(torque, twist, levels) of a linear spring K with a parallel Coulomb friction F cycled
    0 → +A → −A → 0 (A = ``amplitude`` T_N), N samples per ramp: the virgin loading sticks
    until T = F, the descent from +A until T = A − 2F."""
    levels = np.array([0.0, amplitude, -amplitude, 0.0])
    t = np.linspace(0.0, 3.0, 3 * N + 1)
    T = T_N * cosine_ramps(np.arange(4.0), levels)(t)
    A = amplitude * T_N
    x = np.empty_like(T)
    up0, down = slice(0, N + 1), slice(N, 2 * N + 1)
    x[up0] = np.maximum(T[up0] - F, 0.0) / K
    x[down] = np.minimum((A - F) / K, (T[down] + F) / K)
    x[2 * N:] = np.maximum((-A + F) / K, (T[2 * N:] - F) / K)
    return T[None, :], x[None, :], levels


def test_torsion_at_the_tips_is_read_at_rated_torque_on_a_cycle_beyond_it():
    """At ±1.5 T_N the loading branches pass ±T_N at ±(T_N − F)/K; the tips' own twist is
    (1.5 T_N − F)/K, which had been reported under the name."""
    T, x, levels = coulomb_loop(1.5)
    tips = lm.torsion_at_rated_tips(T, x, levels, N, T_N)
    assert tips == pytest.approx([(T_N - F) / K], rel=1e-9)


def test_torsion_at_the_tips_of_a_rated_cycle_is_the_tips_twist():
    T, x, levels = coulomb_loop(1.0)
    assert lm.torsion_at_rated_tips(T, x, levels, N, T_N) == pytest.approx([(T_N - F) / K], rel=1e-12)


def test_torsion_at_rated_is_not_measured_by_a_cycle_short_of_rated():
    T, x, levels = coulomb_loop(0.6)
    assert np.isnan(lm.torsion_at_rated_tips(T, x, levels, N, T_N)).all()


@pytest.mark.parametrize("amplitude, measured", [(0.6, False), (1.5, True)])
def test_a_stiffness_run_reports_the_twist_at_rated_only_where_its_cycle_reaches_it(amplitude, measured):
    """Against the ±T_N run of the same drive: at ±1.5 T_N the twist read at T_N on the way
    out agrees with the ±T_N tips to 1e-3 (it read 9.35 arcmin for 6.71 before)."""
    drive = load_unit("CSG-25-100")
    stiffness = load_scenario("stiffness")
    rated = run_scenario(drive, stiffness, evaluator="quasistatic").metric("torsion_at_rated_tip_arcmin")
    run = run_scenario(drive, stiffness.with_updates({"load.amplitude": amplitude}), evaluator="quasistatic")
    if measured:
        assert run.metric("torsion_at_rated_tip_arcmin") == pytest.approx(rated, rel=1e-3)
    else:  # absent, not NaN: the command line would refuse the whole run for one NaN figure
        assert "torsion_at_rated_tip_arcmin" not in run.metrics
        assert np.isfinite(run.metric("K3_Nm_per_rad"))  # the cycle passes T2: K3 is measured


LOST_MOTION_STIFFNESS = load_scenario("lost_motion").with_updates({"metrics": ["stiffness"]})


def test_the_lost_motion_cycle_cannot_give_the_stiffness_metrics_and_says_why():
    """The ±4 % cycle never reaches T1/2, where the fit starts: it stopped in numpy (np.ptp of
    an empty array); the refusal names the amplitude that gives K1…K3, T2/T_N = 48/87."""
    with pytest.raises(InputError, match=r"T1/2 = 7 N·m.*±0\.04 T_N.*load\.amplitude above T2/T_N = 0\.552"):
        run_scenario(load_unit("CSG-25-100"), LOST_MOTION_STIFFNESS, evaluator="quasistatic")


def test_a_batch_sample_the_cycle_cannot_fit_is_named():
    T, x, levels = coulomb_loop(0.2)  # to 17.4 N·m: above T1/2 = 7 N·m, below T1/2 = 18 N·m
    with pytest.raises(InputError, match=r"T1/2 = 18 N·m.*\(sample 1 of the batch\)"):
        lm.stiffness_fit(np.repeat(T, 2, 0), np.repeat(x, 2, 0), levels, N, np.array([14.0, 36.0]), 48.0, T_N)


def test_the_cli_refuses_the_stiffness_metrics_of_the_lost_motion_cycle_in_one_line(cli, tmp_path):
    code, out, err = cli("simulate", "lost_motion", "--set", 'scenario.metrics=["stiffness"]',
                         "--evaluator", "quasistatic", "--no-figures", "--out", tmp_path / "o")
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "load.amplitude above T2/T_N" in err
    assert not (tmp_path / "o" / "lost_motion.h5").exists()


def test_a_breakpoint_above_the_rated_torque_leaves_its_segment_out_and_the_torsion_at_rated_measured():
    """A datasheet's T2 above T_N (a low ratio's) made K3 and the torsion at T_N NaN, so the
    command refused the run (`hdsim demo` on such a drive file exited 2). K3 is now absent
    and the torsion at T_N reads the two segments below T_N: T1/K1 + (T_N − T1)/K2."""
    drive = load_unit("CSG-25-100")
    rated = float(drive.drive.rated_torque)
    high = drive.with_updates({"hardening.T2": 1.3 * rated})
    run = run_scenario(high, load_scenario("stiffness"), evaluator="quasistatic")
    assert "K3_Nm_per_rad" not in run.metrics
    T1 = float(high.params()["hardening.T1"])
    K1, K2 = run.metric("K1_Nm_per_rad"), run.metric("K2_Nm_per_rad")
    law = T1 / K1 + (rated - T1) / K2
    assert run.metric("torsion_at_rated_arcmin") == pytest.approx(law * 60 * 180 / np.pi, rel=1e-9)


def test_the_refusal_comes_before_the_run(monkeypatch):
    """It came after the whole simulation; the cycle's amplitude and the breakpoints decide it."""
    from hdsim.errors import InputError
    from hdsim.scenarios import locked

    def integrate(*args, **kwargs):
        raise AssertionError("the run started")

    monkeypatch.setattr(locked, "integrate", integrate)
    with pytest.raises(InputError, match="never reaches"):
        run_scenario(load_unit("CSG-25-100"), LOST_MOTION_STIFFNESS, evaluator="dynamic")
