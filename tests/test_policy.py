"""The policy of a round, on hand-built candidate lists: no record, no fit.

Each row of `TABLE` is a round (its candidates, the other forms tried, the state of the
diagnosis) and the decision the rules of docs/tutorial-find-missing-effect.md ("How it
decides") call for, written from those rules, not from a run of the code.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from hdsim.identification.policy import (RoundState, Thresholds, decide_round, rate_question_left,
                                         wants_other_forms)
from hdsim.identification.selection import TWIST_THRESHOLDS

PARTNERS = {"damping": "friction", "friction": "damping"}


def cand(family, score, accepted=True, effect=None, folds=(0.2, 0.2), share=0.0):
    return SimpleNamespace(family=family, effect=effect or family, score=score, accepted=accepted,
                           holdout_gain=list(folds), share=share)


def state(current=(), one_rate=False, added=(), reshaped=(), explained=False, round_no=1):
    return RoundState(round_no=round_no, current={f: f for f in current}, added=tuple(added),
                      reshaped=tuple(reshaped), residual_explained=explained, one_rate=one_rate,
                      rate_partner=lambda f: PARTNERS.get(f, ""), separating=lambda a, b: f"separate {a}/{b}")


# (name, candidates, other forms or None, state, action, chosen family, ambiguous pairs as (families, added))
TABLE = [
    ("best passing is added", [cand("hardening", -300), cand("backlash", -100)], None, state(),
     "add", "hardening", []),
    ("an over-fit best does not hide a passing runner-up",
     [cand("hardening", -300, accepted=False), cand("backlash", -100)], None, state(), "add", "backlash", []),
    ("nothing passes: stop", [cand("hardening", -3, accepted=False)], None, state(), "stop", None, []),
    ("near tie is reported, the better added", [cand("hardening", -100), cand("backlash", -95)], None, state(),
     "add", "hardening", [(["hardening", "backlash"], True)]),
    ("10 % of a large score is the tie margin", [cand("hardening", -1000), cand("backlash", -905)], None, state(),
     "add", "hardening", [(["hardening", "backlash"], True)]),
    ("beyond the margin, no tie", [cand("hardening", -1000), cand("backlash", -850)], None, state(),
     "add", "hardening", []),
    ("another form that explains it better replaces the addition",
     [cand("damping", -50)], [cand("friction", -200, effect="distributed_slip")], state(current=["friction"]),
     "reshape", "friction", []),
    ("another form within the tie margin: the family is added, the pair named",
     [cand("hardening", -100)], [cand("friction", -105, effect="distributed_slip")], state(current=["friction"]),
     "add", "hardening", [(["hardening", "friction"], True)]),
    ("another form that fails does not replace anything",
     [cand("hardening", -100)], [cand("friction", -500, accepted=False)], state(current=["friction"]),
     "add", "hardening", []),
    ("nothing passes, a form does: it is taken",
     [cand("backlash", 3, accepted=False)], [cand("friction", -40, effect="distributed_slip")],
     state(current=["friction"]), "reshape", "friction", []),
    ("one rate, damping best, friction in the model: the pair, stop",
     [cand("damping", -300), cand("backlash", -20)], None, state(current=["friction"], one_rate=True),
     "stop", None, [(["damping", "friction"], False)]),
    ("one rate, damping and friction explain alike: the better stands in",
     [cand("damping", -300), cand("friction", -290), cand("backlash", 2, accepted=False)], None,
     state(one_rate=True), "stand_in", "damping", [(["damping", "friction"], False)]),
    ("one rate, friction far better than damping: added",
     [cand("friction", -300), cand("damping", -100)], None, state(one_rate=True), "add", "friction", []),
    ("two rates: damping beside friction is added", [cand("damping", -300)], None, state(current=["friction"]),
     "add", "damping", []),
    ("one rate, nothing passes, damping beside friction explains part: the pair's question",
     [cand("damping", -96, accepted=False, folds=(0.05, 0.03))], None,
     state(current=["friction"], one_rate=True), "stop", None, [(["damping", "friction"], False)]),
]


@pytest.mark.parametrize("name,ranked,reshapes,st,action,family,pairs", TABLE, ids=[row[0] for row in TABLE])
def test_decide_round(name, ranked, reshapes, st, action, family, pairs):
    d = decide_round(ranked, reshapes, st, TWIST_THRESHOLDS)
    assert d.action == action
    assert (d.chosen.family if d.chosen is not None else None) == family
    assert [(a["families"], a["added"]) for a in d.ambiguous] == pairs
    for a in d.ambiguous:
        assert a["round"] == st.round_no and a["measurement"].startswith("separate")


def test_other_forms_are_tried_with_a_passing_candidate_or_on_the_users_baseline():
    passing, failing = [cand("hardening", -100)], [cand("hardening", 5, accepted=False)]
    assert wants_other_forms(passing, True, state(added=["backlash"]))
    assert wants_other_forms(failing, True, state())                        # the user's baseline
    assert not wants_other_forms(failing, True, state(added=["backlash"]))  # past it
    assert not wants_other_forms(failing, True, state(explained=True))      # nothing left to explain
    assert not wants_other_forms(passing, False, state())                   # no other form exists


def test_ties_judged_by_share_when_the_kind_says_so():
    by_share = Thresholds(tie_share=0.05)
    a, b = cand("friction", -200, share=0.80), cand("ripple", -40, share=0.77)
    d = decide_round([a, b], None, state(), by_share)
    assert d.action == "add" and [x["families"] for x in d.ambiguous] == [["friction", "ripple"]]
    b.share = 0.6
    assert decide_round([a, b], None, state(), by_share).ambiguous == ()


def test_a_loss_left_beside_its_partner_at_one_rate_is_the_pairs_question():
    """Nothing passes, and the best-scored candidate is damping with friction in the model:
    with evidence (score below the threshold) and both hold-out folds better, the pair is
    the question left; without either, or with the partner absent, or another family
    best, there is none."""
    def left(ranked, current):
        return rate_question_left(ranked, state(current=current, one_rate=True), TWIST_THRESHOLDS)

    def c(family, score, folds=(0.05, 0.03)):
        return cand(family, score, accepted=False, folds=folds)

    assert left([c("damping", -96.0), c("backlash", 4.0)], ["friction", "hardening"]) == ("damping", "friction")
    assert left([c("friction", -40.0)], ["damping"]) == ("damping", "friction")
    assert left([c("damping", -96.0)], ["hardening"]) is None                     # no partner
    assert left([c("damping", -3.0)], ["friction"]) is None                       # no evidence
    assert left([c("damping", -96.0, (0.07, -0.02))], ["friction"]) is None      # one fold worse
    assert left([c("backlash", -50.0), c("damping", -40.0)], ["friction"]) is None
    assert left([], ["friction"]) is None
