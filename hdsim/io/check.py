"""The record of one check of a measurement before any fit.

Its own module because both kinds of checks build it: the locked and kinematic-error
checks (`hdsim.io.data_checks`, which also dispatches) and the running-torque checks
(`hdsim.io.running_checks`), so the dispatch can import the running checks without the
running checks importing it back.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Check", "constant_torque"]


@dataclass(frozen=True)
class Check:
    """One data check: ``check`` (its name), ``status`` (ok, warn, fail) and ``message``."""

    check: str
    status: str
    message: str

    def to_json(self) -> dict:
        return {"check": self.check, "status": self.status, "message": self.message}


def constant_torque(value: float) -> Check:
    """The ``torque_varies`` failure of a record whose torque is ``value`` [N·m] on every row
    (a locked test's, a sweep's, a breakaway's: each must vary its torque)."""
    return Check("torque_varies", "fail", f"the torque is {float(value):.6g} N·m on every row: a channel that "
                 "was not logged, or another column (a temperature?) mapped as the torque")
