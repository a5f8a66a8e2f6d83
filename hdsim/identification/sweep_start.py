"""What a friction sweep tells of the drive's starting torque.

The fitted law's starting torque is its level at rest, each way: ``F_s + Δ`` forward and
``F_s − Δ`` reverse (`hdsim.model.input_friction.InputFriction.torque` as ω → 0 from
either side). The law has one Stribeck rise ``F_s − F_c`` for both directions; its
direction asymmetry ``Δ`` shifts the whole level of a direction, at rest as at speed, so a
law with ``Δ ≠ 0`` has two starting torques and one with ``Δ = 0`` one, the same both ways.

A sweep measures the torque only on its plateaus. Between the slowest of them and rest
the law follows the shape it assumes for the rise, ``exp(−(ω/ω_s)²)``, and the fit's
covariance takes that shape as known: on sweeps whose rise has another shape
(power or Lorentzian, validation/README.md §3) the starting torque came out 6–27 % low
with a standard uncertainty of 0.1 %. The record determines
the level at rest only where it shows the rise levelling off: at least `SLOW_PLATEAUS`
distinct plateau speeds (`hdsim.io.running_checks.distinct_speeds`) at or below
`SLOW_SHARE` of the Stribeck speed, where the law's rise holds
``exp(−0.25) = 78 %`` of itself or more, and a rise whose standard uncertainty is finite
and below the rise. The Stribeck speed is the fitted one; a law without such a rise (no
friction family, or a rise fitted to 0 or within its uncertainty of 0) is judged against
the one the catalog laws assume
(`hdsim.model.input_friction.assumed_stribeck_speed`): a sweep that never ran that slow
cannot say that nothing rises below its slowest plateau.

A sweep that runs one way determines its starting torque that way only: the other is null
(not run), and the law holds no direction asymmetry (`RunningFit.held_at_zero`).

Otherwise the starting torque is the law's value with no uncertainty, "not determined by
the record" (the convention of `hdsim.identification.predictions`), and the measurement
that determines it is a breakaway ramp (``# test: breakaway``,
`hdsim.identification.breakaway`; docs/measurements.md), which reads the torque at the
last row at rest before each start.
"""

from __future__ import annotations

import math

import numpy as np

from hdsim.io.running_checks import RPM_PER_RAD_S, distinct_speeds
from hdsim.model.input_friction import assumed_stribeck_speed

__all__ = ["starting_level", "starting_levels", "starting_torque_undetermined", "starting_torque_summary", "BREAKAWAY_TEST"]

#: distinct plateau speeds that must lie on the top of the rise
SLOW_PLATEAUS = 2
#: ... at or below this share of the Stribeck speed
SLOW_SHARE = 0.5
#: the measurement that determines a starting torque
BREAKAWAY_TEST = "a breakaway ramp (# test: breakaway) measures it"
#: the amplitudes the level at rest is the sum of (``family.name`` of `RunningFit.fitted`)
LEVEL, RISE, ASYMMETRY = "base.coulomb_torque", "friction.stribeck_rise", "friction.coulomb_asymmetry"


#: the sign of the asymmetry Δ in the level at rest of each direction ("both": the law's F_s)
DIRECTIONS = {"both": 0.0, "forward": 1.0, "reverse": -1.0}


def starting_level(law, way: str) -> float:
    """The law's starting torque [N·m, WG shaft] ``F_s + Δ`` forward, ``F_s − Δ`` reverse,
    ``F_s`` for ``way="both"``."""
    return float(law.starting_torque) + DIRECTIONS[way] * float(law.coulomb_asymmetry)


def starting_levels(fit) -> dict:
    """The fitted law's starting torque by direction [N·m, WG shaft]: ``{"forward": F_s + Δ,
    "reverse": F_s − Δ}``, or ``{"both": F_s}`` for a law with one level both ways or an
    asymmetry the record does not determine (a standard uncertainty not below it: two
    levels would be an invented difference). On a record that runs one way, that way's
    ``F_s`` and None for the other: the record never runs it."""
    never = fit.record.never_run
    if never:
        return {way: None if way in never else starting_level(fit.law, "both") for way in ("forward", "reverse")}
    seen = _determined(float(fit.law.coulomb_asymmetry), fit.uncertainty.get(ASYMMETRY))
    return {way: starting_level(fit.law, way) for way in (("forward", "reverse") if seen else ("both",))}


