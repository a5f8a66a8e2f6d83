"""Diagnosis of running-torque tests (friction sweeps) on independent truth data.

The cases are those of ``validation/running_torque_battery.py`` (one definition of the
groups), on data from ``tests/truth_running.py``, which shares no code or law with hdsim.
The default run keeps three short records (<= 6,000 rows): nothing hidden, ripple hidden,
damping hidden. The battery with the issue's rates (each hidden family found first, and
nothing added when nothing is hidden, in >= 90 % of runs, 6 seeds per group) is
``-m slow``; it runs all groups once per session, in processes.
"""

from __future__ import annotations

import functools
import os

import pytest

import validation_scripts

SEEDS = tuple(range(6))  # >= 5 seeds per group, as the issue asks


def _battery():
    """validation/running_torque_battery.py as a module (loaded once per session)."""
    return validation_scripts.load("running_torque_battery")


def _explain(row: dict) -> str:
    return (f"{row['group']} seed {row['seed']}: added {row['added']}, ranking {row['ranking']}, "
            f"outcome {row['outcome']}, draws {row['draws']}, error {row['error']}")


# --------------------------------------------------------------------------- fast


# Seeds chosen for coverage, not ease: nothing (4) carries cogging and a temperature
# drift; ripple (6) is a modulated ripple of 16 % of F_c in an output-side file (torque
# and angle both on the output); damping (1) is a power law in a file with the WG angle only.
FAST_CASES = [("nothing", 4), ("ripple", 6), ("damping", 1)]


@pytest.mark.parametrize("group,seed", FAST_CASES)
def test_short_running_record_diagnosed(group, seed):
    row = _battery().run_case(group, seed, max_rows=6000)
    assert row["error"] is None, _explain(row)
    assert row["draws"]["rows"] <= 6000
    if row["hidden"]:
        assert row["ranking"][:1] == row["hidden"], _explain(row)
        assert row["added"][:1] == row["hidden"], _explain(row)
        assert set(row["added"]) <= set(row["hidden"]), _explain(row)
    else:
        assert row["added"] == [], _explain(row)


# --------------------------------------------------------------------------- battery (slow)


@functools.lru_cache(maxsize=None)
def _all_rows() -> tuple:
    """Every group on SEEDS, run once per session (processes: one per core, at most 4)."""
    battery = _battery()
    cases = [(g, s) for g in battery.GROUPS for s in SEEDS]
    workers = max(1, min(4, os.cpu_count() or 1))
    return tuple(battery.run_cases(cases, workers))


def _group(group: str) -> list[dict]:
    return [r for r in _all_rows() if r["group"] == group]


@pytest.mark.slow
@pytest.mark.parametrize("family", ["friction", "damping", "ripple"])
def test_battery_each_family_found_first(family):
    """Ranked first and added first in >= 90 % of the seeds."""
    rows = _group(family)
    assert len(rows) >= 5
    ok = [_battery().case_ok(r) for r in rows]
    assert sum(ok) / len(rows) >= 0.9, "\n".join(_explain(r) for r, k in zip(rows, ok) if not k)


@pytest.mark.slow
def test_battery_nothing_added_when_nothing_hidden():
    rows = _group("nothing")
    assert len(rows) >= 5
    bad = [r for r in rows if r["error"] or r["added"]]
    assert 1 - len(bad) / len(rows) >= 0.9, "\n".join(map(_explain, bad))


@pytest.mark.slow
@pytest.mark.parametrize("group", ["two:friction+damping", "two:friction+ripple", "two:damping+ripple"])
def test_battery_two_hidden_both_added(group):
    """Both hidden families added in >= 90 % (the issue's rate, applied to the pairs too)."""
    rows = _group(group)
    bad = [r for r in rows if not _battery().case_ok(r)]
    assert 1 - len(bad) / len(rows) >= 0.9, "\n".join(map(_explain, bad))


@pytest.mark.slow
def test_battery_criterion_met_and_no_case_raised():
    battery = _battery()
    table = battery.rates(list(_all_rows()))
    assert all(r["errors"] == 0 for r in table.values()), table
    assert battery.verdict(table)["met"], "\n".join(battery.summarise(list(_all_rows())))
