"""Wave generator driven: the drive in motion as an ODE system (set-up ``driven_wave_generator``).

The bench (or robot joint)::

    motor + WG (J_in) ─[WG-shaft friction T_f(ω_w, θ_w)]─ WG ═ mesh ═ flexspline (elastic path)
        ─ output + load (J_out + J_load) ─ load torque T_L(t)

Coordinates: WG angle ``θ_w``, output angle ``θ_o`` [rad]. The output is carried as its
**deviation** ``q = θ_o − θ_w/N`` (the kinematic error of docs/tutorial-kinematic-error.md):
it is arcseconds where θ_o is revolutions, so the solver's tolerances act on the
quantity the metrics read, not on a large angle.

The kinematic error ``e(θ_w, θ_o, T_L/T_N)`` of the model's ``kinematic_error`` slot is a
displacement source in the mesh; the elastic path (`hdsim.simulation.path.ElasticPath`,
with backlash, hardening, damping and friction states) sees the twist::

    δ = q − e,   δ̇ = q̇ − e_w ω_w − e_o ω_o − e_f ḟ        (e_x = ∂e/∂x, f = T_L/T_N)

and carries the torque ``τ = τ(δ, δ̇, z)``. Its generalised forces follow from virtual
work (the path stores V(δ)): ``−τ (1 − e_o)`` on the output and ``+τ (1/N + e_w)`` on the
WG shaft, so a conservative drive conserves energy exactly, kinematic error
included (the ``e_w``, ``e_o`` terms are the instantaneous ratio ripple; the plain
``−τ``, ``+τ/N`` are their e = 0 limit)::

    (J_out + J_load) ω̇_o = T_L(t, ω_o) − τ (1 − e_o)
    J_in ω̇_w             = T_m − T_f(ω_w, θ_w) + τ (1/N + e_w)

The WG-shaft friction (`hdsim.model.input_friction`) is the input-side loss; its
load-dependent term acts on the mesh torque ``τ (1/N + e_w)`` and sets the efficiency under
load. The
load-dependence of the kinematic error follows the load as a function of time
``T_L(t)`` (equal to the drive torque at steady state), which avoids an algebraic loop
between τ and e; a brake (`hdsim.simulation.loads.opposing_load`) applies its torque
at the output's actual speed, ``T_L(t)`` being its value along the commanded motion.

Input modes:

``prescribed``
    The motor follows the profile exactly (an ideally stiff servo): θ_w(t), ω_w(t),
    α_w(t) are known functions, not states. Chosen over a very stiff coupling because
    it is exact and adds no artificial fast mode; the motor torque that the profile
    needs (inverse dynamics, friction included) is an output signal.
    States: ``deviation``, ``deviation_rate``, path states.
``pi``
    Motor torque from a PI loop on the WG speed (`hdsim.simulation.controller.PIController`).
    States: ``theta_wg``, ``omega_wg``, ``deviation``, ``deviation_rate``,
    ``speed_error_integral``, path states.
``torque``
    Motor torque a given function of time (free vibration, breakaway tests).

All memory (friction, hysteresis, the PI integrator, optional work integrals) is ODE
state. SI throughout. The motion profiles are in `hdsim.simulation.motion`, the loads in
`hdsim.simulation.loads`; a scenario file becomes a `Bench` in `hdsim.scenarios.driven`.
"""

from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass
from typing import Callable

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.model.drive import HarmonicDrive
from hdsim.model.input_friction import NO_INPUT_FRICTION, InputFriction
from hdsim.simulation.controller import PIController
from hdsim.simulation.loads import NO_LOAD, Load, per_sample
from hdsim.simulation.motion import Motion
from hdsim.simulation.path import ElasticPath, ODESystem, pack_rates

