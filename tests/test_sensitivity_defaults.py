"""A study of an output that a built-in scenario reports runs that scenario when none is named
(docs/sensitivity.md §1), and an output several report is refused naming them and the option
that picks one (`hdsim.sensitivity.metric_scenarios`).

Before, only the fifteen outputs of the first table had a default: ``windup_arcsec``,
``ke_order_1_arcsec`` or ``natural_frequency_1_Hz`` were refused as unknown metrics, without
a word of ``--scenario``.
"""

from __future__ import annotations

import pytest

import hdsim
from hdsim.errors import InputError
from hdsim.sensitivity.models import from_unit
from hdsim.sensitivity.problem import PYTHON_WORDING
from hdsim.sensitivity.scenario_outputs import model_function

TRACKING_RUNS = "load_step, point_to_point, reversal, sine_oscillation"


@pytest.mark.parametrize("output, scenario", [
    ("windup_arcsec", "kinematic_error"), ("ke_order_1_arcsec", "kinematic_error"),
    ("transmission_accuracy_forward_arcsec", "kinematic_error"), ("running_torque_mNm", "constant_speed"),
    ("natural_frequency_1_Hz", "frequency_sweep"), ("settling_time_s", "point_to_point"),
    ("lost_motion_arcmin", "lost_motion"), ("transmission_accuracy_arcsec", "kinematic_error"),
])
def test_an_output_a_built_in_scenario_reports_runs_it(output, scenario):
    assert model_function("CSG-25-100", ["h_pz"], output).scenario.name == scenario


def test_an_output_several_built_in_scenarios_report_is_refused_naming_them_and_the_option(cli):
    code, out, err = cli("sobol", "--unit", "CSG-25-100", "--params", "h_pz", "--range", "10%",
                         "--output", "max_following_error_arcsec", "--n", "16")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and TRACKING_RUNS in err and "--scenario NAME" in err, err
    with pytest.raises(InputError, match=rf"{TRACKING_RUNS}; name the one to run with scenario='NAME'"):
        hdsim.sobol("CSG-25-100", ["h_pz"], "max_following_error_arcsec", n=16, workers=1)


def test_an_output_no_built_in_scenario_reports_names_the_close_ones_and_the_scenario_option(cli):
    code, _, err = cli("sobol", "--unit", "CSG-25-100", "--params", "h_pz", "--range", "10%",
                       "--output", "windup_arcsek", "--n", "16")
    assert code == 2 and "did you mean windup_arcsec" in err and "--scenario FILE.toml" in err, err


def test_a_new_default_is_recorded_by_name_whether_named_or_not():
    """Named or not, the same study (a resume of one started without --scenario with its
    default named is the same study); the outputs that had a default first keep None, as
    their files hold."""
    def recorded(output, scenario):
        return from_unit("CSG-25-100", ["h_pz"], output, scenario, 0.1, wording=PYTHON_WORDING)[3]["scenario"]

    assert recorded("windup_arcsec", None) == recorded("windup_arcsec", "kinematic_error") == "kinematic_error"
    assert recorded("lost_motion_arcmin", None) is recorded("lost_motion_arcmin", "lost_motion") is None


#: the tests a manufacturer runs: their contract run is the default of every metric it reports
CONTRACT_RUNS = ("lost_motion", "stiffness", "kinematic_error", "running_torque")


@pytest.mark.slow
def test_the_defaults_are_what_the_built_in_scenarios_report():
    """Every built-in scenario run on the default unit (half a minute): each metric's default
    is its contract run, else the one scenario reporting it; the others are shared."""
    from hdsim.scenarios.scenario import builtin_scenario_names
    from hdsim.sensitivity.metric_scenarios import METRIC_SCENARIOS, SHARED_METRICS

    reported: dict[str, list[str]] = {}
    drive = hdsim.load_unit("CSG-25-100")
    for name in builtin_scenario_names():
        for metric in hdsim.run_scenario(drive, name).metrics:
            reported.setdefault(metric, []).append(name)
    defaults, shared = {}, {}
    for metric, names in reported.items():
        contract = [name for name in names if name in CONTRACT_RUNS]
        assert len(contract) <= 1, (metric, contract)
        if contract or len(names) == 1:
            defaults[metric] = (contract or names)[0]
        else:
            shared[metric] = tuple(sorted(names))
    assert METRIC_SCENARIOS == defaults
    assert SHARED_METRICS == shared
