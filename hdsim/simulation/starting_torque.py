"""Starting torque of the driven bench: the motor torque at which the WG breaks away.

Measured as on a test bench: the unloaded drive is driven by a slowly rising motor
torque and breakaway is read where the WG starts to turn (docs/tutorial-kinematic-error.md).
"""

from __future__ import annotations

import numpy as np

from hdsim.model.drive import HarmonicDrive
from hdsim.model.input_friction import InputFriction
from hdsim.simulation.driven import driven_wave_generator
from hdsim.simulation.loads import NO_LOAD
from hdsim.simulation.motion import hold_motion
from hdsim.simulation.solver import SolverOptions, integrate
from hdsim.units import rpm_to_rad_per_s


def starting_torque(model: HarmonicDrive, friction: InputFriction, ramp_rate: float | None = None,
                    threshold_rpm: float = 1.0) -> np.ndarray:
    """Motor torque at which the WG breaks away, per sample, from a slow torque ramp.

    Parameters
    ----------
    model : HarmonicDrive
        A single or batch model, unloaded.
    friction : InputFriction
        The WG-shaft friction.
    ramp_rate : float, optional
        Rise of the motor torque [N·m/s]; default: the friction's starting torque per 0.5 s.
    threshold_rpm : float
        WG speed [rpm] that counts as turning.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Starting torque [N·m] (NaN where the WG did not break away; 0 without friction).
    """
    F = float(friction.starting_torque)
    if F == 0.0:
        return np.zeros(model.batch_size)
    rate = ramp_rate or 2.0 * F
    t_end = 1.5 * F / rate
    hold = hold_motion(t_end)
    system = driven_wave_generator(model, hold, NO_LOAD, mode="torque", motor_torque=lambda t: rate * t,
                                   input_friction=friction)
    t = np.linspace(0.0, t_end, 3001)
    result = integrate(system, (0.0, t_end), t, SolverOptions(rtol=1e-7, atol_scale=1e-7))
    w = result.states["omega_wg"]
    out = np.full(w.shape[0], np.nan)
    for m in range(w.shape[0]):
        above = np.flatnonzero(np.abs(w[m]) > rpm_to_rad_per_s(threshold_rpm))
        if above.size:
            out[m] = rate * t[above[0]]
    return out
