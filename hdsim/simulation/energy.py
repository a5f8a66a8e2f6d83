"""Energy balance of the driven bench: stored, supplied and dissipated energy.

A check of the equations of motion (docs/physics.md): without friction and damping the
drive conserves energy exactly, kinematic error included, and with them the dissipated
energy never decreases.
"""

from __future__ import annotations

import numpy as np

from hdsim.simulation.driven import sample_model
from hdsim.simulation.path import ElasticPath, ODESystem
from hdsim.simulation.solver import SimulationResult


def energy_balance(system: ODESystem, result: SimulationResult) -> dict[str, np.ndarray]:
    """Mechanical energy, work done on the drive and the energy dissipated [J], (M, nt) each.

    ``system`` must be built with ``track_energy=True``
    (`hdsim.simulation.driven.driven_wave_generator`), ``result`` its solution.
    ``dissipated = work_motor + work_load + work_ke − ΔE`` with
    ``E = ½ J_in ω_w² + ½ J_out ω_o² + V``, ``V`` the energy the elastic path stores
    (`ElasticPath.stored_energy`: the spring at its elastic twist and the dead zone's
    contact). Energy held by a friction element (presliding, end stops) counts as
    dissipated here, so a passive model gives ``dissipated ≥ 0`` at all times, and
    exactly 0 without losses.

    Returns
    -------
    dict
        ``energy``, ``kinetic``, ``potential``, ``work`` and ``dissipated`` [J].
    """
    J_in, J_out = system.J
    s = result.signals
    kinetic = 0.5 * np.asarray(J_in)[..., None] * s["wg_speed_rad_per_s"] ** 2 \
        + 0.5 * np.asarray(J_out)[..., None] * s["output_speed_rad_per_s"] ** 2
    twist = s["twist_rad"]
    potential = np.empty_like(twist)
    for m in range(twist.shape[0]):
        path = ElasticPath(sample_model(system.path.model, m))
        states = np.array([result.states[name][m] for name in path.states]).reshape(-1, twist.shape[1])
        potential[m] = path.stored_energy(twist[m], states)
    energy = kinetic + potential
    work = result.states["work_motor"] + result.states["work_load"] + result.states["work_ke"]
    return {"energy": energy, "kinetic": kinetic, "potential": potential, "work": work,
            "dissipated": work - (energy - energy[:, :1])}

