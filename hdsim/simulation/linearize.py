"""Linearisation of a bench system about an operating point, as a ``control.StateSpace``.

The Jacobians are central finite differences of the same right-hand side that
the simulator integrates, so the linear model is exactly the tangent of the
non-linear one (checked against a simulated free ring-down, docs/physics.md). The
driven bench's linear model from load torque to output angle (`linear_model`) gives
its natural frequencies, damping ratios and tangent stiffness
(docs/tutorial-kinematic-error.md).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Callable

import numpy as np

from hdsim.errors import InputError
from hdsim.model.drive import HarmonicDrive
from hdsim.simulation.driven import Bench, driven_wave_generator, scalar_ratio
from hdsim.simulation.loads import constant_load, ramped_load
from hdsim.simulation.motion import hold_motion
from hdsim.simulation.path import ODESystem
from hdsim.simulation.solver import SolverOptions, integrate

# python-control is imported inside the functions that use it: importing it takes about
# a second and imports matplotlib.pyplot, which would switch the backend of a user's session
if TYPE_CHECKING:
    import control

TWO_PI = 2.0 * np.pi


def _central_jacobian(f, x0, steps):
    columns = []
    for i, h in enumerate(steps):
        dx = np.zeros_like(x0)
        dx[i] = h
        columns.append((f(x0 + dx) - f(x0 - dx)) / (2.0 * h))
    return np.column_stack(columns)


def linearize(build: Callable[[float], ODESystem], x_op, u_op: float, outputs=None,
              input_name: str = "torque_Nm", input_scale: float = 1.0) -> control.StateSpace:
    """Linear model ``dx = A dx + B du, dy = C dx`` about ``(x_op, u_op)``.

    Parameters
    ----------
    build : callable
        ``build(u)`` returns the single-sample system with the constant input ``u``.
    x_op : array_like, shape (n,)
        Operating state (SI, in the order of the system's states).
    u_op : float
        Operating input (the unit of ``input_name``).
    outputs : list of str, optional
        State names that are outputs (default: all states).
    input_name : str
        Name of the input signal.
    input_scale : float
        Typical size of the input; the finite-difference step is 1e-6 of it at least.

    Returns
    -------
    control.StateSpace
        The linear model; '.' in state names becomes '_' (python-control reserves it).
    """
    import control

    system = build(u_op)
    if system.batch != 1:
        raise InputError("linearisation needs a single model, not a batch")
    x_op = np.asarray(x_op, dtype=float)
    names = list(system.state_names)
    steps = 1e-6 * np.maximum(np.abs(x_op), system.state_scales)
    A = _central_jacobian(lambda x: system.rhs(0.0, x), x_op, steps)
    du = 1e-6 * max(abs(u_op), input_scale)
    B = ((build(u_op + du).rhs(0.0, x_op) - build(u_op - du).rhs(0.0, x_op)) / (2.0 * du))[:, None]
    outputs = list(outputs or names)
    unknown = [o for o in outputs if o not in names]
    if unknown:
        raise InputError(f"unknown output state(s) {unknown}; states are {names}")
    C = np.zeros((len(outputs), len(names)))
    for row, name in enumerate(outputs):
        C[row, names.index(name)] = 1.0
    # python-control refuses '.' in signal names (it reserves it for subsystem paths)
    safe = lambda label: label.replace(".", "_")  # noqa: E731
    return control.ss(A, B, C, np.zeros((len(outputs), 1)), states=[safe(n) for n in names],
                      inputs=[input_name], outputs=[safe(o) for o in outputs])


def natural_frequencies(sys: control.StateSpace):
    """Undamped natural frequencies and damping ratios of the oscillatory modes.

    Parameters
    ----------
    sys : control.StateSpace
        A linear model.

    Returns
    -------
    tuple of numpy.ndarray
        Natural frequencies [rad/s], ascending, and damping ratios [-]: one entry per
        complex pole pair.
    """
    import control

    wn, zeta, poles = control.damp(sys, doprint=False)
    oscillatory = np.abs(np.imag(poles)) > 1e-9 * np.maximum(np.abs(poles), 1.0)
    wn, zeta = wn[oscillatory], zeta[oscillatory]
    order = np.argsort(wn)
    return wn[order][::2], zeta[order][::2]  # one entry per complex pair


def operating_point(model: HarmonicDrive, bench: Bench, load_fraction, settle_s: float = 0.3) -> np.ndarray:
    """State of the driven bench at rest under a constant load, with the WG held.

    The load is ramped in, the drive settles, the end state is taken.

    Parameters
    ----------
    model : HarmonicDrive
        A single or batch model.
    bench : Bench
        Input mode, controller, input friction and load inertia of the bench.
    load_fraction : float
        Load as a fraction of the rated torque T_N.
    settle_s : float
        Simulated time [s]; the load ramps in over the first 30 %.

    Returns
    -------
    numpy.ndarray, shape (M, n)
        The states, in the order of the system's ``state_names``.
    """
    TN = np.asarray(model.drive.rated_torque, dtype=float)
    hold = hold_motion(settle_s)
    system = driven_wave_generator(model, hold, ramped_load(load_fraction * TN, 0.3 * settle_s),
                                   mode=bench.mode, controller=bench.controller,
                                   input_friction=bench.input_friction, load_inertia=bench.load_inertia)
    result = integrate(system, (0.0, settle_s), np.array([0.0, settle_s]), SolverOptions(rtol=1e-8,
                                                                                        atol_scale=1e-8))
    return np.array([result.states[name][:, -1] for name in system.state_names]).T  # (M, n)


def linear_model(model: HarmonicDrive, bench: Bench, load_fraction: float, x_op=None) -> control.StateSpace:
    """The driven bench linearised about a standstill operating point.

    Built by `linearize` on the same right-hand side the simulator integrates, so the
    tangent stiffness at the operating point is in it.

    Parameters
    ----------
    model : HarmonicDrive
        A single model.
    bench : Bench
        Input mode, controller, input friction and load inertia of the bench.
    load_fraction : float
        Load at the operating point, as a fraction of the rated torque T_N.
    x_op : array_like, optional
        The operating state; default `operating_point`.

    Returns
    -------
    control.StateSpace
        Input ``load_torque_Nm`` [N·m]; outputs ``output_angle`` [rad] (= θ_w/N + q; in
        prescribed mode the WG is held, so it is the deviation) and, for a free WG,
        ``wg_angle`` [rad].
    """
    import control

    if model.batch_size != 1:
        raise InputError("linearisation needs a single model, not a batch")
    TN = float(model.drive.rated_torque)
    if x_op is None:
        x_op = operating_point(model, bench, load_fraction)[0]
    hold = hold_motion(1.0)

    def build(u):  # linearize renames friction.slip → friction_slip for python-control
        return driven_wave_generator(model, hold, constant_load(u), mode=bench.mode,
                                     controller=bench.controller, input_friction=bench.input_friction,
                                     load_inertia=bench.load_inertia)

    full = linearize(build, x_op, load_fraction * TN, input_name="load_torque_Nm", input_scale=TN)
    names = list(full.state_labels)
    N = scalar_ratio(model)
    C = np.zeros((1 if bench.mode == "prescribed" else 2, len(names)))
    C[0, names.index("deviation")] = 1.0
    outputs = ["output_angle"]
    if bench.mode != "prescribed":
        C[0, names.index("theta_wg")] = 1.0 / N
        C[1, names.index("theta_wg")] = 1.0
        outputs.append("wg_angle")
    return control.ss(full.A, full.B, C, np.zeros((C.shape[0], 1)), states=names, inputs=["load_torque_Nm"],
                      outputs=outputs)


def linear_summary(sys: control.StateSpace) -> dict:
    """Natural frequencies and damping ratios of a linear bench model, and its stiffness.

    The quasi-static stiffness at the output is 1/|H| a thousand times below the lowest
    mode (a neutral micro-slip mode the load cannot excite makes ``dcgain``
    ill-conditioned). For the drive's own tangent stiffness use a ``prescribed`` (WG
    held) model, as `drive_tangent_stiffness` does; in ``pi`` mode this value includes
    the servo.

    Parameters
    ----------
    sys : control.StateSpace
        A model from `linear_model` (first input to first output is used).

    Returns
    -------
    dict
        ``natural_frequencies_Hz`` and ``damping_ratios`` of the oscillatory modes, lowest
        first, and ``tangent_stiffness`` [N·m/rad].
    """
    import control

    wn, zeta = natural_frequencies(sys)
    w_low = 1e-3 * (wn[0] if len(wn) else 1.0)
    H = np.asarray(control.frequency_response(sys[0, 0], [w_low]).complex).reshape(-1)[0]
    return {"natural_frequencies_Hz": wn / TWO_PI, "damping_ratios": zeta,
            "tangent_stiffness": 1.0 / abs(H) if H else np.inf}


def drive_tangent_stiffness(model: HarmonicDrive, bench: Bench, load_fraction: float) -> float:
    """Tangent stiffness of the drive [N·m/rad] with the WG held, whatever the bench's input mode.

    Spring, micro-slip and backlash in series, at ``load_fraction`` × T_N; ``model`` is a
    single model.
    """
    held = replace(bench, mode="prescribed", controller=None)
    return linear_summary(linear_model(model, held, load_fraction))["tangent_stiffness"]
