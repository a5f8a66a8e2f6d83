"""Quasi-static evaluator of the driven bench: the wave generator follows its profile, the
output inertia is a known load, the path is solved torque in, twist out.

Why (the same singular-perturbation argument as `hdsim.simulation.quasistatic`)
----------------------------------------------------------------------------------
With the wave generator prescribed (an ideally stiff servo), the output obeys::

    J ω̇_o = T_L − τ (1 − e_o),   ω_o = ω_w/N + q̇,   q = e + δ

(`hdsim.simulation.driven`). The kinematic error ``e`` excites the output at its orders of
the WG speed, tens of Hz in a catalog test, while the output's torsional mode sits at
hundreds: the ratio ``r = f/f_n`` is ~0.05. Split ``q̈ = ë + δ̈``. The rigid part
``J (α_w/N + ë)`` is known along the commanded motion and is kept as a load; what is
dropped is ``J δ̈``, the twist's own acceleration, which is ``r²`` of the inertial load and
``r⁴`` of the kinematic error. Then the torque through the path is known in time::

    τ(t) = (T_L − J (α_w/N + ë)) / (1 − e_o)

and the twist is the locked bench's quasi-static answer to it
(`hdsim.simulation.quasistatic.locked_twist`: every friction, damping, hardening and
backlash law, with its memory). A brake (`hdsim.simulation.loads.opposing_load`) is
applied at the output's kinematic speed ``ω_w/N + ė``: at cruise it is saturated and the
two agree; at a standstill the dynamic model lets the twist relax through the brake
(time constant ``c_b/K``), which this evaluator takes as instantaneous. The torque path
is the same monotone one either way, so the memory of a rate-independent friction law
ends in the same state and the measuring windows, after the settle travel, agree.

`criterion` states when all of this holds; docs/sensitivity.md ("Which evaluator") gives
the figures and the measured agreement with ``solve_ivp``.
"""

from __future__ import annotations

import numpy as np

from hdsim.model.drive import HarmonicDrive
from hdsim.model.input_friction import NO_INPUT_FRICTION
from hdsim.simulation.driven import Bench, sample_model, scalar_ratio
from hdsim.simulation.loads import per_sample
from hdsim.simulation.quasistatic import first_mode_period, locked_twist, sticking_tangent

#: the metric groups read in constant-speed windows, which this evaluator reproduces
#: (docs/sensitivity.md, "Which evaluator": transmission accuracy within 0.01 arcsec and lost motion on reversal
#: within 0.05 arcsec on the contract run)
QUASISTATIC_GROUPS = ("transmission_accuracy", "lost_motion_on_reversal", "windup", "order_spectrum")

#: the kinematic error's effective frequency ratio squared, ``(J/K) max|ë| / max|e|``, at
#: most this: the dropped twist acceleration is ``r⁴`` of the error, 1e-4 here
MAX_RIPPLE_RATIO = 1e-2

#: inside the measuring windows, the applied torque changes on a time scale
#: (``max|τ| / max|τ̇|``) of at least this many first-mode periods: a cosine ramp of
#: duration D has the time scale 2D/π, so this is the locked bench's 100 periods per ramp
#: (`hdsim.scenarios.locked.MIN_PERIODS_PER_RAMP`)
MIN_PERIODS_PER_CHANGE = 64.0

#: anywhere in the run, at least this many: a smooth change over ``D ≥ 10·(π/2)`` periods
#: leaves a residual vibration of at most ``1/(4 (D/T_n)² − 1) ≈ 1e-3`` of its step, which
#: the path's own losses (it must have some) take out during the settle travel
MIN_PERIODS_PER_CHANGE_OUTSIDE = 10.0

#: the friction's sticking stiffness (its path tangent at rest) at most this many times the
#: spring's: a stiffer presliding adds a mode the dynamic model resolves and its answer moves
#: with it (a Coulomb law at 43× drifts 3 arcsec over the contract run's reverse pass, a Dahl
#: law at 3× and a Coulomb law at 2× agree within 0.02 arcsec), while the quasi-static answer
#: does not depend on it
MAX_STICKING_RATIO = 10.0

#: a brake relaxes the twist with the time constant ``c_b/K``; each measuring window starts
#: at least this many of them after the speed last changed
MIN_RELAXATIONS_BEFORE_WINDOW = 20.0


