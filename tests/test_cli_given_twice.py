"""An option value the command would drop is refused, as Python refuses it (docs/cli.md,
``hdsim simulate`` ``--set`` and ``hdsim sobol``).

Before: ``--set friction=none --set friction.slip_torque=3`` set the slip torque on the
friction it then switched off, and ran (Python's ``with_updates`` refuses the name on a drive
without friction); a ``--set``, ``--bounds`` or ``--dist`` name given twice kept its last
value without a word, where a parameter twice in ``--params`` was refused.
"""

from __future__ import annotations

import pytest

import hdsim
from hdsim.cli._common import apply_sets
from hdsim.errors import InputError

SWITCHED_OFF = "the same command switches friction to none, which has no parameter slip_torque"


@pytest.mark.parametrize("sets", [("friction=none", "friction.slip_torque=3"),
                                  ("friction.slip_torque=3", "friction=none")])
def test_a_parameter_of_an_effect_the_command_switches_off_is_refused_in_either_order(sets, cli, tmp_path):
    code, out, err = cli("simulate", "lost_motion", "--set", sets[0], "--set", sets[1], "--out", tmp_path / "o")
    assert code == 2 and out == "" and err.count("\n") == 1 and SWITCHED_OFF in err, err
    assert list(tmp_path.iterdir()) == []


def test_a_parameter_of_an_effect_still_on_is_set_beside_another_switched_off():
    model, _ = apply_sets(hdsim.load_unit("CSG-25-100"), None, {"backlash": "none", "friction.slip_torque": "0.5"})
    assert model.params()["friction.slip_torque"] == 0.5 and not any(k.startswith("backlash.") for k in model.params())


@pytest.mark.parametrize("args, message", [
    (["simulate", "lost_motion", "--set", "flexspline.h_c=0.6e-3", "--set", "flexspline.h_c=0.7e-3"],
     "--set flexspline.h_c is given twice (0.6e-3 and 0.7e-3); give it once"),
    (["sobol", "--unit", "CSG-25-100", "--params", "h_c", "--output", "lost_motion_arcmin", "--n", "16",
      "--bounds", "h_c=0.55e-3:0.7e-3", "--bounds", "h_c=0.5e-3:0.6e-3"],
     "--bounds h_c is given twice (0.55e-3:0.7e-3 and 0.5e-3:0.6e-3); give it once"),
    (["sobol", "--unit", "CSG-25-100", "--params", "h_c", "--output", "lost_motion_arcmin", "--n", "16",
      "--bounds", "h_c=0.55e-3:0.7e-3", "flexspline.h_c=0.5e-3:0.6e-3"],
     "--bounds names h_c twice (as h_c and flexspline.h_c); give it once"),
    (["sobol", "--unit", "CSG-25-100", "--params", "h_c", "--range", "10%", "--output", "lost_motion_arcmin",
      "--n", "16", "--dist", "h_c=unif", "--dist", "h_c=logunif"],
     "--dist h_c is given twice (unif and logunif); give it once"),
])
def test_a_name_given_twice_is_refused(args, message, cli, tmp_path):
    code, out, err = cli(*args, "--out", tmp_path / ("study.h5" if args[0] == "sobol" else "o"))
    assert code == 2 and out == "" and message in err and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []


def test_python_refuses_a_distribution_given_under_two_names_of_one_parameter():
    with pytest.raises(InputError, match=r"dists names h_c twice \(as h_c and flexspline.h_c\)"):
        hdsim.sobol("CSG-25-100", ["h_c"], "lost_motion_arcmin", n=16, workers=1,
                    dists={"h_c": "unif", "flexspline.h_c": "logunif"})