def _determined(value: float, sigma) -> bool:
    """Whether an amplitude is told from zero: not zero, with a finite standard uncertainty
    below its size."""
    return value != 0.0 and sigma is not None and math.isfinite(sigma) and sigma < abs(value)


def starting_torque_undetermined(fit) -> str | None:
    """Why the sweep does not determine its law's starting torque (module text), or None
    when it does."""
    law = fit.law
    rise = float(fit.fitted.get(RISE, 0.0))
    determined_rise = rise > 0.0 and _determined(rise, fit.uncertainty.get(RISE))
    omega_s = float(law.stribeck_speed) if determined_rise else assumed_stribeck_speed()
    speeds = distinct_speeds(fit.record.segments)
    slow = [w for w in speeds if w <= SLOW_SHARE * omega_s]
    whose = "the fitted" if determined_rise else "an assumed"
    if len(slow) < SLOW_PLATEAUS:
        return (f"the law extrapolated below the slowest plateau ({min(speeds) * RPM_PER_RAD_S:.3g} rpm), not "
                f"determined by the record (that takes plateaus at {SLOW_PLATEAUS} or more speeds below "
                f"{SLOW_SHARE * omega_s * RPM_PER_RAD_S:.3g} rpm, half {whose} Stribeck speed); {BREAKAWAY_TEST}")
    if rise > 0.0 and not determined_rise:
        return f"the law at rest, on a Stribeck rise the record does not determine; {BREAKAWAY_TEST}"
    return None


def _sigma(fit, weights: dict) -> float | None:
    """Standard uncertainty of ``Σ weights[k] · amplitude k`` from the fit's covariance; None
    without one or when it is not finite."""
    coordinates = fit.coordinates
    if coordinates is None:
        return None
    g = np.array([weights.get(k, 0.0) for k in coordinates.keys])
    used = g != 0.0
    variance = float(g[used] @ coordinates.covariance[np.ix_(used, used)] @ g[used])
    return math.sqrt(variance) if math.isfinite(variance) and variance >= 0.0 else None


def starting_torque_summary(fit) -> dict:
    """The law's starting torque on the file's side [N·m] for a fit's JSON (``derived``).

    ``starting_torque_Nm`` is the law's ``F_s`` (both ways, or the mean of the two when the
    law is asymmetric); with an asymmetry ``starting_torque_forward_Nm`` / ``_reverse_Nm``
    too. Each has its ``…_uncertainty_Nm``: the standard uncertainty from the fit's
    covariance, None when the record does not determine it; ``starting_torque_basis`` says
    which (module text).
    """
    side = abs(fit.record.side_factor)
    reason = starting_torque_undetermined(fit)

    def sigma(weights):
        s = None if reason else _sigma(fit, weights)
        return None if s is None else side * s

    levels = starting_levels(fit)
    out = {"starting_torque_Nm": side * float(fit.law.starting_torque),
           "starting_torque_uncertainty_Nm": sigma({LEVEL: 1.0, RISE: 1.0})}
    for way, sign in (("forward", 1.0), ("reverse", -1.0)):
        if way in levels and levels[way] is None:  # a direction the record never runs
            out[f"starting_torque_{way}_Nm"] = out[f"starting_torque_{way}_uncertainty_Nm"] = None
        elif way in levels:
            out[f"starting_torque_{way}_Nm"] = side * levels[way]
            out[f"starting_torque_{way}_uncertainty_Nm"] = sigma({LEVEL: 1.0, RISE: 1.0, ASYMMETRY: sign})
    never = fit.record.never_run
    ways = (f"{never[0]} not run: the record determines neither its starting torque nor a direction asymmetry"
            if never else "each way: the law's direction asymmetry shifts its level at rest" if "both" not in levels
            else "one level both ways: the law has no direction asymmetry" if fit.law.coulomb_asymmetry == 0.0
            else "one level both ways: the record does not determine the law's direction asymmetry")
    basis = reason or ("determined by the plateaus on the top of the Stribeck rise"
                       if out["starting_torque_uncertainty_Nm"] is not None else "without an uncertainty: the fit "
                       "has no covariance")
    out["starting_torque_basis"] = f"{basis}; {ways}"
    return out
