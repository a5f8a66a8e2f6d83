"""The breakaway (starting-torque) test kind: the torque raised from rest until the drive turns.

A breakaway record (``# test: breakaway``, docs/measurements.md) holds one or more
starts of the free shaft from rest, usually each way. What it can tell:

- **the starting torque of each direction**, model-free: the torque at the last row at
  rest before each start (`hdsim.signals.breakaway_episodes`), averaged per direction,
  with its uncertainty from the torque noise and the sampling. This is the figure
  ``fit`` reports (``metrics.starting_torque_forward_Nm`` / ``_reverse_Nm``, positive
  magnitudes on the file's torque side) beside the catalog's starting torque;
- **what the torque does once the shaft turns**, by a least-squares law on the rows from
  each start to the next rest, on the wave-generator shaft::

      T = d·S + J·α + b·ω                        (base: one level S both ways, inertia, viscous)
        + d·[d < 0]·A                            (asymmetry: the reverse level is S + A)
        − d·D·(1 − exp(−|ω|/ω_s))                (friction: the Stribeck drop D ≥ 0 after breakaway)

  with ``d`` the direction of the start, ``α`` and ``ω`` from the angle; the last 20 ms
  at rest before each start enter with ``ω = α = 0``: the torque there is the static level
  the rest held at its limit, and a drop shows as the distance to the torque at speed. The law is
  linear in its amplitudes for a fixed ``ω_s``, which is chosen on a log grid, as a
  friction sweep's law is (`hdsim.identification.running_fit`); the diagnosis is the
  running-torque test's (`hdsim.identification.running_diagnosis.RunningSession`) on
  these rows, held out by alternate 10 ms blocks of them.

A record in which the shaft never started from rest is not a breakaway test (its
identity check ``broke_away`` fails: ``wrong_test``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.identification.optimizer import inverse_gram, json_finite
from hdsim.identification.running_diagnosis import RunningSession, TorqueTest
from hdsim.identification.running_fit import TorqueFit, bounded_lsq
from hdsim.identification.test_kinds import register_test_kind
from hdsim.io.data_checks import Check, slipping_starts
from hdsim.io.running_checks import SIGN_SHARE, negated_torque, side_factor, speed_and_acceleration
from hdsim.model.family import FamilyKnowledge
from hdsim.signals import breakaway_episodes, noise_level

__all__ = ["BreakawayRecord", "BreakawayFit", "fit_breakaway", "BreakawayTest", "breakaway_checks"]

#: the rows at rest this long before each start enter the fit as the static level [s]
#: (the same rows `hdsim.signals.breakaway_episodes` averages for the starting torque)
VERGE_S = 0.02
#: the Stribeck speeds tried [rad/s on the WG shaft]
STRIBECK_GRID = np.geomspace(0.3, 300.0, 16)


class Asymmetry(FamilyKnowledge):
    """The starting level differs between the directions."""

    separated_from_any = "more starts in each direction"


class StribeckDrop(FamilyKnowledge):
    """The torque to keep turning falls below the starting torque as the speed rises."""

    separated_from_any = "starts held longer after breakaway, so the shaft reaches speed"


FAMILIES = {"asymmetry": Asymmetry, "friction": StribeckDrop}
FAMILY_IDS = {"asymmetry": "direction_level", "friction": "stribeck_drop"}


@dataclass
class BreakawayRecord:
    """A breakaway measurement prepared for fitting (all torques on the WG shaft).

    ``side_factor``: file torque = side_factor × WG-shaft torque (1 on the input, the ratio
    on the output). ``moving``: the rows from each start to its next rest; ``direction``:
    the direction of the start each row belongs to (0 elsewhere).
    """

    measurement: object
    speed: np.ndarray
    accel: np.ndarray
    torque: np.ndarray
    side_factor: float
    starts: list
    moving: np.ndarray
    direction: np.ndarray
    noise_floor: float

    @classmethod
    def of(cls, meas) -> "BreakawayRecord":
        if isinstance(meas, cls):
            return meas
        side = side_factor(meas)
        t = np.asarray(meas.time, dtype=float)
        wg = np.asarray(meas.wg_angle, dtype=float)
        torque = np.asarray(meas.torque, dtype=float) / side
        speed, accel = speed_and_acceleration(t, wg, window_s=0.02)
        starts = breakaway_episodes(t, wg, torque)
        moving = np.zeros(t.size, dtype=bool)
        direction = np.zeros(t.size)
        verge = max(int(VERGE_S / float(np.median(np.diff(t)))), 3)
        for s in starts:
            # the last rows at rest hold the static level at its limit: the law at ω = 0, α = 0
            held = slice(max(s.rest, s.onset - verge + 1), s.onset + 1)
            speed[held] = accel[held] = 0.0
            moving[held.start:s.stop] = True
            direction[held.start:s.stop] = s.direction
        return cls(meas, speed, accel, torque, side, starts, moving, direction, noise_level(torque, meas.time))

    def starting_torques(self) -> dict:
        """Per direction: the mean starting torque of its starts and its standard
        uncertainty, on the file's side [N·m]; None for a direction never started."""
        out = {}
        for name, sign in (("forward", 1), ("reverse", -1)):
            own = [s for s in self.starts if s.direction == sign]
            if not own:
                out[name] = out[name + "_uncertainty"] = None
                continue
            values = np.array([sign * s.torque for s in own]) * abs(self.side_factor)
            each = np.array([s.uncertainty for s in own]) * abs(self.side_factor)
            spread = float(np.std(values, ddof=1)) / math.sqrt(values.size) if values.size > 1 else 0.0
            out[name] = float(np.mean(values))
            out[name + "_uncertainty"] = math.hypot(float(np.sqrt(np.sum(each ** 2))) / values.size, spread)
        return out


