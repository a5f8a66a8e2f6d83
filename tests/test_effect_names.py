"""The effects a fit or a diagnosis is given are checked the same way whatever form they take
(text, list, {family: effect id}) and whichever call takes them (`hdsim.fit`, `hdsim.diagnose`),
before the record is examined, in the library's words rather than the command line's.

Before, a dict with a misspelt family was fitted as the bare model by `hdsim.fit` (the
string form and `hdsim.diagnose` refused it); a family of another test was fitted as nothing
(``kinematic_error`` on a stiffness record) or called unknown (``ripple``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hdsim
from hdsim.errors import InputError
from hdsim.identification.fit import fit as fit_model, parse_effects
from hdsim.io.measurement import make_measurement

EXAMPLE = Path(__file__).parent / "data" / "stiffness_example.csv"


@pytest.fixture(scope="module")
def stiffness():
    return hdsim.load_measurement(EXAMPLE)


@pytest.mark.parametrize("effects", ["frictoin", ["frictoin"], {"frictoin": "dahl"}, {"frictoin": None}])
def test_a_misspelt_family_is_refused_in_every_form_by_fit_and_diagnose(stiffness, effects):
    for call in (hdsim.fit, hdsim.diagnose, fit_model):
        with pytest.raises(InputError, match=r"^unknown effect family (or effect id )?'frictoin'; did you mean "
                                             r"friction\?$"):
            call(stiffness, effects)


def test_a_dict_is_read_as_family_equals_id():
    assert parse_effects({"friction": "dahl", "hardening": None}) == parse_effects("hardening,friction=dahl")
    assert parse_effects({"friction": "none"}) == {}
    with pytest.raises(InputError, match="unknown friction effect 'dhal'; did you mean dahl"):
        parse_effects({"friction": "dhal"})


def _running(test="running_torque"):
    t = np.arange(0.0, 1.0, 1e-3)
    return make_measurement(test, t, np.full(t.size, 0.05), None, wg_angle=10.0 * t, ratio=100.0)


@pytest.mark.parametrize("test, effects, family", [
    ("stiffness", "kinematic_error", "kinematic_error"), ("stiffness", "fourier", "kinematic_error"),
    ("stiffness", "ripple", "ripple"), ("stiffness", {"ripple": "position_torque"}, "ripple"),
    ("running_torque", "friction,hardening", "hardening"), ("breakaway", ["damping"], "damping")])
def test_a_family_the_test_cannot_show_is_refused_as_diagnose_families_refuses_it(stiffness, test, effects, family):
    meas = stiffness if test == "stiffness" else _running(test)
    with pytest.raises(InputError) as given:
        hdsim.diagnose(meas, families=[family])
    expected = str(given.value)
    assert expected.startswith(f"a {test} test cannot show the {family} family; it shows ")
    for call in (hdsim.fit, hdsim.diagnose):
        with pytest.raises(InputError) as info:
            call(meas, effects)
        assert str(info.value) == expected


def test_two_effects_of_one_family_are_refused_in_python_words(stiffness, cli, tmp_path):
    for effects in ("dahl,maxwell_slip", ["dahl", "friction=maxwell_slip"]):
        with pytest.raises(InputError, match=r"^the effects name two friction effects, dahl and maxwell_slip; give "
                                             r"one per family$"):
            hdsim.fit(stiffness, effects)
    code, _, err = cli("fit", EXAMPLE, "--effects", "dahl,maxwell_slip", cwd=tmp_path)
    assert code == 2 and "name two friction effects, dahl and maxwell_slip" in err and "Traceback" not in err


def test_diagnose_reads_a_dicts_forms_and_a_families_effect_ids_as_fit_does(stiffness, monkeypatch):
    """A dict's form reached hdsim.diagnose unparsed ({"friction": None} was a raw TypeError,
    {"friction": "none"} a baseline friction, "dhal" refused only after the record was
    examined); `families` took an effect id ("dahl") as a family of another test."""
    from hdsim.identification import workflow

    def examined(*args, **kwargs):
        raise AssertionError("the record was examined before the effects were checked")

    with monkeypatch.context() as patch:
        patch.setattr(workflow, "prepare_record", examined)
        with pytest.raises(InputError, match="unknown friction effect 'dhal'; did you mean dahl"):
            hdsim.diagnose(stiffness, {"friction": "dhal"})
    d = hdsim.diagnose(stiffness, {"friction": "none"}, max_rounds=1)
    assert d.to_json()["baseline"]["effects"] == []
    assert hdsim.diagnose(stiffness, families=["dahl"], max_rounds=1).to_json()["ranking"][0]["family"] == "friction"
