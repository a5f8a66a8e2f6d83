"""The effects a fit or a diagnosis is given are checked the same way whatever form they take
(text, list, {family: effect id}) and whichever call takes them (`hdsim.fit`, `hdsim.diagnose`),
before the record is examined, in the library's words rather than the command line's.

Before, a dict with a misspelt family was fitted as the bare model by `hdsim.fit` (the
string form and `hdsim.diagnose` refused it).
"""

from __future__ import annotations

from pathlib import Path

import pytest

import hdsim
from hdsim.errors import InputError
from hdsim.identification.fit import fit as fit_model, parse_effects

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
