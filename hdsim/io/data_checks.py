"""Checks of a measurement before any fit: is it the test it claims, and what can it tell?

Every check is model-free: it reads the record and, where it needs a scale, the drive's
datasheet numbers (rated torque, the softest and stiffest catalog stiffness K1, K3).
Each returns a `Check`: a name, a status (``ok``, ``warn``, ``fail``) and one plain
sentence a bench engineer would write in a log book. A ``fail`` of an *identity* check
(the twist span of a locked test, the angle following the torque, a locked test's torque
that never varies, a kinematic error that is identically zero, a ratio the angles
contradict) means the record is not the test it claims; `wrong_test` gives that sentence
(docs/measurements.md, "Checks").

The signal analysis the checks rest on (noise without a model, torque legs, loading
rates) is in `hdsim.signals`; a running-torque record goes to `hdsim.io.running_checks`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hdsim.io.check import Check, constant_torque
from hdsim.signals import breakaway_episodes, loading_rates, noise_level, rate_groups, torque_legs

__all__ = ["DriveScale", "run_checks", "wrong_test", "import_checks", "unit_checks", "slipping_starts", "twist_slope",
           "torque_sign_convention"]

#: a locked drive twists at most this many times its softest catalog compliance predicts
#: (K1 over the whole torque swing, plus a generous lost motion) before the record is
#: taken for an output turning freely
SPAN_FACTOR = 20.0
#: lost motion allowed on top of the elastic twist [rad] (catalog classes are 1-3 arcmin;
#: a worn or home-built drive may reach ten)
LOST_MOTION_ALLOWANCE = math.radians(10.0 / 60.0)
#: rank correlation of angle and torque below which the angle does not follow the torque
FOLLOW_MIN = 0.5
#: torque noise over its swing: above the first a warning, above the second the record
#: cannot show a loop at all
NOISE_WARN, NOISE_FAIL = 0.05, 0.3
#: drift a kinematic error may show against the nominal output angle, besides the elastic
#: twist [rad]: catalog transmission accuracy is 1-1.5 arcmin, lost motion 1-3 (a worn or
#: home-built drive several times that); `ratio_consistency`
RATIO_DRIFT_ALLOWANCE = math.radians(10.0 / 60.0)
#: a load whose correlation with the output angle is this or more follows the angle (a ramp,
#: a spring): the ratio check fits no elastic twist of its own then
RAMP_CORRELATION = 0.9
#: identity checks: a fail means the record is not the test it claims
IDENTITY = ("twist_span", "angle_follows_torque", "kinematic_error_not_zero", "ratio_consistent", "turns_steadily",
            "torque_varies", "holds_without_slipping", "broke_away")


@dataclass(frozen=True)
class DriveScale:
    """The datasheet numbers the checks compare a record with.

    Attributes
    ----------
    name : str
        The drive, for the messages.
    rated_torque : float
        T_N [N·m].
    K_soft, K_stiff : float
        Softest and stiffest catalog stiffness (K1, K3) [N·m/rad].
    running_torque : float
        Catalog no-load running torque on the input at 2000 rpm [N·m] (0: unknown).
    starting_torque : float
        Catalog starting torque on the input [N·m] (0: unknown).
    ratio : float
        Transmission ratio [-].
    """

    name: str
    rated_torque: float
    K_soft: float
    K_stiff: float
    running_torque: float = 0.0
    ratio: float = 1.0
    starting_torque: float = 0.0

    @classmethod
    def of(cls, model) -> "DriveScale":
        """The scale of a `hdsim.model.drive.HarmonicDrive` (its catalog numbers, else its
        base stiffness)."""
        from hdsim.model.input_friction import catalog_values

        catalog = model.provenance.get("catalog") or {}
        K = float(np.max(model.base_stiffness))
        friction = catalog_values(model)
        return cls(str(model.name), float(np.max(model.drive.rated_torque)),
                   float(catalog.get("K1", K)), float(catalog.get("K3", K)),
                   float(friction["running_torque_2000rpm"]), float(np.max(np.abs(model.drive.ratio))),
                   float(friction["starting_torque"]))


def _rank_correlation(a, b) -> float:
    """Spearman's rank correlation: Pearson's of the ranks, ties sharing their mean rank.
    (`scipy.stats.spearmanr` gives the same; importing scipy.stats costs 0.7 s per command.)"""
    if np.ptp(a) == 0 or np.ptp(b) == 0:
        return 0.0
    return float(np.corrcoef(_mean_ranks(a), _mean_ranks(b))[0, 1])


def _mean_ranks(x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="mergesort")
    ordered = x[order]
    starts = np.flatnonzero(np.r_[True, ordered[1:] != ordered[:-1]])  # first of each run of ties
    counts = np.diff(np.r_[starts, x.size])
    ranks = np.empty(x.size)
    ranks[order] = np.repeat(starts + 0.5 * (counts - 1), counts)
    return ranks


def _arcmin(x: float) -> str:
    return f"{math.degrees(x) * 60:.3g} arcmin" if abs(x) < math.radians(2) else f"{math.degrees(x):.3g}°"


def braked_rows(meas, torque) -> np.ndarray:
    """Rows of a kinematic-error record whose torque opposes the output's motion: a brake
    holding the load it is set to (the test turns the output "against a load that opposes
    the motion", scenarios/kinematic_error.toml).

    In the record's convention (a positive torque twists the output ahead, after
    `torque_sign_convention`) a brake on a forward pass makes the output lag, so its torque
    and the output's speed have opposite signs: T·ω < 0. A brake is torque-controlled, and a
    noise-free or finely quantised torque then repeats its set value for the whole pass,
    which is the load, not a clipped channel. The direction is that of the nominal output
    angle (wave-generator angle / ratio) from row to row: no time step, no encoder noise.
    """
    T = np.asarray(torque, dtype=float)
    if meas.test != "kinematic_error" or meas.wg_angle is None or not meas.ratio or T.size < 2:
        return np.zeros(T.size, dtype=bool)
    direction = np.sign(np.gradient(np.asarray(meas.wg_angle, dtype=float) / meas.ratio))
    return T * direction < 0.0


def _saturation(name: str, x, held=None) -> Check | None:
    """A channel that sits at its extreme value for many samples: clipped or saturated.

    ``held`` marks rows where an extreme value is the load as set (`braked_rows`), which do
    not count; those same rows of a clipped reading of a brake cannot be told from it by
    their values, and a kinematic-error row shows the drive in its angles either way.

    A channel without noise on its other rows (a simulated record, a set load logged as
    its set point) repeats any value it holds: repeats are then no sign of clipping. A
    clipped channel is one whose noise stops at a rail.
    """
    x = np.asarray(x, dtype=float)
    held = np.zeros(x.size, dtype=bool) if held is None else held
    for value, end in ((np.max(x), "maximum"), (np.min(x), "minimum")):
        at = (x == value) & ~held
        if (np.count_nonzero(at) >= max(5, 0.01 * x.size) and np.ptp(x) > 0
                and noise_level(x[x != value]) > 1e-9 * float(np.max(np.abs(x)))):  # noise above round-off
            return Check("saturation", "warn", f"the {name} sits at its {end} {value:.6g} for "
                         f"{np.count_nonzero(at)} rows ({100 * np.mean(at):.1f} %): clipped or saturated, "
                         "those rows do not show the drive")
    return None


def run_checks(meas, drive: DriveScale) -> tuple[list[Check], dict]:
    """Every data check of a measurement, and the figures the data summary reports.

    Parameters
    ----------
    meas : hdsim.io.measurement.Measurement
        The record.
    drive : DriveScale
        The datasheet numbers.

    Returns
    -------
    tuple
        (list of `Check`, ``{"noise_floor_rad", "torque_noise_Nm", "reversals",
        "loading_rates"}``): the noise floor is the angle's (stiffness test) or the
        kinematic error's (kinematic-error test), estimated without any model.
    """
    T = np.asarray(meas.torque, dtype=float)
    t = np.asarray(meas.time, dtype=float)
    ke = meas.test == "kinematic_error"
    response = np.asarray(meas.kinematic_error if ke else meas.angle, dtype=float)
    torque_noise = noise_level(T, t)
    smooth_T, turns = torque_legs(T)
    swing = float(np.ptp(smooth_T))
    rates = loading_rates(t, smooth_T, turns)
    reversals = len(turns) - 2
    checks: list[Check] = []

    constant = not ke and np.ptp(T) == 0.0  # a driven test may hold one load; a locked test must vary it
    if constant:
        checks.append(constant_torque(T[0]))
    else:
        checks += _kinematic_error_identity(meas, drive) if ke else _locked_identity(meas, T, drive)
        checks.append(_torque_noise_check(torque_noise, swing))
    if not ke:
        cycles = reversals / 2.0
        status = "ok" if reversals >= 2 else "warn"
        tail = "" if reversals >= 2 else (": without a return the loop (friction, hysteresis, backlash) "
                                          "cannot be seen")
        checks.append(Check("reversals", status, f"{reversals} torque reversals ({cycles:g} cycles){tail}"))
        groups = rate_groups(rates)
        status = "ok" if len(groups) >= 2 else "warn"
        tail = "" if len(groups) >= 2 else (": rate-dependent losses (damping) cannot be told from "
                                            "rate-independent ones (friction)")
        shown = ", ".join(f"{r:.3g}" for r in groups[:5])
        checks.append(Check("loading_rates", status, f"{len(groups)} distinct loading rate(s) "
                            f"({shown or 'none'} N·m/s){tail}"))
    for name, x, held in (("torque", T, braked_rows(meas, T)), ("angle", meas.angle, None)):
        found = _saturation(name, x, held)
        if found:
            checks.append(found)
    floor = noise_level(_without_wg_orders(response, meas.wg_angle, meas.ratio) if ke else response, t)
    figures = {"noise_floor_rad": floor, "torque_noise_Nm": torque_noise,
               "reversals": reversals, "loading_rates": len(rate_groups(rates))}
    return checks, figures


#: the wave-generator orders removed before a kinematic error's noise is estimated
WG_ORDERS = 8


def _without_wg_orders(kinematic_error, wg_angle, ratio) -> np.ndarray:
    """The kinematic error less its least-squares part periodic in the wave-generator angle
    (orders 1 to `WG_ORDERS`, and once per output revolution).

    The noise level of a signal is its rms about a local cubic through seven samples
    (`hdsim.signals.noise_level`). A kinematic error logged at a few samples per WG
    revolution is not locally cubic: at 29 samples a turn a period of its 4x order spans
    the seven, and the estimate came out 11x the encoder noise. These orders are
    in every drive, not a model's choice, so the floor stays the data's, whatever is fitted.
    """
    e = np.asarray(kinematic_error, dtype=float)
    A = np.column_stack([np.ones_like(e), *_wg_order_columns(wg_angle, ratio, WG_ORDERS)])
    return e - A @ np.linalg.lstsq(A, e, rcond=None)[0]


def _wg_order_columns(wg_angle, ratio, orders: int) -> list:
    """cos and sin of the wave-generator orders 1 … ``orders`` and of the output's first
    order: the part of a kinematic error that is periodic in the angles."""
    wg = np.asarray(wg_angle, dtype=float)
    columns = []
    for phase in [k * wg for k in range(1, orders + 1)] + [wg / float(ratio)]:
        columns += [np.cos(phase), np.sin(phase)]
    return columns


def _locked_identity(meas, T, drive: DriveScale) -> list[Check]:
    angle = np.asarray(meas.angle, dtype=float)
    span = float(np.ptp(angle))
    expected = float(np.ptp(T)) / drive.K_soft + LOST_MOTION_ALLOWANCE
    least = float(np.ptp(T)) / drive.K_stiff
    torque_text = f"{np.max(np.abs(T)):.3g} N·m"
    slip = _slip_after_rest(meas, T, angle, drive)  # the more telling sentence first: it names the test
    out = [slip] if slip else []
    if span > SPAN_FACTOR * expected:
        out.append(Check("twist_span", "fail", f"the angle spans {_arcmin(span)}, but a locked {drive.name} "
                         f"twists about {_arcmin(expected)} at {torque_text}: this looks like an output "
                         "turning freely (a running or friction test), or an angle in other units "
                         "(revolutions? rotor side, not divided by the ratio?)"))
    elif span < least / SPAN_FACTOR:
        out.append(Check("twist_span", "warn", f"the angle spans only {_arcmin(span)}, while a {drive.name} "
                         f"twists at least {_arcmin(least)} at {torque_text}: an angle in other units "
                         "(degrees read as radians?) or a torque in other units"))
    else:
        out.append(Check("twist_span", "ok", f"the angle spans {_arcmin(span)} at {torque_text}, possible "
                         f"for a locked {drive.name}"))
    rho = _rank_correlation(T, angle)
    if abs(rho) < FOLLOW_MIN:
        out.append(Check("angle_follows_torque", "fail", f"the angle does not follow the torque (rank "
                         f"correlation {rho:.2f}): the output was not held by the drive alone, or the "
                         "columns are swapped"))
    elif rho < 0:
        out.append(Check("angle_follows_torque", "warn", f"the angle falls as the torque rises (rank "
                         f"correlation {rho:.2f}): angle and torque are signed the opposite ways"))
    else:
        out.append(Check("angle_follows_torque", "ok", f"the angle follows the torque (rank correlation "
                         f"{rho:.2f})"))
    return out


def slipping_starts(time, angle, torque, drive: DriveScale) -> list:
    """The starts from rest (`hdsim.signals.breakaway_episodes`, output angle and torque) in
    which the drive broke free: the rest held a third of the torque's swing or more, and the
    angle then turned far beyond the elastic twist of the torque's change during the motion.

    A locked drive's angle follows its torque, so it never rests while the torque rises; the
    rests it has (at a turning point of the torque) hold nothing and end in elastic twist."""
    T = np.asarray(torque, dtype=float)
    swing = float(np.ptp(T))
    out = []
    for start in breakaway_episodes(time, angle, T):
        elastic = SPAN_FACTOR * float(np.ptp(T[start.onset:start.stop])) / drive.K_soft
        if start.held_torque >= swing / 3.0 and abs(start.travel) > elastic:
            out.append(start)
    return out


def _slip_after_rest(meas, T, angle, drive: DriveScale) -> Check | None:
    """A fail when the drive broke free from rest (`slipping_starts`): a breakaway, not held."""
    for start in slipping_starts(meas.time, angle, T, drive):
        return Check("holds_without_slipping", "fail", f"the angle stood still while the torque rose to "
                     f"{abs(start.torque):.3g} N·m, then turned {_arcmin(abs(start.travel))} at about that torque, "
                     f"far beyond the elastic twist of a held {drive.name}: the drive broke free, this looks like "
                     "a breakaway test (--test breakaway)")
    return None


def twist_slope(meas) -> tuple[float, float]:
    """The angle's slope against the torque [rad/(N·m)] and its t-statistic, model-free.

    Locked test: the angle regressed on the torque and an offset. Kinematic-error test:
    the kinematic error regressed on the torque, an offset and the first
    four orders of the wave-generator angle and the first of the output's, so that the
    kinematic error itself does not pass for a twist. A drive twists with its load:
    the slope is positive (the compliance) in the file's convention, whatever the drive.
    """
    T = np.asarray(meas.torque, dtype=float)
    if meas.test == "kinematic_error":
        y = np.asarray(meas.kinematic_error, dtype=float)
        # no drift term: the model has none, a ramped load would pass for one
        columns = [T, np.ones_like(T), *_wg_order_columns(meas.wg_angle, meas.ratio, 4)]
    else:
        y = np.asarray(meas.angle, dtype=float)
        columns = [T, np.ones_like(T)]
    X = np.column_stack(columns)
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ coef
    dof = max(y.size - X.shape[1], 1)
    # the residual is correlated: scale the variance by the effective sample count
    rho = float(np.clip(np.corrcoef(r[1:], r[:-1])[0, 1], 0.0, 0.999)) if r.size > 2 and np.ptp(r) > 0 else 0.0
    cov = float(r @ r) / dof * np.linalg.pinv(X.T @ X) * (1.0 + rho) / (1.0 - rho)
    se = math.sqrt(max(cov[0, 0], 0.0))
    return float(coef[0]), float(coef[0] / se) if se > 0 else 0.0


def _torque_noise_check(torque_noise: float, swing: float) -> Check:
    """The torque noise [N·m rms] against the torque's swing [N·m]."""
    if swing <= 0 or torque_noise > NOISE_FAIL * swing:
        return Check("torque_noise", "fail", f"the torque noise ({torque_noise:.3g} N·m rms) is "
                     f"{torque_noise / max(swing, 1e-300):.2g} of its swing ({swing:.3g} N·m): the "
                     "record cannot show how the drive answers the torque")
    if torque_noise > NOISE_WARN * swing:
        return Check("torque_noise", "warn", f"the torque is noisy ({torque_noise:.3g} N·m rms, "
                     f"{100 * torque_noise / swing:.0f} % of its swing; torque from motor current?): "
                     "loading and unloading are told apart on the smoothed torque")
    return Check("torque_noise", "ok", f"torque noise {torque_noise:.3g} N·m rms, "
                 f"{100 * torque_noise / swing:.2g} % of its swing")