class BreakawayFit(TorqueFit):
    """The law of a breakaway record fitted on its moving rows (module text)."""

    def metrics(self) -> dict:
        # starting_torque_forward_Nm, …_forward_uncertainty_Nm, …_reverse_Nm, …_reverse_uncertainty_Nm
        return {f"starting_torque_{k}_Nm": v for k, v in self.record.starting_torques().items()}

    @property
    def drive(self):
        """The fit's unit (with the record's ratio) carrying what the fit determined.

        Its input friction (on the WG shaft) breaks away at the fitted static level, the mean
        of the directions, with the asymmetry as its ``coulomb_asymmetry`` (forward level
        ``F + Δ``, reverse ``F − Δ``: Δ is minus half the fitted reverse excess); with the
        friction family it drops by the fitted drop to its running level at speed; its
        ``viscous`` is the fitted one. The fitted inertia becomes ``drive.J_in`` where the
        record determines it (`hdsim.identification.fit.with_fitted_inertia`).

        Not carried: the shape of the drop (the drive's law decays as a Gaussian of
        ``ω/ω_s``, this fit's as an exponential, so the fitted Stribeck speed is the scale,
        not the same curve). What a breakaway cannot show keeps the unit's: the ripple,
        the position torque, the mesh-loss coefficient and the smoothing speed ``ω_ε``, and
        the Stribeck speed without the friction family.
        """
        from hdsim.identification.fit import _unit_model, with_fitted_inertia  # every fit's drive starts so

        base = _unit_model(self.unit, self.measurement)
        side, f = abs(self.record.side_factor), self.fitted
        excess = f.get("asymmetry.reverse_excess", 0.0) / side
        start = f["level"] / side + 0.5 * excess
        law = base.input_friction.with_updates(
            starting_torque=start, coulomb_torque=start - f.get("friction.stribeck_drop", 0.0) / side,
            coulomb_asymmetry=-0.5 * excess, viscous=f["viscous"],
            stribeck_speed=f.get("friction.stribeck_speed", base.input_friction.stribeck_speed))
        drive = with_fitted_inertia(base, f["inertia"], self.uncertainty.get("inertia", math.inf), self.measurement)
        return drive.with_input_friction(law)

    def to_toml(self) -> str:
        import tomli_w

        doc = {"format": "hdsim-breakaway-fit-1", "test": "breakaway", "source": str(self.measurement.source),
               "torque_side": self.measurement.torque_side, "effects": list(self.families),
               "metrics": {k: v for k, v in self.metrics().items() if v is not None},
               "fitted": self.fitted, "uncertainty": {k: v for k, v in self.uncertainty.items() if math.isfinite(v)},
               "fit": {"rows": self.n, "rmse_Nm": self.rmse_Nm, "n_params": self.n_params}}
        return "# hdsim breakaway fit: torques on the file's shaft [N·m], speeds on the WG shaft [rad/s]\n" + \
            tomli_w.dumps(doc)

    def summary(self) -> dict:
        """JSON-ready summary (the ``hdsim fit --json`` object of a breakaway test)."""
        rec = self.record
        return {"test": "breakaway", "torque_side": self.measurement.torque_side, "effects": list(self.families),
                "rows": self.n, "starts": len(rec.starts), "fitted": self.fitted,
                "uncertainty": json_finite(self.uncertainty),
                "metrics": self.metrics(), "rmse_Nm": self.rmse_Nm,
                "noise_floor_Nm": rec.noise_floor * abs(rec.side_factor),
                "breakaways": [{"time_s": float(rec.measurement.time[s.onset]),
                                "direction": "forward" if s.direction > 0 else "reverse",
                                "torque_Nm": float(s.direction * s.torque * abs(rec.side_factor)),
                                "uncertainty_Nm": float(s.uncertainty * abs(rec.side_factor))} for s in rec.starts]}


