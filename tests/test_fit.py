"""Fit: quasi-static evaluator against the dynamic model, fit round trips, write-back, CLI.

Data made with hdsim's own effects are *self-consistency* tests (labelled so); the
discovery tests on independent truth data are in ``test_diagnosis.py``.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from hdsim.model import effects as fx
from hdsim.model.catalog import load_unit
from hdsim.errors import InputError
from hdsim.identification.fit import fit, load_fitted, parse_effects, split_stiffness
from hdsim.io.measurement import make_measurement
from hdsim.physics import friction as fr
from hdsim.scenarios.profiles import cosine_ramps
from hdsim.simulation.quasistatic import (UnsupportedEffect, dynamic_locked_twist, locked_twist,
                               sample_grid, stack_models)

UNIT = load_unit()
K = float(UNIT.base_stiffness)


def full_model(**changes):
    model = UNIT.with_effects(hardening=fx.TanhHardening(e_inf=2.5, T_s=30.0),
                              backlash=fx.DeadZoneBacklash(gap=1.5e-4),
                              friction=fx.DahlFriction(torque_max=4.0, sigma=2 * K),
                              damping=fx.ViscousDamping(coefficient=300.0, stiffness_share=0.5))
    return model.with_effects(**changes) if changes else model


def slow_profile(n=1500):
    """0 → +T_N → −T_N → +T_N → 0 with cosine ramps (no rate jumps: no ringing)."""
    f = cosine_ramps(np.array([0, 1, 3, 5, 6.0]), np.array([0, 87, -87, 87, 0.0]))
    t = np.linspace(0, 6, n)
    return t, f(t)


# --------------------------------------------------------------------------- quasi-static


@pytest.mark.parametrize("drop,tol_rms", [
    (("hardening", "backlash", "friction"), 1e-8),  # linear spring + damper: the scheme is exact
    (("backlash",), 2e-7),                          # tanh hardening + Dahl + viscous
])
def test_quasistatic_matches_dynamic_model_on_a_slow_profile(drop, tol_rms):
    model = full_model().without(*drop)
    t, T = slow_profile()
    q = locked_twist(model, t, T)[0]
    d = dynamic_locked_twist(model, t, T).ravel()
    err = q - d
    assert np.sqrt(np.mean(err**2)) < tol_rms
    assert np.max(np.abs(err)) < 50 * tol_rms + 1e-7
    assert np.ptp(d) > 3e-3  # a real ±T_N loop was compared


@pytest.mark.parametrize("drop", [("friction", "hardening"), ("friction",), ()])
def test_quasistatic_with_backlash_differs_only_in_the_boundary_layer_at_zero_torque(drop):
    """Backlash + damping (and body friction): the body in series with the dead zone has its
    own state in the dynamic model (``backlash.closure``). Only the output inertia differs:
    it crosses the gap in a fast transient where the quasi-static limit jumps."""
    model = full_model().without(*drop)
    t, T = slow_profile()
    q = locked_twist(model, t, T)[0]
    d = dynamic_locked_twist(model, t, T).ravel()
    err = np.abs(q - d)
    # measured: 3e-8 .. 1.1e-7 rad beyond 4 N·m, 2e-6 beyond 1 N·m, 6e-6 inside
    assert np.max(err[np.abs(T) > 4.0]) < 5e-7
    assert np.max(err[np.abs(T) > 1.0]) < 4e-6
    assert np.sqrt(np.mean(err**2)) < 5e-7


def test_series_dead_zone_keeps_the_body_lag_through_the_gap():
    """Closed form: linear spring K₀ ∥ damper c behind a dead zone of width b, torque ramp
    of rate Ṫ. After the start transient (time constant c/K₀) the body lags by c·Ṫ/K₀²
    whatever the dead zone does, and the dead zone adds ±b/2 on either side of T = 0:
    ``x = T/K₀ − c Ṫ/K₀² ± b/2``. (The ElastoBacklash contact rule would drop the lag
    where the gap opens.)"""
    gap, c = 1e-4, 600.0
    model = UNIT.with_effects(hardening=fx.NO_EFFECT["hardening"], backlash=fx.DeadZoneBacklash(gap=gap),
                              friction=fx.NO_EFFECT["friction"], damping=fx.ViscousDamping(coefficient=c))
    K0 = float(UNIT.base_stiffness)
    rate = -350.0  # [N·m/s]: the fast block of a bench test; the lag is c·Ṫ/K₀ = 6.8 N·m
    t = np.linspace(0.0, 0.8, 4001)
    T = 150.0 + rate * t
    x = locked_twist(model, t, T)[0]
    settled = t > 10 * c / K0  # the start from rest has decayed to e⁻¹⁰
    for side in (+1, -1):
        # beyond the rounded corner (closes over ~K₀·0.2·b = 0.6 N·m), within the lag's reach
        sel = settled & (side * T > 4.0) & (side * T < 60.0)
        expected = T[sel] / K0 - c * rate / K0**2 + side * gap / 2
        np.testing.assert_allclose(x[sel], expected, rtol=0, atol=5e-8)  # old rule: 1.5e-5
    assert c * abs(rate) / K0**2 > 1e-4  # the lag is there to be lost


def test_load_dependent_damping_follows_the_tangent_stiffness():
    """On a slow ramp the damper makes the twist lag by c(e)·Ṫ/K_t(e)² (quasi-steady),
    with c(e) = c₀[(1 − s) + s K_t/K₀] and K_t the hardening law's tangent stiffness."""
    hardening = fx.TanhHardening(e_inf=2.5, T_s=30.0)
    c0, rate = 300.0, 20.0
    t = np.linspace(0.0, 4.0, 4001)
    T = rate * t
    for share in (0.0, 0.6, 1.0):
        model = UNIT.with_effects(hardening=hardening, backlash=fx.NO_EFFECT["backlash"],
                                  friction=fx.NO_EFFECT["friction"],
                                  damping=fx.ViscousDamping(coefficient=c0, stiffness_share=share))
        undamped = locked_twist(model.without("damping"), t, T)[0]
        lag = undamped - locked_twist(model, t, T)[0]
        cs, cm = model.split()
        K0 = float(hardening.tangent(0.0, cs, cm))
        sel = (T > 20.0) & (T < 80.0)
        Kt = hardening.tangent(undamped[sel], cs, cm)
        expected = c0 * (1.0 - share + share * Kt / K0) * rate / Kt**2
        assert np.ptp(Kt) / K0 > 0.4  # the tangent stiffness does change over the ramp
        np.testing.assert_allclose(lag[sel], expected, rtol=0.02)