SETUP = "driven_wave_generator"
#: what the bench's core computes at one time: angles, speeds, accelerations, load, kinematic
#: error, twist, torques, path rates, speed command, deviation and its rate. A named tuple, read
#: by name: a dict cost the right-hand side ~1.5 µs a call, this ~0.5 µs
BenchQuantities = namedtuple("BenchQuantities", ("th_w", "w_w", "acc_w", "th_o", "w_o", "acc_o", "T_L", "e", "e_f",
                                                 "frac_rate", "delta", "tau", "rates", "hyst", "T_m", "T_f",
                                                 "w_cmd", "q", "qd"))
TWO_PI = 2.0 * np.pi
#: input modes of `driven_wave_generator`
INPUT_MODES = ("prescribed", "pi", "torque")


def scalar_ratio(model: HarmonicDrive) -> float:
    """The transmission ratio N of a (batch) model; InputError if the batch has several."""
    ratio = np.atleast_1d(np.asarray(model.drive.ratio, dtype=float))
    if not np.allclose(ratio, ratio[0]):
        raise InputError("driven scenarios need one transmission ratio for the whole batch")
    return float(ratio[0])


def sample_model(model: HarmonicDrive, m: int) -> HarmonicDrive:
    """Sample ``m`` of a batch model as a single model.

    Parameters
    ----------
    model : HarmonicDrive
        A single or batch model.
    m : int
        Index of the sample.

    Returns
    -------
    HarmonicDrive
        The model itself if it is single.
    """
    if model.batch_size == 1:
        return model
    return model.with_updates({k: np.atleast_1d(v)[m] for k, v in model.params().items() if np.size(v) > 1})