def torque_sign_convention(meas):
    """The record with its torque in the convention of the contract (positive torque, positive
    twist), and the check that says whether it was turned: a torque that the angle falls
    with, clearly (t < −5, `twist_slope`), was logged with the other sign (the torque the
    drive delivers rather than the load it carries, or a sensor mounted the other way), and
    is negated; a fit would otherwise run the stiffness to its bound (no compliance)."""
    if float(np.ptp(np.asarray(meas.torque, dtype=float))) <= 0:
        return meas, []
    slope, t_stat = twist_slope(meas)
    if t_stat < -5.0:
        from dataclasses import replace

        return replace(meas, torque=-np.asarray(meas.torque, dtype=float)), [Check(
            "torque_sign", "warn", f"the angle falls as the torque rises (slope {slope:.3g} rad/(N·m), t = "
            f"{t_stat:.0f}): the torque was logged with the other sign (the torque the drive delivers, not the "
            "load on it); it is negated for the fits")]
    if abs(t_stat) < 3.0:
        return meas, [Check("twist_under_load", "warn", f"the angle does not follow the torque clearly (t = "
                            f"{t_stat:.1f}): a load that hardly varies twists the drive by a constant, which "
                            "the encoder offset takes; the stiffness is not determined by this record (a run "
                            "under a load that varies, or both directions under load, determines it)")]
    return meas, [Check("torque_sign", "ok", f"the angle rises with the torque (t = {t_stat:.0f})")]