def test_dahl_update_is_the_exact_solution_of_the_library_law():
    from scipy.integrate import solve_ivp

    sigma, F = 6e4, 4.0
    for z0, dx in ((0.0, 2e-4), (3.0, -1.5e-4), (-3.9, 4e-5)):
        sol = solve_ivp(lambda th, z: [fr.dahl_rate(z[0], np.sign(dx), sigma, F)], (0, abs(dx)), [z0],
                        rtol=1e-11, atol=1e-12)
        model = UNIT.with_effects(friction=fx.DahlFriction(torque_max=F, sigma=sigma))
        from hdsim.simulation.quasistatic import _Kernel

        kern = _Kernel(stack_models(model))
        z, _ = kern.dahl(np.array([z0]), np.array([dx]))
        assert z[0] == pytest.approx(sol.y[0, -1], abs=1e-8)


def test_rate_independent_without_damping():
    model = full_model().without("damping")
    t, T = slow_profile(800)
    a = locked_twist(model, t, T)
    b = locked_twist(model, 10.0 * t, T)
    np.testing.assert_allclose(a, b, atol=1e-13)


def test_stacked_models_equal_separate_runs_and_neutral_parameters_are_exact():
    t, T = slow_profile(600)
    models = [full_model(), full_model().without("backlash", "friction"),
              UNIT.with_effects(hardening=fx.NO_EFFECT["hardening"], backlash=fx.NO_EFFECT["backlash"],
                                friction=fx.NO_EFFECT["friction"], damping=fx.NO_EFFECT["damping"])]
    together = locked_twist(models, t, T)
    for i, m in enumerate(models):
        alone = locked_twist(m, t, T)[0]
        np.testing.assert_allclose(together[i], alone, rtol=0, atol=3e-9)  # Newton stop x_tol
    # the linear model is T/K exactly
    np.testing.assert_allclose(together[2], T / K, rtol=1e-12, atol=1e-15)


def test_batch_parameters():
    model = full_model().with_updates({"damping.coefficient": np.array([100.0, 300.0, 600.0])})
    t, T = slow_profile(500)
    out = locked_twist(model, t, T)
    assert out.shape == (3, 500)
    single = locked_twist(full_model().with_updates({"damping.coefficient": 600.0}), t, T)[0]
    np.testing.assert_allclose(out[2], single, atol=3e-9)  # Newton stop x_tol = 1e-8 rad


