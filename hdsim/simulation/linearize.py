"""Linearisation of a bench system about an operating point, as a ``control.StateSpace``.

The Jacobians are central finite differences of the same right-hand side that
the simulator integrates, so the linear model is exactly the tangent of the
non-linear one (tested against a simulated free ring-down).
"""

from __future__ import annotations

from typing import Callable

import control
import numpy as np

from hdsim.simulation.path import ODESystem
from hdsim.errors import InputError


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

    ``build(u)`` returns the single-sample system with a constant input ``u``;
    ``outputs`` are state names (default: all states).
    """
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
    """Undamped natural frequencies [rad/s] and damping ratios of the oscillatory modes."""
    wn, zeta, poles = control.damp(sys, doprint=False)
    oscillatory = np.abs(np.imag(poles)) > 1e-9 * np.maximum(np.abs(poles), 1.0)
    wn, zeta = wn[oscillatory], zeta[oscillatory]
    order = np.argsort(wn)
    return wn[order][::2], zeta[order][::2]  # one entry per complex pair
