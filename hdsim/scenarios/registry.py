"""The bench set-ups, registered once: name → `hdsim.scenarios.setups.Setup`.

A new bench defines its `Setup` in its own module and is added to `SETUPS` here; the
scenario validation (`hdsim.scenarios.scenario`) and the runner dispatch
(`hdsim.scenarios.run.run_scenario`) read nothing else.
"""

from __future__ import annotations

from hdsim.errors import unknown_name
from hdsim.scenarios.driven import DRIVEN
from hdsim.scenarios.locked import LOCKED
from hdsim.scenarios.setups import Setup

#: every bench set-up by its scenario ``setup`` name
SETUPS: dict[str, Setup] = {setup.name: setup for setup in (LOCKED, DRIVEN)}


def get_setup(name: str, where: str = "setup") -> Setup:
    """The registered set-up called ``name``.

    Parameters
    ----------
    name : str
        A scenario's ``setup`` value.
    where : str
        What named it, for the message (``"setup in scenarios/x.toml"``).

    Raises
    ------
    InputError
        For an unknown name, with the close matches.
    """
    if name not in SETUPS:
        raise unknown_name(where, name, SETUPS)
    return SETUPS[name]
