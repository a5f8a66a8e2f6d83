"""What a diagnosis knows of an effect family, declared once for every kind of family.

The elastic path's effects (`hdsim.model.effects.base.Effect`), the running-torque law's
terms (`hdsim.model.running_terms.RunningTerm`) and the families of a test kind written
elsewhere (`hdsim.identification.test_kinds`) all derive from `FamilyKnowledge`; a
family's base class sets what differs from the defaults.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import ClassVar

__all__ = ["FamilyKnowledge"]


class FamilyKnowledge:
    """A family's knowledge, as class attributes (the defaults: no partner, no separating test)."""

    #: the family a record at one loading rate cannot tell this one from: of such a pair,
    #: one loss grows with the rate and the other does not ('' for none)
    rate_partner: ClassVar[str] = ""
    #: True for a family whose signature is its change with the loading rate, so that a
    #: record at one rate cannot ask about it
    rate_dependent: ClassVar[bool] = False
    #: other family -> the measurement that separates this family from it (each pair is
    #: written on one of its two families)
    separated_by: ClassVar[Mapping[str, str]] = MappingProxyType({})
    #: the measurement that separates this family from any other ('' for none)
    separated_from_any: ClassVar[str] = ""