def test_unsupported_effect_is_refused():
    t, T = slow_profile(100)
    with pytest.raises(UnsupportedEffect):
        locked_twist(UNIT, t, T)  # the unit's default friction is dahl_slip


def test_sub_grid_of_a_long_record_stays_below_the_noise():
    model = full_model()
    t, T = slow_profile(20000)
    grid = sample_grid(t, T, max_steps=4000)
    assert grid.size <= 4000 and grid[0] == 0 and grid[-1] == t.size - 1
    every = locked_twist(model, t, T)[0]
    sub = locked_twist(model, t, T, grid=4000)[0]
    err = np.abs(every - sub)
    # the jump across the dead zone may land one sample earlier or later: that single
    # sample aside, the sub-grid is within a fraction of the encoder noise (2e-6 rad)
    assert np.quantile(err, 0.999) < 1e-6
    assert np.sqrt(np.mean(err**2)) < 1e-6


# --------------------------------------------------------------------------- fit


def library_data(model, seed=0, n=1500, offset=-2.4, noise=2e-6):
    """Self-consistency data: the library's own quasi-static model plus noise and an offset."""
    t, T = slow_profile(n)
    rng = np.random.default_rng(seed)
    angle = offset + locked_twist(model, t, T)[0] + rng.normal(0, noise, n)
    return make_measurement("stiffness", t, T, angle, rated_torque=87.0)


def test_self_consistency_fit_recovers_parameters_and_offset():
    truth_model = full_model().without("backlash")
    meas = library_data(truth_model, offset=2.9)
    res = fit(meas, "hardening,friction,damping")
    assert res.rmse_rad < 2.4e-6  # at the noise
    assert res.offset == pytest.approx(2.9, abs=2e-6)
    assert res.params["friction.torque_max"] == pytest.approx(4.0, rel=0.05)
    assert res.params["damping.coefficient"] == pytest.approx(300.0, rel=0.05)
    assert res.internal["stiffness.K0"] == pytest.approx(K, rel=0.01)
    for name in res.internal:
        assert res.uncertainty[name] > 0
    # the uncertainty is honest: the true value within 4 sigma
    assert abs(res.params["friction.torque_max"] - 4.0) < 4 * res.uncertainty["friction.torque_max"] + 0.02


def test_offset_is_not_error():
    model = UNIT.without(*[f for f in ("hardening", "backlash", "friction", "damping")])
    a = fit(library_data(model, offset=0.0))
    b = fit(library_data(model, offset=-3.1))
    assert a.rmse_rad == pytest.approx(b.rmse_rad, rel=1e-3)


def test_fitted_parameter_set_round_trip(tmp_path):
    truth_model = full_model().without("backlash")
    meas = library_data(truth_model)
    res = fit(meas, "hardening,friction,damping")
    path = res.save(tmp_path / "fit.toml")
    text = path.read_text()
    assert "[parameters]" in text and '"friction.torque_max"' in text
    model = load_fitted(path)
    assert model.friction.id == "dahl" and model.backlash.id == "none"
    again = locked_twist(model, meas.time, meas.torque)[0] + res.offset
    np.testing.assert_allclose(again, res.prediction, atol=1e-10)
    # the loaded model is an ordinary model: the dynamic simulator runs it as well
    dyn = dynamic_locked_twist(model, meas.time[:400], meas.torque[:400]).ravel()
    assert np.max(np.abs(dyn - (res.prediction[:400] - res.offset))) < 5e-6


def test_split_stiffness_keeps_k0_and_k_inf():
    for K0, ratio in ((3e4, 1.0), (3e4, 2.0), (3e4, 15.0), (2e5, 1.0)):
        up, e_inf = split_stiffness(UNIT, np.array([K0]), np.array([ratio]))
        model = UNIT.with_updates({k: float(v[0]) for k, v in up.items()})
        cs, cm = (float(np.asarray(v)) for v in model.split())
        assert 1.0 / (cs + cm) == pytest.approx(K0, rel=1e-9)
        assert 1.0 / (cs + cm / e_inf[0]) == pytest.approx(ratio * K0, rel=1e-9)