#: the path is solved wherever the slow torque has moved by this share of T_N, and at
#: least every `MAX_GAP` samples (`step_grid`): ~700 steps instead of the contract run's
#: 26,000 samples. The gap matters more than the share: a Dahl-slip law ratchets a little
#: at each reversal of the kinematic error's inertial ripple, which steps 64 samples apart
#: see in part (windup 0.024 arcsec from solve_ivp; every sample: 0.015 arcsec, 13x slower)
STEP_OF_RATED = 2e-3
MAX_GAP = 64

#: Newton iterations per step before a step is bisected on its bracket: Newton crawls on a
#: Dahl-slip law near its slip limit (at 3000 rpm the contract run needs ~70 at one sample,
#: `hdsim.simulation.quasistatic._solve`); 200 lets it finish there, as when the studies'
#: figures were measured
MAX_ITER = 200


def _rigid_pass(model: HarmonicDrive, bench: Bench, t: np.ndarray) -> dict:
    """The commanded motion with the kinematic error and no twist: everything the path's
    torque needs, as arrays of shape (nt, M) (or (nt, 1) where no parameter enters)."""
    N = scalar_ratio(model)
    TN = per_sample(model.drive.rated_torque)
    motion, load = bench.motion, bench.load
    tt = t[:, None]
    th_w, w_w, a_w = motion.angle(tt), motion.speed(tt), motion.accel(tt)
    frac = load.torque(tt) / TN + 0.0 * tt  # the load the kinematic error follows, known in time
    frac_rate = load.rate(tt) / TN + 0.0 * tt
    ke = model.kinematic_error.displacement_and_partials
    e = 0.0
    for _ in range(2):  # θ_o = θ_w/N + e: the output-order terms see the error itself (e_o ~ 1e-4)
        e, e_w, e_o, e_f = ke(th_w, th_w / N + e, frac)
    e_rate = e_w * w_w + e_o * (w_w / N) + e_f * frac_rate + 0.0 * frac
    e_accel = np.gradient(e_rate, t, axis=0)
    w_o = w_w / N + e_rate
    a_o = a_w / N + e_accel
    T_L = load.torque(tt) + 0.0 * frac if load.at_output_speed is None else load.at_output_speed(w_o)
    J_out = per_sample(np.asarray(model.drive.J_out, dtype=float) + float(bench.load_inertia))
    torque = (T_L - J_out * a_o) / (1.0 - e_o)
    slow = T_L - J_out * a_w / N  # the load and the commanded motion's inertia, without the error's ripple
    return dict(th_w=th_w, w_w=w_w, a_w=a_w, frac=frac, e=e, e_w=e_w, e_o=e_o, e_accel=e_accel, T_L=T_L,
                torque=torque, slow=slow)


def step_grid(slow_torque: np.ndarray, step: float, max_gap: int) -> np.ndarray:
    """Sample indices to solve the path on: wherever the slow torque has moved by ``step``
    [N·m] since the last one (its total variation in steps), and at least every
    ``max_gap`` samples; the first and last sample always. A cruise at constant load
    needs few, a reversal as many as its torque swing asks."""
    travel = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(slow_torque)))])
    moved = np.flatnonzero(np.diff(np.floor(travel / step)) > 0) + 1
    every = np.arange(0, slow_torque.size, max_gap)
    return np.unique(np.concatenate([every, moved, [slow_torque.size - 1]]))


def _twist(model: HarmonicDrive, t: np.ndarray, torque: np.ndarray, slow: np.ndarray):
    """Twist (M, nt) and friction states of the path under ``torque`` (nt, M): one pass for a
    batch that shares its torque history, else one per parameter set.

    The path is solved on `step_grid` of the slow torque (the load and the commanded
    inertia); between its steps `locked_twist` moves the interpolated body twist by each
    sample's own torque, so the kinematic error's inertial ripple adds its elastic twist
    there (``J ë / K``, ~1e-8 rad) through the branch's compliance.
    """
    M = model.batch_size
    torque = np.broadcast_to(torque, (t.size, M))
    slow = np.broadcast_to(slow, (t.size, M))
    grid = step_grid(slow[:, 0], STEP_OF_RATED * float(np.max(model.drive.rated_torque)), MAX_GAP)
    options = dict(grid=grid, return_states=True, max_iter=MAX_ITER)
    shared = np.allclose(torque, torque[:, :1], rtol=1e-12, atol=0.0)
    if shared:
        twist, states = locked_twist(model, t, np.ascontiguousarray(torque[:, 0]), **options)
    else:
        parts = [locked_twist(sample_model(model, m), t, np.ascontiguousarray(torque[:, m]), **options)
                 for m in range(M)]
        twist = np.concatenate([p[0] for p in parts])
        states = np.concatenate([np.atleast_2d(p[1]) if np.ndim(p[1]) == 2 else p[1] for p in parts], axis=-2)
    return twist, states


