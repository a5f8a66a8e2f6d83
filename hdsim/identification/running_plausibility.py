"""A friction sweep's fitted law (`hdsim.identification.running_fit`) against the drive's
catalog and physics: the running-torque kind's ``plausibility``."""

from __future__ import annotations

__all__ = ["running_plausibility"]


def running_plausibility(fit, drive) -> list[dict]:
    """The fitted law compared with the drive's catalog and with physics, as checks.

    ``warn`` for a Coulomb level more than 30× the catalog running torque either way, a
    law whose ripple and asymmetry exceed its level (it would deliver power: an offset or
    a load larger than the friction), and each amplitude whose uncertainty exceeds it;
    one ``ok`` when none is found (``fit``: a `hdsim.identification.running_fit.RunningFit`).
    """
    out = []
    law = fit.law
    catalog = getattr(drive, "running_torque", 0.0)
    if catalog and not catalog / 30.0 <= law.coulomb_torque + abs(law.coulomb_asymmetry) <= 30.0 * catalog:
        out.append({"check": "friction_level", "status": "warn",
                    "message": f"the fitted level {law.coulomb_torque:.3g} N·m on the input is "
                               f"{law.coulomb_torque / catalog:.3g}× the catalog running torque of {drive.name}: "
                               "another drive, the torque on the other shaft, or torque in other units"})
    if not law.dissipative:
        out.append({"check": "dissipative", "status": "warn",
                    "message": f"the fitted asymmetry {law.coulomb_asymmetry:.3g} N·m and ripple exceed the level "
                               f"{law.coulomb_torque:.3g} N·m: the torque keeps one sign in both directions, an "
                               "offset or a load (gravity, a spring) larger than the friction"})
    start = fit.starting_torque()
    value, sigma = start["starting_torque_Nm"], start["starting_torque_uncertainty_Nm"]
    if sigma is None:  # an extrapolation below the slowest plateau (`sweep_start`)
        out.append({"check": "starting_torque", "status": "warn",
                    "message": f"the starting torque {value:.3g} N·m is {start['starting_torque_basis']}"})
    elif sigma > 0.5 * value:
        out.append({"check": "starting_torque", "status": "warn",
                    "message": f"the starting torque {value:.3g} ± {sigma:.2g} N·m: the sweep hardly determines "
                               "it; a breakaway ramp (# test: breakaway) measures it"})
    for name, value in fit.fitted.items():
        sigma = fit.uncertainty.get(name, 0.0)
        if abs(sigma) > abs(value) and abs(value) > 0:
            out.append({"check": "uncertainty", "status": "warn",
                        "message": f"{name} = {value:.3g} ± {sigma:.2g}: the sweep does not determine it"})
    return out or [{"check": "plausibility", "status": "ok",
                    "message": f"the fitted law is within what the catalog of {drive.name} and physics allow"}]