def test_parse_effects():
    assert parse_effects("friction,hardening") == {"hardening": "tanh", "friction": "dahl"}
    assert parse_effects("dahl, dead_zone") == {"backlash": "dead_zone", "friction": "dahl"}
    assert parse_effects("friction=dahl,none,") == {"friction": "dahl"}
    assert parse_effects("") == {} and parse_effects(None) == {}
    with pytest.raises(InputError, match="did you mean friction"):
        parse_effects("fricton")
    with pytest.raises(InputError, match="two friction effects"):
        parse_effects("dahl,coulomb")


def test_fit_refuses_an_effect_it_cannot_evaluate():
    meas = library_data(UNIT.without("hardening", "backlash", "friction", "damping"))
    with pytest.raises(InputError):
        fit(meas, "coulomb")


# --------------------------------------------------------------------------- CLI


def run_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "hdsim", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


def test_cli_fit_json_and_parameter_file(tmp_path):
    import truth

    cols, tr = truth.make_stiffness_data({"friction"}, set(), seed=3, n_rows=600, quarter_s=(1.0,))
    truth.write_csv(tmp_path / "bench.csv", cols, tr["meta"])
    out = run_cli("fit", "bench.csv", "--effects", "friction", "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    assert summary["effects"] == ["friction"] and summary["rmse_rad"] < 1e-5
    assert (tmp_path / "bench.fit.toml").is_file()
    assert load_fitted(tmp_path / "bench.fit.toml").friction.id == "dahl"
    assert abs(summary["offset_rad"] - tr["params"]["offset_rad"]) < 1e-5


BAD_FILES = {
    "missing_column": "# test: stiffness\ntime_s,torque_Nm\n" + "".join(f"{i},1\n" for i in range(12)),
    "unknown_column": "# test: stiffness\ntime_s,torque_Nm,angle_rad,x\n" + "".join(f"{i},1,0,0\n" for i in range(12)),
    "non_numeric": "# test: stiffness\ntime_s,torque_Nm,angle_rad\n" + "".join(
        f"{i},{'abc' if i == 4 else 1},0\n" for i in range(12)),
    "nan": "# test: stiffness\ntime_s,torque_Nm,angle_rad\n" + "".join(
        f"{i},{'nan' if i == 4 else 1},0\n" for i in range(12)),
    "time_not_increasing": "# test: stiffness\ntime_s,torque_Nm,angle_rad\n" + "".join(
        f"{min(i, 5)},1,0\n" for i in range(12)),
    "too_few_rows": "# test: stiffness\ntime_s,torque_Nm,angle_rad\n" + "".join(f"{i},1,0\n" for i in range(9)),
    "unknown_test": "# test: stifness\ntime_s,torque_Nm,angle_rad\n" + "".join(f"{i},1,0\n" for i in range(12)),
    "no_test": "time_s,torque_Nm,angle_rad\n" + "".join(f"{i},1,0\n" for i in range(12)),
}


def run_main(args, tmp_path, capsys, monkeypatch):
    from hdsim.cli import main

    monkeypatch.chdir(tmp_path)
    code = main(list(args))
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("verb", ["fit", "diagnose"])
@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_cli_refuses_bad_files_with_one_line_and_writes_nothing(tmp_path, capsys, monkeypatch, verb, name):
    (tmp_path / "bad.csv").write_text(BAD_FILES[name])
    before = sorted(p.name for p in tmp_path.iterdir())
    args = [verb, "bad.csv", "--json"] + (["--report", "rep"] if verb == "diagnose" else [])
    code, out, err = run_main(args, tmp_path, capsys, monkeypatch)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "bad.csv" in lines[0] and "Traceback" not in err
    assert out == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_cli_bad_file_exit_status_from_the_console(tmp_path):
    (tmp_path / "bad.csv").write_text(BAD_FILES["nan"])
    out = run_cli("diagnose", "bad.csv", "--json", cwd=tmp_path)
    assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1 and out.stdout == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv"]


@pytest.mark.parametrize("args,text", [
    (["--effects", "fricton"], "did you mean friction"),
    (["--unit", "CSG-99-100"], "unknown unit"),
    (["--columns", "time=t"], "column map"),
])
def test_cli_refuses_bad_options(tmp_path, capsys, monkeypatch, args, text):
    (tmp_path / "ok.csv").write_text(BAD_FILES["too_few_rows"])
    code, out, err = run_main(["fit", "ok.csv", *args], tmp_path, capsys, monkeypatch)
    assert code == 2 and text in err and len(err.strip().splitlines()) == 1