def _columns(rec: BreakawayRecord, families, stribeck_speed: float):
    d, w = rec.direction, rec.speed
    names, cols, lower = ["level", "inertia", "viscous"], [d, rec.accel, w], [0.0, 0.0, 0.0]
    if "asymmetry" in families:
        names.append("asymmetry.reverse_excess")
        cols.append(d * (d < 0))
        lower.append(-np.inf)
    if "friction" in families:
        names.append("friction.stribeck_drop")
        cols.append(-d * (1.0 - np.exp(-np.abs(w) / stribeck_speed)))
        lower.append(0.0)
    return names, np.column_stack(cols), np.array(lower)


def fit_breakaway(record, families=(), rows=None, unit=None) -> BreakawayFit:
    """Fit the breakaway law with ``families`` (any of ``asymmetry``, ``friction``) on the
    moving rows of ``record`` (within ``rows`` when given); ``unit`` is the drive the fit's
    ``.drive`` starts from (default: the catalog default).

    Raises
    ------
    InputError
        No start from rest, an unknown family, or too few rows to fit.
    """
    rec = BreakawayRecord.of(record)
    families = list(families)
    for f in families:
        if f not in FAMILIES:
            raise BreakawayTest().cannot_show(f)
    use = rec.moving if rows is None else rec.moving & np.asarray(rows, dtype=bool)
    n = int(np.count_nonzero(use))
    if not rec.starts:
        raise InputError("the shaft never started from rest: there is no breakaway to fit")
    grid = STRIBECK_GRID if "friction" in families else STRIBECK_GRID[:1]

    def solve(ws):
        names, A, lower = _columns(rec, families, ws)
        if n <= A.shape[1] + 1:
            raise InputError(f"{n} moving rows: too few to fit {A.shape[1]} parameters")
        x = bounded_lsq(A[use], rec.torque[use], lower, np.inf)
        r = rec.torque[use] - A[use] @ x
        return float(r @ r), ws, names, A, x

    rss, ws, names, A, x = min((solve(ws) for ws in grid), key=lambda s: s[0])
    side = abs(rec.side_factor)
    residual = (rec.torque - A @ x) * side
    cov = rss / max(n - len(names), 1) * inverse_gram(A[use])
    units = {"level": side, "asymmetry.reverse_excess": side, "friction.stribeck_drop": side}
    fitted = {k: float(v) * units.get(k, 1.0) for k, v in zip(names, x)}
    uncertainty = {k: float(math.sqrt(max(cov[i, i], 0.0))) * units.get(k, 1.0) for i, k in enumerate(names)}
    if "friction" in families:
        fitted["friction.stribeck_speed"] = float(ws)
    return BreakawayFit(rec, families, residual, use, len(names) + ("friction" in families), fitted, uncertainty,
                        unit)


