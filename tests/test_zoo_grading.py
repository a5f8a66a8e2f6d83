"""How ``validation/zoo_battery.py`` grades a run, on runs written by hand.

The expected shares are counted by hand from the rows below, not produced by the
grader: a family the truth holds as a minor part (the viscous part of Coulomb +
viscous friction) is not a spurious addition, but is one in the strict share; a
two-hidden run whose missed family was reported with its partner as the one-rate
damping/friction pair is left out of ``both|dec`` and kept in ``both``.
"""

from __future__ import annotations

import pytest

import validation_scripts


@pytest.fixture(scope="module")
def zb():
    return validation_scripts.load("zoo_battery")


def run(group, hidden, added, *, secondary=None, ambiguous=(), ranking=None, outcome="improved"):
    return {"group": group, "seed": 0, "profile": "one_rate", "hidden": {f: "x" for f in hidden},
            "added": list(added), "ranking": list(ranking if ranking is not None else added),
            "ambiguous": [list(p) for p in ambiguous], "outcome": outcome, "secondary": secondary or {},
            "error": None, "seconds": 1.0}


VISCOUS = {"damping": "viscous part of coulomb_viscous"}


def test_a_minor_part_of_the_truth_is_not_spurious_but_counts_in_the_strict_share(zb):
    rows = [run("single:friction:coulomb_viscous", ["friction"], ["friction", "damping"], secondary=VISCOUS),
            run("single:friction:lugre", ["friction"], ["friction", "hardening"]),
            run("nothing:hardening+friction", [], ["damping"], secondary=VISCOUS),
            run("nothing:linear", [], [])]
    r = zb.rates(rows)
    assert r["spurious"] == pytest.approx(1 / 4)  # the hardening beside LuGre
    assert r["spurious_strict"] == pytest.approx(3 / 4)
    assert r["secondary"] == pytest.approx(2 / 4)
    nothing = zb.rates(rows[2:])
    assert nothing["nothing_added"] == pytest.approx(1.0)
    assert nothing["nothing_added_strict"] == pytest.approx(1 / 2)


def test_a_missed_family_flagged_as_the_one_rate_pair_leaves_both_decided(zb):
    rows = [run("two:hardening+damping", ["hardening", "damping"], ["hardening"],
                ambiguous=[("damping", "friction")]),                              # flagged: left out
            run("two:friction+damping", ["friction", "damping"], ["friction"]),    # plain miss
            run("two:hardening+backlash", ["hardening", "backlash"], ["hardening"],
                ambiguous=[("backlash", "hardening")]),                            # not the rate pair
            run("two:backlash+friction", ["backlash", "friction"], ["friction", "backlash"])]
    r = zb.rates(rows)
    assert r["both"] == pytest.approx(1 / 4)
    assert r["both_decided"] == pytest.approx(1 / 3)
    v = zb.verdict(rows)
    assert v["both_added"]["value"] == pytest.approx(1 / 3)
    assert v["both_added"]["raw"] == pytest.approx(1 / 4)
    assert not v["both_added"]["met"]


def test_the_verdict_grades_spurious_additions_against_the_truth(zb):
    rows = [run("single:friction:coulomb_viscous", ["friction"], ["friction", "damping"], secondary=VISCOUS)
            for _ in range(19)] + [run("single:friction:lugre", ["friction"], ["friction", "hardening"])]
    v = zb.verdict(rows)
    assert v["spurious"]["value"] == pytest.approx(1 / 20)
    assert v["spurious"]["strict"] == pytest.approx(1.0)
    assert v["spurious"]["met"]
