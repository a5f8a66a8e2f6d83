"""The honest outcome of a diagnosis: what was found, and what the record cannot tell.

``outcome`` is one of

- ``found``: families added and the residual explained (white, or at the noise floor);
- ``improved``: families added, yet structure remains in the residual;
- ``nothing_missing``: nothing added and nothing left to explain;
- ``cannot_decide``: nothing (more) could be decided from this record: too few
  independent samples, too few reversals, candidates that explain the residual equally
  well, or a rate question asked of one loading rate; ``next_measurement`` says what
  to record so that it can;
- ``wrong_test``: the data are not the test they claim (`hdsim.io.data_checks`); no
  model is fitted.

"Nothing added" is never reported as "nothing missing" unless the residual is explained:
a diagnosis that could not look is not a diagnosis that looked and found nothing
(docs/tutorial-find-missing-effect.md, "Outcomes").
"""

from __future__ import annotations

#: fewer effectively independent samples than this cannot rank families (the score's
#: ln(n_eff) penalty and the hold-out folds need a few dozen)
MIN_EFFECTIVE_SAMPLES = 30

def assess(diagnosis_json: dict, data: dict, kind) -> tuple[str, str]:
    """(outcome, next_measurement) of a diagnosis.

    Parameters
    ----------
    diagnosis_json : dict
        `hdsim.identification.engine.Diagnosis.to_json` of the diagnosis.
    data : dict
        The data summary of `hdsim.identification.workflow.examine` (``reversals``,
        ``loading_rates``, ``rows``).
    kind : hdsim.identification.test_kinds.TestKind
        The record's test kind: what keeps its records from deciding (`TestKind.limits`)
        and what to record when no family explains the residual (`TestKind.unexplained`).

    Returns
    -------
    tuple of str
        The outcome and, for ``cannot_decide`` (and ``improved``), what to measure next
        ('' when nothing more is needed).
    """
    explained = bool(diagnosis_json["success"])
    added = diagnosis_json["added"]
    ranking = [c for c in diagnosis_json["ranking"] if c.get("score") is not None]
    reasons = kind.limits(diagnosis_json, data, ranking)
    # a loss one loading rate could not name (a pair reported, neither of it added) still
    # asks for its measurement, and nothing can be "missing nothing" while it is open
    open_pairs = [a["measurement"] for a in diagnosis_json.get("ambiguous", []) if a.get("added") is False]
    # a near tie that was decided by a score still has a measurement that would settle it
    ties = [a["measurement"] for a in diagnosis_json.get("ambiguous", []) if a.get("added") and a.get("measurement")]
    if added:
        if explained:
            return "found", (open_pairs + ties + [""])[0]
        return "improved", reasons[0] if reasons else ""
    if explained:
        return ("cannot_decide", open_pairs[0]) if open_pairs else ("nothing_missing", "")
    return "cannot_decide", reasons[0] if reasons else kind.unexplained()


def twist_limits(kind, diagnosis_json: dict, data: dict, ranking: list) -> list[str]:
    """What kept a twist test's record from deciding, each as the measurement that would,
    most pressing first."""
    out = []
    rows = int(data.get("rows", 0))
    # the samples of the round where the diagnosis stopped: a candidate of an earlier round
    # scored against a residual that a later addition took away (a gap with n_eff 2 behind
    # a loss that was not yet in the model) says nothing about what keeps it from going on
    last = next(([c for c in r["candidates"] if c.get("score") is not None]
                 for r in reversed(diagnosis_json.get("rounds", [])) if r.get("candidates")), ranking)
    n_eff = min((c.get("n_eff") or 0.0 for c in last), default=0.0)
    if last and n_eff < MIN_EFFECTIVE_SAMPLES:
        out.append(f"more independent samples: the residual is correlated over many rows (about {n_eff:.0f} "
                   f"independent samples of {rows}); record more cycles, or the same cycle more slowly "
                   "with less filtering")
    if kind.needs_reversals and int(data.get("reversals", 2)) < 2:
        out.append("a full torque cycle and back (0 → +T → −T → 0): without reversals the loop that "
                   "friction, hysteresis and backlash leave cannot be seen")
    out += [pair["measurement"] for pair in diagnosis_json.get("ambiguous", [])]
    if data.get("loading_rates", 2) < 2 and ranking and kind.rate_dependent(ranking[0]["family"]):
        out.append("the same torque cycle at a second loading rate (4× faster or slower): with one rate, "
                   "rate-dependent losses cannot be told from friction")
    return out


#: a fitted stiffness this far from the datasheet's K1 … K3 (either way) is named
STIFFNESS_FACTOR = 3.0
#: a dead zone wider than this is no gear's backlash [rad] (catalog classes are arcminutes)
GAP_LIMIT_RAD = 0.5 * 3.141592653589793 / 180.0


def plausibility(fit_summary: dict, drive) -> list[dict]:
    """Fitted parameters compared with what the drive's datasheet allows, as checks.

    Parameters
    ----------
    fit_summary : dict
        `hdsim.identification.fit.FitResult.summary` (``fitted``, ``uncertainty``, ``derived``).
    drive : hdsim.io.data_checks.DriveScale
        The datasheet numbers (rated torque, K1, K3).

    Returns
    -------
    list of dict
        ``{"check", "status", "message"}``: ``warn`` for a stiffness more than 3× outside
        K1 … K3, a friction or slip torque above the rated torque, a gap of more than half a
        degree, and each parameter whose standard uncertainty exceeds its value; one ``ok``
        when none is found.
    """
    fitted, sigma, derived = fit_summary["fitted"], fit_summary["uncertainty"], fit_summary["derived"]
    out = []
    K = derived.get("K0_Nm_per_rad", fitted.get("stiffness.K0"))
    if K is not None and not drive.K_soft / STIFFNESS_FACTOR <= K <= drive.K_stiff * STIFFNESS_FACTOR:
        out.append(_warn("stiffness", f"the fitted stiffness {K:.3g} N·m/rad is {K / drive.K_soft:.2g}× the "
                         f"datasheet's K1 ({drive.K_soft:.3g} N·m/rad) of {drive.name}: another drive, torque or "
                         "angle in other units, or a compliant fixture in the loop"))
    for name, value in fitted.items():
        if "torque" in name.split(".")[-1] and abs(value) > drive.rated_torque:
            out.append(_warn("friction_level", f"{name} = {value:.3g} N·m is above the rated torque "
                             f"{drive.rated_torque:.3g} N·m of {drive.name}: not a friction a drive can have"))
        if name == "backlash.gap" and value > GAP_LIMIT_RAD:
            out.append(_warn("gap", f"the fitted gap {value * 180 / 3.141592653589793:.3g}° is no gear backlash "
                             "(catalog classes are arcminutes): a loose coupling or a free output"))
        if name in sigma and sigma[name] is None:
            out.append(_warn("uncertainty", f"{name} = {value:.3g}: the record does not determine it (it "
                             "hardly changes the fit's error)"))
        elif abs(sigma.get(name) or 0.0) > abs(value):
            out.append(_warn("uncertainty", f"{name} = {value:.3g} ± {sigma[name]:.2g}: the record does not "
                             "determine it (its uncertainty exceeds its value)"))
    return out or [{"check": "plausibility", "status": "ok",
                    "message": f"the fitted parameters are within what the datasheet of {drive.name} allows"}]


def _warn(check: str, message: str) -> dict:
    return {"check": check, "status": "warn", "message": message}