def breakaway_checks(meas, scale) -> tuple[list, dict]:
    """The model-free checks of a breakaway record: did it break away, where, at what torque
    against the catalog's starting torque."""
    rec = BreakawayRecord.of(meas)
    side = abs(rec.side_factor)
    output_torque = np.asarray(meas.torque, dtype=float) * (1.0 if meas.torque_side == "output" else meas.ratio)
    # rests that held nothing, or ended in an elastic twist, are a locked drive's: no start
    starts = rec.starts if scale is None or slipping_starts(meas.time, meas.angle, output_torque, scale) else []
    if not starts:
        never = Check("broke_away", "fail", "the shaft never started from rest (no rest that held the torque "
                      "followed by a turn beyond the drive's elastic twist)")
        return [never], {"starts": 0}
    where = ", ".join(f"{'forward' if s.direction > 0 else 'reverse'} at {float(meas.time[s.onset]):.3g} s, "
                      f"{abs(s.torque) * side:.3g} N·m" for s in starts[:6])
    checks = [Check("broke_away", "ok", f"{len(starts)} start(s) from rest: {where}")]
    ways = {s.direction for s in starts}
    if len(ways) < 2:
        checks.append(Check("both_directions", "warn", "the shaft started one way only: the other direction's "
                            "starting torque, and any asymmetry, cannot be told"))
    catalog = getattr(scale, "starting_torque", 0.0)
    if catalog:
        mine = rec.starting_torques()
        seen = [v for k, v in mine.items() if v is not None and not k.endswith("uncertainty")]
        ratio = max(seen) / (catalog * side)
        status = "ok" if 0.2 <= ratio <= 5.0 else "warn"
        checks.append(Check("catalog_starting_torque", status, f"starting torque {max(seen):.3g} N·m is "
                            f"{ratio:.2g}× the catalog's {catalog * side:.3g} N·m of {scale.name} on the "
                            f"{meas.torque_side} shaft" + ("" if status == "ok" else
                                                           ": a torque on the other shaft, or in other units?")))
    return checks, {"starts": len(starts), "directions": len(ways)}


class BreakawayTest(TorqueTest):
    """The breakaway (starting-torque) test: the torque raised from rest until the drive turns.

    No figures of its own (the residual against time, drawn for every kind, shows each
    start) and no predictions (the starting torque is measured, with its uncertainty, in
    its own section)."""

    name = "breakaway"
    record_word = "ramp"

    def families(self):
        return dict(FAMILIES)

    def parse_effects(self, effects):
        names = [e.strip() for e in effects.split(",")] if isinstance(effects, str) else list(effects or ())
        for name in names:
            if name and name not in FAMILIES:
                raise unknown_name("breakaway family", name, FAMILIES)
        return {f: FAMILY_IDS[f] for f in names if f}

    def fit(self, meas, effects=None, *, unit=None):
        return fit_breakaway(meas, list(self.parse_effects(effects)), unit=unit)

    def fit_summary(self, result, stem, scale) -> dict:
        summary = result.summary()
        catalog = getattr(scale, "starting_torque", 0.0)
        summary["metrics"]["catalog_starting_torque_Nm"] = catalog * abs(result.record.side_factor) or None
        return summary

    def session(self, meas, chosen, *, unit=None, candidates=None, max_steps=None):
        return BreakawaySession(meas, chosen, unit)

    def fit_json(self, fit) -> dict:
        return {"fitted": fit.fitted, "uncertainty": fit.uncertainty}

    def prepare(self, meas):
        return breakaway_torque_sign(meas)

    def checks(self, meas, scale):
        return breakaway_checks(meas, scale)

    def limits(self, diagnosis_json, data, ranking):
        out = ["starts in the other direction: an asymmetry needs both"] if data.get("directions", 2) < 2 else []
        return out + super().limits(diagnosis_json, data, ranking)  # and the ties' measurements

    def unexplained(self) -> str:
        return ("the torque after breakaway keeps a structure no breakaway family explains: look at the residual "
                "against time in the report (a controller that changes the torque, a load on the shaft)")

    parameters_heading = "Fitted parameters (torques on the file's shaft)"
    #: a start from rest is a transient of a few rows, which the noise check (a median)
    #: does not see thinned away: a breakaway log is fitted whole
    thinnable = False

    def report_sections(self, diagnosis, diagnosis_json):
        return _starting_torque_section(diagnosis_json["metrics"])

    def fit_sections(self, result, summary):
        return _starting_torque_section(summary["metrics"])