def _kinematic_error_identity(meas, drive: DriveScale) -> list[Check]:
    out_angle = np.asarray(meas.angle, dtype=float)
    ke = np.asarray(meas.kinematic_error, dtype=float)
    checks = []
    scale = max(float(np.max(np.abs(out_angle))), 1.0)
    if np.ptp(ke) <= 1e-12 * scale:
        checks.append(Check("kinematic_error_not_zero", "fail", "the kinematic error is identically zero: "
                            "the output angle is the wave-generator angle divided by the ratio, one encoder "
                            "logged twice"))
    else:
        checks.append(Check("kinematic_error_not_zero", "ok", f"the kinematic error spans {_arcmin(np.ptp(ke))}"))
    check = ratio_consistency(meas, "fail", drive)
    return checks + ([check] if check else [])


def ratio_consistency(meas, status: str, drive: DriveScale | None = None) -> Check | None:
    """Does the output turn the wave-generator angle divided by the ratio? A ``status`` check
    when it does not; None when the record has no ratio or does not turn.

    Judged by the drift a wrong ratio leaves in the kinematic error, not by a share of the
    slope: the output angle regressed on the nominal one (wave-generator angle / ratio) has
    a slope s, and ``|s − 1|`` times the nominal output travel is the drift. A kinematic
    error is periodic, arcseconds to a few arcminutes, so the drift may be
    `RATIO_DRIFT_ALLOWANCE` plus the elastic twist over the torque's swing (at the drive's
    softest catalog stiffness) and no more: a ratio of 101 for 100 drifts 0.01 rad per
    radian of output travel, 230 arcmin over one revolution each way.
    """
    if meas.ratio is None or meas.wg_angle is None:
        return None
    wg, out_angle = np.asarray(meas.wg_angle, dtype=float), np.asarray(meas.angle, dtype=float)
    nominal = wg / meas.ratio
    travel = float(np.ptp(nominal))
    if not travel > 0:
        return None
    torque = np.asarray(meas.torque, dtype=float)
    # the elastic twist, unless the load follows the angle (a ramp or a spring): the torque's
    # column would then take up the slope, and the slope would say nothing; the allowance
    # below holds that twist anyway
    follows = np.ptp(torque) > 0 and abs(np.corrcoef(nominal, torque)[0, 1]) >= RAMP_CORRELATION
    columns = [nominal, np.ones_like(nominal)] + ([torque] if np.ptp(torque) > 0 and not follows else [])
    slope = float(np.linalg.lstsq(np.column_stack(columns), out_angle, rcond=None)[0][0])
    drift = abs(slope - 1.0) * travel
    allowed = RATIO_DRIFT_ALLOWANCE + (float(np.ptp(torque)) / drive.K_soft if drive else 0.0)
    over = f"over {_arcmin(travel)} of output travel"
    if drift > allowed:
        implied = meas.ratio / slope  # a whole number when it is one within what the drift allows
        if slope > 0 and abs(implied - round(implied)) <= abs(implied) * allowed / travel:
            implied = round(implied)
        return Check("ratio_consistent", status, f"the output turns {slope:.6g} times the wave-generator angle "
                     f"divided by the ratio {meas.ratio:g}, a drift of {_arcmin(drift)} {over} where a kinematic "
                     f"error stays within {_arcmin(allowed)}: a wrong ratio (the slope says {implied:.4g}, "
                     f"the file says {meas.ratio:g}), or an angle in other units")
    return Check("ratio_consistent", "ok", f"the output follows the wave generator through the ratio "
                 f"{meas.ratio:g} (slope {slope:.6g}: a drift of {_arcmin(drift)} {over})")