def driven_wave_generator(model: HarmonicDrive, motion: Motion, load: Load = NO_LOAD, *,
                          mode: str = "prescribed", controller: PIController | None = None,
                          motor_torque: Callable | None = None,
                          input_friction: InputFriction = NO_INPUT_FRICTION, load_inertia: float = 0.0,
                          track_energy: bool = False) -> ODESystem:
    """The driven drive as an `hdsim.simulation.path.ODESystem` (batched, sample-major).

    Parameters
    ----------
    model : HarmonicDrive
        A single or batch model; the batch must share one transmission ratio.
    motion : Motion
        The prescribed WG motion (``mode="prescribed"``) or the speed loop's reference
        (``"pi"``); in ``"torque"`` mode only its start angle and speed are used.
    load : Load
        Load torque on the output.
    mode : str
        ``"prescribed"``, ``"pi"`` or ``"torque"`` (module description).
    controller : PIController, optional
        The speed loop, required in ``"pi"`` mode.
    motor_torque : callable, optional
        Motor torque [N·m] as a function of time [s], required in ``"torque"`` mode.
    input_friction : InputFriction
        WG-shaft friction (default: none).
    load_inertia : float
        Inertia added to the output [kg·m²].
    track_energy : bool
        Add the work integrals ``work_motor``, ``work_load`` and ``work_ke`` [J] (the last
        done by a time-varying, load-dependent kinematic error) as states, for
        `hdsim.simulation.energy.energy_balance`.

    Returns
    -------
    ODESystem
        States as listed in the module description; signals ``wg_angle_rad``,
        ``output_angle_rad``, ``deviation_rad``, ``twist_rad``, ``drive_torque_Nm``,
        ``load_torque_Nm``, ``motor_torque_Nm``, … of shape (M, nt). It also carries
        ``path`` (the `ElasticPath`) and ``J`` (J_in, J_out + J_load) [kg·m²].
    """
    if mode not in INPUT_MODES:
        raise unknown_name("input mode", mode, INPUT_MODES)
    if mode == "pi" and controller is None:
        raise InputError("input mode 'pi' needs a controller")
    if mode == "torque" and motor_torque is None:
        raise InputError("input mode 'torque' needs a motor torque function")
    path = ElasticPath(model)
    ke = model.kinematic_error.displacement_and_partials  # (e, ∂e/∂θ_w, ∂e/∂θ_o, ∂e/∂f)
    M = model.batch_size
    N = scalar_ratio(model)
    TN = per_sample(model.drive.rated_torque)
    J_in = per_sample(model.drive.J_in)
    J_out = per_sample(np.asarray(model.drive.J_out, dtype=float) + float(load_inertia))
    fr = input_friction
    friction_on = fr is not NO_INPUT_FRICTION
    prescribed = mode == "prescribed"

    mech = ("deviation", "deviation_rate") if prescribed else ("theta_wg", "omega_wg", "deviation",
                                                               "deviation_rate")
    extra = ("speed_error_integral",) if mode == "pi" else ()
    energy = ("work_motor", "work_load", "work_ke") if track_energy else ()
    names = mech + extra + path.states + energy
    n = len(names)
    iq = 0 if prescribed else 2
    i_fric = len(mech) + len(extra)
    n_fric = len(path.states)

    def core(t, x):
        """All quantities at time ``t`` for states ``x`` (sequence of arrays, (M,) or (nt, M)), as
        `BenchQuantities`."""
        if prescribed:
            th_w, w_w, a_ref = motion.at(t)
        else:
            th_w, w_w = x[0], x[1]
        q, qd = x[iq], x[iq + 1]
        th_o = th_w / N + q
        w_o = w_w / N + qd
        T_t, T_rate = load.at(t)  # the load as a function of time, which the kinematic error follows
        frac = T_t / TN
        e, e_w, e_o, e_f = ke(th_w, th_o, frac)
        frac_rate = T_rate / TN
        delta = q - e
        delta_rate = qd - e_w * w_w - e_o * w_o - e_f * frac_rate
        fstates = x[i_fric:i_fric + n_fric]
        tau, rates, hyst = path.evaluate(delta, delta_rate, fstates)
        out_force = tau * (1.0 - e_o)
        wg_force = tau * (1.0 / N + e_w)
        T_L = T_t if load.at_output_speed is None else load.at_output_speed(w_o)  # a brake: actual speed
        acc_o = (T_L - out_force) / J_out
        T_f = fr.torque(w_w, th_w, wg_force) if friction_on else 0.0 * w_w
        w_cmd = None
        if prescribed:
            acc_w = a_ref
            T_m = J_in * a_ref + T_f - wg_force
        else:
            if mode == "pi":
                ref_angle, ref_speed, ref_accel = motion.at(t)
                w_cmd = controller.command(ref_speed, ref_angle, th_w)
                T_m = (controller.kp * (w_cmd - w_w) + controller.ki * x[len(mech)]
                       + controller.feedforward_inertia * ref_accel)
            else:
                T_m = motor_torque(t) + 0.0 * w_w
            acc_w = (T_m - T_f + wg_force) / J_in
        return BenchQuantities(th_w, w_w, acc_w, th_o, w_o, acc_o, T_L, e, e_f, frac_rate, delta, tau, rates, hyst,
                               T_m, T_f, w_cmd, q, qd)

    def rhs(t, y):
        t = float(t)
        # one sample: Python floats through the laws (numpy on 1-element arrays costs ~4x)
        x = y.tolist() if M == 1 else y.reshape(M, n).T
        c = core(t, x)
        # the rates in the order of the states
        rate = [] if prescribed else [c.w_w, c.acc_w]
        rate += [c.qd, c.acc_o - c.acc_w / N]
        if mode == "pi":
            rate.append(c.w_cmd - c.w_w)
        rate += c.rates
        if track_energy:
            rate += [c.T_m * c.w_w, c.T_L * c.w_o, -c.tau * c.e_f * c.frac_rate]
        return pack_rates(rate, n, M)

    def outputs(t, states):
        tt = np.asarray(t, dtype=float)[:, None]
        x = [states[name].T for name in names]
        c = core(tt, x)
        shape = (len(t), M)
        signals = {
            "wg_angle_rad": c.th_w, "wg_speed_rad_per_s": c.w_w, "output_angle_rad": c.th_o,
            "output_speed_rad_per_s": c.w_o, "deviation_rad": c.q, "ke_source_rad": c.e,
            "twist_rad": c.delta, "drive_torque_Nm": c.tau, "load_torque_Nm": c.T_L,
            "motor_torque_Nm": c.T_m, "input_friction_Nm": c.T_f,
            "reference_angle_rad": motion.angle(tt), "reference_speed_rad_per_s": motion.speed(tt),
            "hysteretic_twist_rad": c.hyst,
        }
        return {k: np.ascontiguousarray(np.broadcast_to(v, shape).T) for k, v in signals.items()}

    # typical magnitudes for the absolute tolerances
    K = np.asarray(model.base_stiffness, dtype=float)
    theta_scale = float(np.max(1e-2 * TN / K))
    wn = float(np.max(np.sqrt(K / J_out)))
    speed_scale = max(float(motion.max_speed), 1.0)
    scales = {"theta_wg": TWO_PI, "omega_wg": speed_scale, "deviation": theta_scale,
              "deviation_rate": theta_scale * wn, "speed_error_integral": 1e-3,
              "work_motor": float(np.max(TN)) * theta_scale, "work_load": float(np.max(TN)) * theta_scale,
              "work_ke": float(np.max(TN)) * theta_scale}
    state_scales = np.array([scales.get(nm, 1e-2 * float(np.max(TN)) if nm.endswith("torque") else theta_scale)
                             for nm in names])

    # consistent start: WG at the profile's start, no twist (q = e), no friction memory
    y0 = np.zeros((M, n))
    th_w0 = float(motion.angle(0.0))
    w_w0 = float(motion.speed(0.0))
    if not prescribed:
        y0[:, 0], y0[:, 1] = th_w0, w_w0
    frac0 = np.broadcast_to(load.torque(0.0) / TN, (M,))
    e0, e_w0, e_o0, _ = ke(th_w0, th_w0 / N, frac0)
    y0[:, iq] = np.broadcast_to(e0, (M,))
    y0[:, iq + 1] = np.broadcast_to(e_w0 * w_w0 + e_o0 * w_w0 / N, (M,))
    system = ODESystem(SETUP, names, M, rhs, y0.ravel(), outputs, state_scales)
    system.path = path  # for hdsim.simulation.energy.energy_balance
    system.J = (J_in, J_out)
    return system


