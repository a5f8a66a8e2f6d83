"""Efficiency of the driven bench: output power over input power at constant speed under load.

Measured as a catalog does (docs/physics.md, running torque): the wave generator turns
at constant speed against a brake on the output and the efficiency is the mean output
power over the mean motor power over whole WG revolutions, after the start-up has died
away,

    η = −⟨T_L ω_o⟩ / ⟨T_m ω_w⟩.

Every loss of the model is in it: the WG-shaft friction and its mesh (load) term
(`hdsim.model.input_friction`), and the hysteresis of the elastic path.
"""

from __future__ import annotations

import numpy as np

from hdsim.model.drive import HarmonicDrive
from hdsim.model.input_friction import InputFriction
from hdsim.simulation.driven import driven_wave_generator, per_sample, scalar_ratio
from hdsim.simulation.loads import opposing_load
from hdsim.simulation.motion import constant_speed_motion
from hdsim.simulation.solver import SolverOptions, integrate

TWO_PI = 2.0 * np.pi
#: WG turns before the measured ones (the brake ramps in, the elastic path winds up)
SETTLE_TURNS = 2.0
#: solver steps per WG revolution (the ripple of the law is at 1x, 2x and 4x)
STEPS_PER_TURN = 64


def efficiency(model: HarmonicDrive, friction: InputFriction, speed: float, load_fraction: float = 1.0,
               revolutions: float = 4.0, ramp_s: float = 0.05) -> np.ndarray:
    """Efficiency at constant WG speed against a brake of ``load_fraction`` T_N, per sample.

    Parameters
    ----------
    model : HarmonicDrive
        A single or batch model.
    friction : InputFriction
        The WG-shaft friction.
    speed : float
        WG speed [rad/s], non-zero.
    load_fraction : float
        Brake torque as a fraction of the rated torque [-].
    revolutions : float
        Measured WG turns [-].
    ramp_s : float
        Speed ramp [s].

    Returns
    -------
    numpy.ndarray, shape (M,)
        Efficiency [-].
    """
    N = scalar_ratio(model)
    motion = constant_speed_motion(speed, N, ramp_s, revolutions / abs(N), SETTLE_TURNS / abs(N))
    TN = per_sample(model.drive.rated_torque)
    load = opposing_load(abs(load_fraction) * TN, motion, 0.05 * abs(speed), N)
    system = driven_wave_generator(model, motion, load, mode="prescribed", input_friction=friction)
    t_end = motion.t_end
    t0, t1 = motion.windows["constant"]
    t = np.linspace(t0, t1, int(STEPS_PER_TURN * revolutions) + 1)
    options = SolverOptions(rtol=1e-5, max_step=TWO_PI / (STEPS_PER_TURN * abs(speed)))
    result = integrate(system, (0.0, t_end), t, options)
    s = result.signals
    p_out = -np.trapezoid(s["load_torque_Nm"] * s["output_speed_rad_per_s"], t, axis=1)
    p_in = np.trapezoid(s["motor_torque_Nm"] * s["wg_speed_rad_per_s"], t, axis=1)
    return p_out / p_in