def driven_signals(model: HarmonicDrive, bench: Bench, t: np.ndarray) -> dict:
    """The driven bench's signals with the twist's inertia dropped (module description).

    Parameters
    ----------
    model : HarmonicDrive
        Single or batch model with one transmission ratio.
    bench : Bench
        A bench in ``prescribed`` input mode.
    t : numpy.ndarray
        Output times [s] (`Bench.sample_times`).

    Returns
    -------
    dict
        The signals of `hdsim.simulation.driven.driven_wave_generator`, shape (M, nt).
    """
    N = scalar_ratio(model)
    M = model.batch_size
    rigid = _rigid_pass(model, bench, t)
    twist, states = _twist(model, t, rigid["torque"], rigid["slow"])
    delta = twist.T
    th_w, w_w = rigid["th_w"], rigid["w_w"]
    # the error at the output's actual angle, to first order: the twist moves the output by
    # ~1e-3 rad, and e_o δ is ~1e-7 of e (the second order, and δ's effect on e_w, far below)
    e = rigid["e"] + rigid["e_o"] * delta
    q = e + delta
    tau = rigid["torque"]
    wg_force = tau * (1.0 / N + rigid["e_w"])
    friction = bench.input_friction
    T_f = friction.torque(w_w, th_w, wg_force) if friction is not NO_INPUT_FRICTION else 0.0 * tau
    J_in = per_sample(model.drive.J_in)
    slip_states = np.moveaxis(np.asarray(states), -1, -2)  # (…, nt, M) as the path's states
    hysteretic = model.friction.series_slip(slip_states if slip_states.ndim == 3 else slip_states[None])
    signals = {
        "wg_angle_rad": th_w, "wg_speed_rad_per_s": w_w, "output_angle_rad": th_w / N + q,
        "output_speed_rad_per_s": w_w / N + np.gradient(q, t, axis=0), "deviation_rad": q,
        "ke_source_rad": e, "twist_rad": delta, "drive_torque_Nm": tau, "load_torque_Nm": rigid["T_L"],
        "motor_torque_Nm": J_in * rigid["a_w"] + T_f - wg_force, "input_friction_Nm": T_f,
        "reference_angle_rad": th_w, "reference_speed_rad_per_s": w_w, "hysteretic_twist_rad": hysteretic,
    }
    shape = (t.size, M)
    return {k: np.ascontiguousarray(np.broadcast_to(v, shape).T) for k, v in signals.items()}