@dataclass
class Bench:
    """Everything a driven scenario asks for, in SI, for one (batch) model.

    Attributes
    ----------
    motion : Motion
        The WG motion (prescribed, or the speed loop's reference); its ``windows`` hold
        the load's windows too.
    load : Load
        Load torque on the output.
    mode : str
        Input mode, ``prescribed`` or ``pi``.
    controller : PIController or None
        The speed loop (``pi`` mode).
    input_friction : InputFriction
        WG-shaft friction.
    load_inertia : float
        Inertia added to the output [kg·m²].
    t_end : float
        End of the run [s].
    sample_rate : float
        Output sample rate [Hz].
    metrics : list
        The metric groups the scenario asks for.
    """

    motion: Motion
    load: Load
    mode: str
    controller: PIController | None
    input_friction: InputFriction
    load_inertia: float
    t_end: float
    sample_rate: float
    metrics: list

    def system(self, model, track_energy=False) -> ODESystem:
        """The ODE system of this bench for ``model`` (see `driven_wave_generator`)."""
        return driven_wave_generator(model, self.motion, self.load, mode=self.mode, controller=self.controller,
                                     input_friction=self.input_friction, load_inertia=self.load_inertia,
                                     track_energy=track_energy)

    def sample_times(self) -> np.ndarray:
        """Uniform output times [s] over the run at ``sample_rate``."""
        n = int(np.ceil(self.t_end * self.sample_rate)) + 1
        return np.linspace(0.0, self.t_end, n)
