"""The built-in scenario a study of an output runs when no scenario is named (docs/sensitivity.md §1).

An output has a default when the built-in scenarios settle it: one of the four tests a
manufacturer runs reports it (``lost_motion``, ``stiffness``, ``kinematic_error``,
``running_torque``: their contract run is the default of all their metrics, the
kinematic-error run's windup and orders too, which ``constant_speed`` and ``reversal``
also report), or exactly one built-in scenario does. The tracking metrics of the
controlled runs are reported by four built-ins, none of them a contract run: a study of one
is refused with their names, to pass as ``--scenario`` (``scenario=`` in Python).

The tables are written out, not found by running every built-in scenario (half a minute);
``tests/test_sensitivity_defaults.py`` runs them under ``-m slow`` and checks both.
"""

from __future__ import annotations

from hdsim.errors import InputError, unknown_name
from hdsim.sensitivity.problem import PYTHON_WORDING, Wording

#: the built-in scenario of each output that has one (see the module text)
METRIC_SCENARIOS = {
    "lost_motion_arcmin": "lost_motion",
    "torsion_at_rated_arcmin": "stiffness", "torsion_at_rated_tip_arcmin": "stiffness",
    "hysteresis_loss_arcmin": "stiffness", "lost_motion_centre_line_arcmin": "stiffness",
    "K1_Nm_per_rad": "stiffness", "K2_Nm_per_rad": "stiffness", "K3_Nm_per_rad": "stiffness",
    "transmission_accuracy_arcsec": "kinematic_error", "lost_motion_on_reversal_arcsec": "kinematic_error",
    "transmission_accuracy_forward_arcsec": "kinematic_error",
    "transmission_accuracy_reverse_arcsec": "kinematic_error",
    "windup_arcsec": "kinematic_error", "windup_load_Nm": "kinematic_error",
    "ke_order_1_arcsec": "kinematic_error", "ke_order_2_arcsec": "kinematic_error",
    "ke_order_4_arcsec": "kinematic_error", "ke_output_order_1_arcsec": "kinematic_error",
    # the input friction's (`input_friction.*`): a friction sweep, breakaway and efficiency
    "running_torque_forward_Nm": "running_torque", "running_torque_reverse_Nm": "running_torque",
    "starting_torque_mNm": "running_torque", "backdriving_torque_Nm": "running_torque",
    "efficiency_percent": "running_torque", "efficiency_speed_rpm": "running_torque",
    "running_torque_500rpm_mNm": "running_torque", "running_torque_1000rpm_mNm": "running_torque",
    "running_torque_2000rpm_mNm": "running_torque", "running_torque_3500rpm_mNm": "running_torque",
    # reported by one built-in scenario each
    "running_torque_mNm": "constant_speed", "running_speed_rpm": "constant_speed",
    "natural_frequency_1_Hz": "frequency_sweep", "damping_ratio_1": "frequency_sweep",
    "tangent_stiffness_Nm_per_rad": "frequency_sweep", "bode_magnitude_error_pct": "frequency_sweep",
    "bode_phase_error_deg": "frequency_sweep", "bode_compared_up_to_Hz": "frequency_sweep",
    "load_step_deflection_arcsec": "load_step", "load_step_peak_arcsec": "load_step",
    "load_step_settling_time_s": "load_step", "load_step_twist_arcsec": "load_step",
    "settling_time_s": "point_to_point", "dwell_error_p2p_arcsec": "point_to_point",
    "oscillation_gain": "sine_oscillation", "oscillation_phase_deg": "sine_oscillation",
    "oscillation_deviation_p2p_arcsec": "sine_oscillation",
}

#: outputs several built-in scenarios report, none of them a contract run: no default
SHARED_METRICS = {name: ("load_step", "point_to_point", "reversal", "sine_oscillation")
                  for name in ("max_following_error_arcsec", "final_error_arcsec", "max_wg_tracking_error_deg",
                               "peak_motor_torque_Nm")}

#: the outputs that had a default before the others: their study files record the default
#: scenario as None, named or not (`hdsim.sensitivity.models.from_unit`), and must resume
FIRST_DEFAULTS = frozenset({
    "lost_motion_arcmin", "torsion_at_rated_arcmin", "torsion_at_rated_tip_arcmin", "hysteresis_loss_arcmin",
    "lost_motion_centre_line_arcmin", "K1_Nm_per_rad", "K2_Nm_per_rad", "K3_Nm_per_rad",
    "transmission_accuracy_arcsec", "lost_motion_on_reversal_arcsec", "running_torque_forward_Nm",
    "running_torque_reverse_Nm", "starting_torque_mNm", "backdriving_torque_Nm", "efficiency_percent",
})


def default_scenario(output: str, wording: Wording = PYTHON_WORDING) -> str:
    """The built-in scenario a study of ``output`` runs when none is named.

    Parameters
    ----------
    output : str
        A metric, e.g. ``"windup_arcsec"``.
    wording : Wording
        How the refusal names the scenario option (``scenario=``, or ``--scenario``).

    Raises
    ------
    InputError
        For an output several built-in scenarios report (naming them, and the option that
        picks one) or none does (naming the close matches).
    """
    if output in METRIC_SCENARIOS:
        return METRIC_SCENARIOS[output]
    if output in SHARED_METRICS:
        names = SHARED_METRICS[output]
        raise InputError(f"output metric '{output}' is reported by the built-in scenarios {', '.join(names)}; "
                         f"name the one to run with {wording.scenario_of.format(name='NAME')}")
    unknown = unknown_name("output metric", output, [*METRIC_SCENARIOS, *SHARED_METRICS])
    raise InputError(f"{unknown} (a metric of a scenario of your own: "
                     f"{wording.scenario_of.format(name='FILE.toml')})")