def wrong_test(checks) -> str:
    """The sentence of the first failed identity check ('' when the record is the test it claims)."""
    for c in checks:
        if c.status == "fail" and c.check in IDENTITY:
            return c.message
    return ""


def import_checks(meas) -> list[Check]:
    """What the import options did to the rows, as checks (a user must see what was left out)."""
    rows = meas.rows
    total = len(meas) + rows.dropped_rows + rows.windowed_rows
    out = []
    if rows.dropped_rows:
        share = rows.dropped_rows / max(total, 1)
        out.append(Check("dropped_rows", "warn" if share > 0.05 else "ok",
                         f"{rows.dropped_rows} of {total} rows dropped for a NaN, empty or glitch cell "
                         f"({100 * share:.2g} %)"))
    if rows.windowed_rows:
        out.append(Check("window", "ok", f"{rows.windowed_rows} rows outside the time window left out"))
    if rows.runs > 1:
        out.append(Check("concatenated_runs", "ok", f"{rows.runs} runs joined end to end (their clock "
                         "restarted); the drive's state is carried across the joins"))
    if rows.time_from_rows:
        out.append(Check("time_axis", "warn", "no time column: time is the row index over the given sample "
                         "rate, so rate-dependent effects (damping) are not identifiable from this log"))
    return out


def unit_checks(meas, drive: DriveScale) -> list[Check]:
    """The record's rated torque and ratio (its header) against the drive it is fitted with:
    a fit puts the record's on the drive, so a record of another unit changes the drive's
    law (the hardening's breakpoints scale with the rated torque) and the user must see it."""
    out = []
    for key, given, unit, own in (("rated_torque", meas.rated_torque, "N·m", drive.rated_torque),
                                  ("ratio", meas.ratio, "", drive.ratio)):
        if given is not None and own and abs(float(given) / float(own) - 1.0) > 0.01:
            out.append(Check(f"{key}_of_unit", "warn", f"the record's {key.replace('_', ' ')} {float(given):.4g}"
                             f"{' ' + unit if unit else ''} is not the {drive.name}'s {float(own):.4g}"
                             f"{' ' + unit if unit else ''}: the fit puts the record's on the drive (name the unit "
                             "the record was made on, or correct the record's header)"))
    return out