def breakaway_torque_sign(meas):
    """The ramp with its torque in the sign docs/measurements.md gives (the torque before a start has the sign of
    the motion that follows), and the check that says whether it was turned: with the other shaft
    free nothing but the torque applied starts the shaft, so a torque against the start on
    three quarters of the starts or more was logged with the other sign, and is negated (as a
    twist test's is, `hdsim.io.data_checks.torque_sign_convention`)."""
    torque = np.asarray(meas.torque, dtype=float)
    if meas.wg_angle is None or torque.size < 10 or np.ptp(torque) == 0.0:
        return meas, []
    starts = breakaway_episodes(meas.time, meas.wg_angle, torque / side_factor(meas))
    against = [s for s in starts if np.sign(s.torque) == -s.direction]
    if not starts or len(against) < SIGN_SHARE * len(starts):
        return meas, []
    return negated_torque(meas, f"the torque before {len(against)} of {len(starts)} starts is against the motion "
                                "that follows, which nothing but the torque applied can start")


def _starting_torque_section(metrics: dict) -> list:
    """The measured starting torque of each direction with its uncertainty, as a page's table:
    the figure a breakaway test is for (the fitted level is the model's, not the measurement)."""
    from hdsim.identification.report_page import rounded  # the page's rounding, matplotlib-free

    rows = []
    for way in ("forward", "reverse"):
        value = metrics.get(f"starting_torque_{way}_Nm")
        sigma = metrics.get(f"starting_torque_{way}_uncertainty_Nm")
        rows.append((way, "— (never started this way)" if value is None else rounded(value, sigma)))
    return [("Starting torque, measured (the file's shaft)", (("direction", "value ± standard uncertainty [N·m]"),
                                                             rows))]


class BreakawaySession(RunningSession):
    """The running-torque session on a breakaway record's moving rows (module text)."""

    fold_rule = "alternate blocks of 10 ms of the rows each start moves"
    widens = False

    record_of = staticmethod(BreakawayRecord.of)

    @staticmethod
    def folds_of(record):
        """Two folds of alternate blocks of moving rows, each half the static rows long: each
        fold holds static rows and rows at speed of every start (a fold of whole starts, or of
        halves, would leave one fold without the static level and nothing to predict it by)."""
        rows = np.flatnonzero(record.moving)
        t = np.asarray(record.measurement.time, dtype=float)
        block = max(int(0.5 * VERGE_S / float(np.median(np.diff(t)))), 2)
        first = np.zeros(record.moving.size, dtype=bool)
        first[rows[(np.arange(rows.size) // block) % 2 == 0]] = True
        second = record.moving & ~first
        return [first, second], [second, first]

    def fit_model(self, ids, rows=None, widened=()):
        by_id = {v: k for k, v in FAMILY_IDS.items()}
        return fit_breakaway(self.record, [by_id.get(i, i) for i in ids], rows=rows, unit=self.unit)

    def entry_forms(self, family: str) -> tuple:
        return (FAMILY_IDS[family],)


register_test_kind(BreakawayTest())