def criterion(model: HarmonicDrive, bench: Bench):
    """Whether `driven_signals` reproduces the dynamic bench on ``bench`` (the driven
    `Setup.quasistatic_criterion`): ``(holds, reason, figures)``.

    It holds when the wave generator is prescribed, every metric group is read in
    constant-speed windows (`QUASISTATIC_GROUPS`), the kinematic error is slow against
    the first mode (`MAX_RIPPLE_RATIO`), the applied torque changes slowly
    (`MIN_PERIODS_PER_CHANGE`), and a brake has let the twist settle before each window
    (`MIN_RELAXATIONS_BEFORE_WINDOW`). Evaluated on ``model`` (the nominal drive of a study).
    """
    if bench.mode != "prescribed":
        return False, (f"input mode {bench.mode!r}: the motor loop is a dynamic system of its own; "
                       f"only a prescribed wave generator is quasi-static"), {}
    others = [g for g in bench.metrics if g not in QUASISTATIC_GROUPS]
    if others:
        return False, f"metric groups {others} are read outside constant-speed windows", {}
    t = bench.sample_times()
    rigid = _rigid_pass(model, bench, t)
    torque = rigid["torque"]
    inertia = np.asarray(model.drive.J_out, dtype=float) + float(bench.load_inertia)
    period = first_mode_period(model, np.max(np.abs(torque)), inertia)
    stiffness = float(np.min(inertia)) * (2.0 * np.pi / period) ** 2
    e = rigid["e"] + 0.0 * torque
    in_windows = np.zeros(t.size, dtype=bool)
    for a, b in bench.motion.windows.values():
        in_windows |= (t >= a) & (t <= b)
    e_span = float(np.max(np.abs(e[in_windows] - np.mean(e[in_windows], axis=0)))) if in_windows.any() else 0.0
    ripple = (float(np.max(inertia)) / stiffness * float(np.max(np.abs(rigid["e_accel"][in_windows])))
              / e_span) if e_span > 0.0 else 0.0
    slow = rigid["slow"]
    rate = np.abs(np.gradient(slow, t, axis=0))
    change = float(np.max(np.abs(slow))) / max(float(np.max(rate[in_windows])), 1e-300)
    change_outside = float(np.max(np.abs(slow))) / max(float(np.max(rate)), 1e-300)
    relax, settle = _brake_relaxation(bench, t, stiffness)
    figures = {"first_period_s": period, "ripple_ratio": ripple, "max_ripple_ratio": MAX_RIPPLE_RATIO,
               "periods_per_change_in_windows": change / period, "min_periods_per_change": MIN_PERIODS_PER_CHANGE,
               "periods_per_change": change_outside / period,
               "min_periods_per_change_outside": MIN_PERIODS_PER_CHANGE_OUTSIDE,
               "brake_relaxation_s": relax, "settle_before_window_s": settle}
    if model.friction.is_null and model.damping.is_null:
        return False, ("the path has neither friction nor damping: a vibration the run excites never decays, "
                       "and the quasi-static evaluator has none"), figures
    if not model.friction.driven_quasistatic:
        return False, (f"the friction law {model.friction.id!r} has not been shown to follow its dynamic form under "
                       f"the kinematic error's vibration (Friction.driven_quasistatic)"), figures
    sticking = _sticking_ratio(model)
    figures["sticking_ratio"] = sticking
    if sticking > MAX_STICKING_RATIO:
        return False, (f"the friction sticks with {sticking:.3g} times the spring's stiffness (above "
                       f"{MAX_STICKING_RATIO:g}): its presliding mode is not quasi-static"), figures
    if ripple > MAX_RIPPLE_RATIO:
        return False, (f"the kinematic error excites the output at (f/f_n)² = {ripple:.3g}, above "
                       f"{MAX_RIPPLE_RATIO:g}: the inertia matters"), figures
    for scale, least, where in ((change, MIN_PERIODS_PER_CHANGE, "in the measuring windows"),
                                (change_outside, MIN_PERIODS_PER_CHANGE_OUTSIDE, "in the run")):
        if scale < least * period:
            return False, (f"{where} the applied torque changes within {scale:.3g} s, {scale / period:.3g} periods "
                           f"of the first mode ({period:.3g} s), under {least:g}: the inertia matters"), figures
    if relax * MIN_RELAXATIONS_BEFORE_WINDOW > settle:
        return False, (f"the brake relaxes the twist in {relax:.3g} s, and a window starts {settle:.3g} s after the "
                       f"speed last changed (fewer than {MIN_RELAXATIONS_BEFORE_WINDOW:g} relaxations)"), figures
    return True, (f"the wave generator is prescribed, the kinematic error is slow against the first mode "
                  f"((f/f_n)² = {ripple:.2g}), the torque changes over {change_outside / period:.3g} periods or more "
                  f"and the metrics are read in constant-speed windows"), figures


def _sticking_ratio(model: HarmonicDrive) -> float:
    """The friction's path tangent at rest over the spring's base stiffness (largest of a batch)."""
    K, tangent = sticking_tangent(model)
    return float(np.max(tangent / K))


def _brake_relaxation(bench: Bench, t: np.ndarray, stiffness: float) -> tuple[float, float]:
    """(the brake's relaxation time ``c_b/K`` [s], the shortest time from the last change of
    speed to a window's start [s]); (0, inf) without a brake."""
    brake = bench.load.at_output_speed
    if brake is None:
        return 0.0, np.inf
    step = 1e-6 * max(float(bench.motion.max_speed), 1.0)
    slope = float(np.max(np.abs((np.asarray(brake(step)) - np.asarray(brake(-step))) / (2.0 * step))))
    speed = np.asarray(bench.motion.speed(t), dtype=float)
    settle = np.inf
    for a, _ in bench.motion.windows.values():
        k = int(np.searchsorted(t, a))
        cruise = speed[min(k, t.size - 1)]
        changed = np.flatnonzero(np.abs(speed[:k] - cruise) > 1e-3 * max(abs(cruise), 1e-12))
        settle = min(settle, a - (t[changed[-1]] if changed.size else t[0]))
    return slope / stiffness, float(settle)
