"""Scenario tables of the ``driven_wave_generator`` set-up (`hdsim.scenarios.driven.DRIVEN`).

Values are checked for type by `hdsim.scenarios.scenario`; their meaning and ranges by
`hdsim.scenarios.driven.bench_from_scenario`. Switches are strings (the scenario
schema has no booleans). See docs/tutorial-kinematic-error.md for every key.
"""

DRIVEN_SCHEMA = {
    "input": {
        "mode": str,                 # prescribed | pi
        "profile": str,              # hold | constant | reversal | trapezoid | sine | sweep | csv
        "speed_rpm": float,          # WG cruise speed (constant, reversal, trapezoid)
        "speeds_rpm": list,          # sweep: WG speeds, each run forward and back
        "revolutions": float,        # sweep: measured WG turns per cruise (settle_revolutions before them)
        "ramp_s": float,             # speed ramp time (cosine; linear for trapezoid)
        "output_revolutions": float,  # measured output revolutions at cruise (each way)
        "settle_revolutions": float,  # cruise travel before the measured part
        "dwell_s": float,            # standstill between moves / after a reversal
        "hold_s": float,             # duration of a hold profile (if the load does not set it)
        "move_deg": float,           # trapezoid: output move [deg]
        "return": str,               # trapezoid: "yes" moves back after the dwell
        "amplitude_deg": float,      # sine: output amplitude [deg]
        "frequency_Hz": float,       # sine
        "cycles": float,             # sine
        "csv": str,                  # csv: measured profile, path relative to the scenario file
    },
    "load": {
        "profile": str,              # none | constant | opposing | step | sweep | csv
        "torque": float,             # fraction of T_N (constant: signed; opposing: magnitude)
        "ramp_s": float,             # ramp-in of the initial load
        "step_time_s": float,
        "step_to": float,            # fraction of T_N after the step
        "rise_s": float,             # step rise time
        "sweep_amplitude": float,    # fraction of T_N
        "f_start_Hz": float,
        "f_stop_Hz": float,
        "sweep_s": float,
        "settle_s": float,           # rest at the preload before the sweep
        "tail_s": float,             # rest after the sweep (response decays)
        "smoothing": float,          # opposing: sign switch over this fraction of the cruise speed
        "inertia": float,            # load inertia added to the output [kg m^2]
    },
    "controller": {
        "bandwidth_Hz": float,       # speed-loop crossover
        "kp": float,                 # N m s/rad on WG speed error (overrides the tuning)
        "ki": float,                 # N m/rad on the integral of the WG speed error
        "feedforward": str,          # "yes" | "no": acceleration feedforward J_total * alpha_ref
        "position_loop": str,        # "yes" | "no": outer position loop (gain = crossover / 6)
        "position_gain_per_s": float,  # outer position-loop gain (overrides the tuning)
    },
    "input_friction": {
        "model": str,                # drive (default: the drive's law, the keys below on top) | catalog | none
        "starting_torque_Nm": float,
        "running_torque_Nm": float,  # no-load running torque at 2000 rpm input
        "coulomb_share": float,
        "stribeck_speed_rpm": float,
        "viscous_Nms": float,
        "ripple_orders": list,
        "ripple_amplitudes_of_level": list,  # fractions of the Coulomb level
        "ripple_amplitudes": list,   # the same (the law field's own name)
        "ripple_phases": list,
        "position_torque_orders": list,         # a torque that does not reverse with the motion (cogging)
        "position_torque_amplitudes_Nm": list,
        "position_torque_phases": list,
        "coulomb_asymmetry_Nm": float,  # forward level minus the mean level
        "load_coefficient": float,   # mesh loss per unit of transmitted torque (efficiency under load)
    },
    "efficiency": {
        "speed_rpm": float,          # WG speed of the efficiency run (default 2000, as the catalog)
        "load": float,               # brake torque, fraction of T_N (default 1: efficiency at rated torque)
        "revolutions": float,        # measured WG turns
    },
    "linearise": {
        "load": float,               # operating-point load, fraction of T_N
        "f_min_Hz": float,           # frequency-response check from here (default 1.5 x the sweep start)
        "compare_below": float,      # frequency-response check up to this fraction of the first resonance
    },
    "analysis": {
        "settle_band_arcsec": float,
        "orders": list,              # WG orders reported by the order spectrum (besides 1/N)
    },
    "output": {
        "samples_per_segment": int,  # accepted for compatibility; unused by this set-up
        "samples_per_wg_rev": int,
        "sample_rate_Hz": float,
    },
}

DRIVEN_REQUIRED = {"input": ("mode", "profile")}
