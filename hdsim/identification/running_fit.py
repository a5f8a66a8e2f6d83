"""Fit of a running-torque test (a friction sweep) with the drive's one running-torque law.

The record: the drive turned at one or more constant speeds each way, the torque it
needs logged (often from motor current), on the input or the output shaft
(``# torque_side``). The model: ``T = InputFriction.torque(ω, θ) + J α`` on the WG shaft
(`hdsim.model.input_friction`, the law the driven bench uses), with the families of
`hdsim.model.running_terms` switched on. A record on the output shaft is referred to the
WG shaft by the ratio for the fit, and every torque the fit reports is given back on
the file's side.

Speed and acceleration come from the WG angle by Savitzky–Golay differentiation
(Savitzky & Golay, Anal. Chem. 36, 1964); on a plateau the speed is the slope of the
angle over the whole plateau (`hdsim.io.running_checks.sweep_kinematics`). The fit uses the rows where the drive turns
at least half as fast as on its slowest steady plateau: near a reversal the torque
passes through presliding friction that no running law describes, and the speed from
an encoder is least certain there.

Every amplitude enters the law linearly, so the fit is a bounded linear least-squares
problem (`scipy.optimize.lsq_linear`) for each Stribeck speed of a short log-spaced
grid, the best of which is kept. A fit costs milliseconds, so a diagnosis can refit
every candidate on every hold-out fold. The columns span amplitudes the law cannot hold
(a ripple on a Coulomb level of 0); a solution with such amplitudes is replaced by
the best one the law holds (`RunningTerm.holds`), so a family added to a model never
fits worse than the model without it.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace

import numpy as np

from hdsim.errors import InputError
from hdsim.identification.optimizer import FittedRows, effective_n, json_finite, widened_inverse
from hdsim.identification.sweep_nonlinear import nonlinear_columns, refine_nonlinear
from hdsim.io.measurement import Measurement
from hdsim.io.running_checks import Segment, running_levels, shaft_sign, side_factor, sweep_kinematics
from hdsim.model.input_friction import InputFriction
from hdsim.model.running_terms import BASE_TERM, RUNNING_FAMILIES, PositionRipple, RunningTerm, running_term, unit_law
from hdsim.signals import noise_level

__all__ = ["SweepRecord", "Segment", "TorqueFit", "RunningFit", "fit_running"]

#: owner of the columns of a family's other shapes (not in the law)
SHAPE = "shape"
#: rows slower than this fraction of the slowest plateau are left out of the fit
MOVING_FRACTION = 0.5
#: columns (scaled to unit norm) whose smallest singular value is below this share of the
#: largest hold a combination the record does not determine (`bounded_lsq`)
DEGENERATE = 1e-8


@dataclass(frozen=True, eq=False)
class SweepRecord:
    """What the fit needs of a running-torque measurement, on the WG shaft.

    Attributes
    ----------
    measurement : Measurement
        The record.
    speed, accel : numpy.ndarray
        WG speed [rad/s] and acceleration [rad/s²].
    torque : numpy.ndarray
        The torque referred to the WG shaft [N·m].
    side_factor : float
        File torque = ``side_factor`` × WG-shaft torque (1 on the input, the ratio on the output).
    segments : list of Segment
        The constant-speed plateaus.
    moving : numpy.ndarray
        Rows the fit uses (bool).
    velocity_scale : float
        ω_ε of the fitted law [rad/s]: 5 % of the slowest plateau.
    noise_floor : float
        Model-free rms noise of the torque on the WG shaft [N·m].
    output_turns : float
        Span of the output angle [revolutions].
    directions : tuple of int
        The directions the record runs in, by its plateaus (+1 forward, −1 reverse): a
        ramp's stray row of the other sign is no run in that direction.
    """

    measurement: Measurement
    speed: np.ndarray
    accel: np.ndarray
    torque: np.ndarray
    side_factor: float
    segments: list
    moving: np.ndarray
    velocity_scale: float
    noise_floor: float
    output_turns: float
    directions: tuple
    #: columns already computed, by (term, non-linear value): a diagnosis refits the same
    #: terms many times (candidates, hold-out halves, the Stribeck grid)
    cache: dict = field(default_factory=dict, repr=False)

    def columns(self, term: RunningTerm, nonlinear, other: bool = False, keep: bool = True):
        """The term's columns along the record (``other``: its other shapes, or None);
        ``keep`` False: not cached (a value off the grid, met once)."""
        key = (term, nonlinear, other)
        if key in self.cache:
            return self.cache[key]
        meas = self.measurement
        ratio = float(meas.ratio) if meas.ratio is not None else 1.0
        make = term.other_shapes if other else term.columns
        columns = make(self.speed, meas.wg_angle, self.velocity_scale, ratio, nonlinear)
        if keep:
            self.cache[key] = columns
        return columns

    @classmethod
    def of(cls, meas: Measurement | SweepRecord) -> "SweepRecord":
        """The record of a running-torque measurement (a record is its own); InputError if it
        never turns steadily."""
        if isinstance(meas, cls):
            return meas
        if meas.test != "running_torque":
            raise InputError(f"{meas.source}: a {meas.test} test is not a running-torque test")
        side = side_factor(meas)
        speed, accel, segments = sweep_kinematics(meas.time, meas.wg_angle)
        if not segments:
            raise InputError(f"{meas.source}: the drive never turns at a steady speed; a running-torque test "
                             "needs plateaus of constant speed (a friction sweep)")
        slowest = min(abs(s.speed) for s in segments)
        ways = tuple(d for d in (1, -1) if any(np.sign(s.speed) == d for s in segments))
        # turning in a direction the record runs in: a ramp's stray row of the other sign on a
        # one-way record is no run that way, and the law there has no level of its own
        moving = (np.abs(speed) >= MOVING_FRACTION * slowest) & np.isin(np.sign(speed), ways)
        torque = np.asarray(meas.torque, dtype=float) / side
        turns = float(np.ptp(meas.angle)) / (2.0 * math.pi)
        return cls(meas, speed, accel, torque, side, segments, moving, 0.05 * slowest,
                   noise_level(torque, meas.time), turns, ways)

    @property
    def never_run(self) -> tuple:
        """The directions ("forward", "reverse") the record never runs in."""
        return tuple(way for way, d in (("forward", 1), ("reverse", -1)) if d not in self.directions)

    def term(self, name: str) -> RunningTerm:
        """The term of a family (its default form) or a term id, for this record (the ripple
        drops the output's order when the output turned less than once: a periodic term would
        only fit a drift)."""
        term = running_term(name)
        if isinstance(term, PositionRipple) and self.output_turns < 1.0:
            return replace(term, output_order=False)
        return term


@dataclass
class TorqueFit(FittedRows):
    """A least-squares torque law fitted on the rows a record moves (a sweep's, a breakaway's):
    its rms error [N·m], effective sample count and BIC (``n_params``: its free parameters)."""

    record: object
    families: list
    residual: np.ndarray
    rows: np.ndarray
    n_params: int
    fitted: dict
    uncertainty: dict
    #: the drive the fit was made for (`hdsim.fit`'s ``unit``; None: the default unit)
    unit: object

    @property
    def measurement(self) -> Measurement:
        return self.record.measurement

    @property
    def rmse_Nm(self) -> float:
        r = self.residual[self.rows]
        return float(np.sqrt(np.mean(r * r))) if r.size else float("nan")

    @property
    def n_eff(self) -> float:
        return effective_n(self.residual[self.rows])

    def bic(self, n_eff: float | None = None) -> float:
        """``n_eff ln(RSS/n) + k ln n_eff``: the BIC with the residual's effective sample count."""
        n_eff = self.n_eff if n_eff is None else n_eff
        return n_eff * math.log(max(self.rss, 1e-300) / max(self.n, 1)) + self.n_params * math.log(n_eff)


@dataclass
class RunningFit(TorqueFit):
    """The fitted running-torque law and what the fit says about it.

    Attributes
    ----------
    record : SweepRecord
        The record.
    families : list of str
        The families switched on (the base always is).
    law : InputFriction
        The fitted law on the WG shaft.
    inertia : float
        Fitted inertia of motor and WG [kg·m²].
    prediction, residual : numpy.ndarray
        Model and measured-minus-model torque on the file's side [N·m], every row.
    rows : numpy.ndarray
        Rows the fit minimised (bool).
    fitted, uncertainty : dict
        Amplitudes by ``family.name`` on the WG shaft, and their 1-σ uncertainties.
    """

    law: InputFriction
    inertia: float
    prediction: np.ndarray
    #: family -> the id of its form in the law
    forms: dict = field(default_factory=dict)
    #: the amplitudes and their covariance (None without one)
    coordinates: SweepCoordinates | None = None

    def metrics(self) -> dict:
        """``running_torque_forward_Nm`` / ``_reverse_Nm`` on the file's side: one definition
        everywhere (checks, fit, diagnosis, report) — the measured torque averaged over the
        whole WG turns of each direction's plateaus, per unit of angle
        (`hdsim.io.running_checks.running_levels`): a ripple averages out and no model
        enters. A direction with plateaus but less than one whole turn gets the fitted law's
        mean over one turn at its plateau speeds (`running_torque_basis` says which); None
        for a direction the record never runs in."""
        return {f"running_torque_{way}_Nm": value for way, (value, _) in self._running_torques().items()}

    def starting_torque(self) -> dict:
        """The law's starting torque on the file's side [N·m], with its standard uncertainty and
        basis (`hdsim.identification.sweep_start.starting_torque_summary`)."""
        from hdsim.identification.sweep_start import starting_torque_summary

        return starting_torque_summary(self)

    def running_torque_basis(self) -> dict:
        """Direction -> what its running torque rests on (measured turns, or the fitted law)."""
        return {way: basis for way, (_, basis) in self._running_torques().items() if basis}

    def _running_torques(self) -> dict:
        rec = self.record
        side = abs(rec.side_factor)
        # with the sign of the WG's motion, as the checks read the levels
        measured = running_levels(shaft_sign(self.measurement) * np.asarray(self.measurement.torque, dtype=float),
                                  self.measurement.wg_angle, rec.segments)
        grid = np.linspace(0.0, 2.0 * math.pi, 72, endpoint=False)
        out = {}
        for way, direction in (("forward", 1), ("reverse", -1)):
            if measured[way] is not None:
                out[way] = (measured[way], f"measured over {measured[way + '_turns']} whole WG turn(s)")
                continue
            speeds = [s.speed for s in rec.segments if np.sign(s.speed) == direction]
            law = [np.mean(direction * self.law.torque(np.full(grid.size, w), grid)) for w in speeds]
            out[way] = ((float(side * np.mean(law)), "the fitted law's mean over one turn (less than one "
                         "whole turn of steady motion)") if speeds else (None, ""))
        return out

    @property
    def held_at_zero(self) -> dict:
        """``family.name`` -> why: the amplitudes the record does not determine, held at 0 in the
        law (a direction asymmetry on a record that runs one way; `RunningTerm.direction_columns`)."""
        if len(self.record.never_run) != 1:
            return {}
        other = self.record.never_run[0]
        run = "reverse" if other == "forward" else "forward"
        why = (f"not determined by the record: it runs {run} only, where a direction asymmetry is the level "
               f"itself; the law is written with none (the same level {other})")
        terms = [self.record.term(form) for form in self.forms.values()]
        return {f"{t.family}.{n}": why for t in terms for n in t.direction_columns}

    def law_table(self) -> dict:
        """The fitted law as a scenario's ``[input_friction]`` table (WG shaft, SI; rpm for ω_s)."""
        law = self.law
        share = law.coulomb_torque / law.starting_torque if law.starting_torque > 0 else 1.0
        return {"starting_torque_Nm": float(law.starting_torque), "coulomb_share": float(share),
                "stribeck_speed_rpm": float(law.stribeck_speed * 30.0 / math.pi),
                "viscous_Nms": float(law.viscous), "coulomb_asymmetry_Nm": float(law.coulomb_asymmetry),
                "ripple_orders": [float(k) for k in law.ripple_orders],
                "ripple_amplitudes_of_level": [float(r) for r in law.ripple_amplitudes],
                "ripple_phases": [float(p) for p in law.ripple_phases],
                "position_torque_orders": [float(k) for k in law.position_orders],
                "position_torque_amplitudes_Nm": [float(a) for a in law.position_amplitudes],
                "position_torque_phases": [float(p) for p in law.position_phases]}

    def summary(self) -> dict:
        """JSON-ready summary (the ``hdsim fit --json`` object of a running-torque test)."""
        side = abs(self.record.side_factor)
        r = self.residual[self.rows]
        return {
            "test": "running_torque",
            "torque_side": self.measurement.torque_side,
            "effects": list(self.families),
            "rows": self.n,
            "rmse_Nm": self.rmse_Nm,
            "max_abs_error_Nm": float(np.max(np.abs(r))) if r.size else float("nan"),
            "noise_floor_Nm": float(side * self.record.noise_floor),
            "bic": self.bic(),
            "n_params": self.n_params,
            "fitted": {k: float(v) for k, v in self.fitted.items()},
            "uncertainty": json_finite(self.uncertainty),  # null: not determined by the record
            "not_determined": self.held_at_zero,
            "derived": {"inertia_kg_m2": float(self.inertia), **self.starting_torque()},
            "metrics": self.metrics(),
            "running_torque_basis": self.running_torque_basis(),
            "ripple_Nm": [{"order": float(k), "amplitude_Nm": side * a, "phase_rad": float(p), "form": form}
                          for form, orders, amplitudes, phases in (
                              ("ripple", self.law.ripple_orders, self.law.ripple_torques(), self.law.ripple_phases),
                              ("position_torque", self.law.position_orders, self.law.position_amplitudes,
                               self.law.position_phases))
                          for k, a, p in zip(orders, amplitudes, phases)],
            "forms": dict(self.forms),
            "law": self.law_table(),
            "plateau_speeds_rpm": [float(s.speed * 30.0 / math.pi) for s in self.record.segments],
        }

    def to_toml(self) -> str:
        import tomli_w

        doc = {"format": "hdsim-running-fit-1", "test": "running_torque",
               "source": str(self.measurement.source), "torque_side": self.measurement.torque_side,
               "effects": list(self.families), "input_friction": self.law_table(),
               "inertia": {"J_in_kg_m2": float(self.inertia)},
               "metrics": {k: v for k, v in self.metrics().items() if v is not None},
               "fit": {"rows": self.n, "rmse_Nm": self.rmse_Nm, "n_params": self.n_params}}
        head = ("# hdsim running-torque fit. [input_friction] is on the wave-generator shaft and pastes into a\n"
                "# driven scenario's [input_friction] table (docs/cli.md, hdsim fit).\n")
        head += "".join(f"# {key} held at 0: {why}\n" for key, why in self.held_at_zero.items())
        return head + tomli_w.dumps(doc)

    @property
    def drive(self):
        """The drive the sweep was fitted for (``unit``), running the fitted law (`drive_for`).

        ``hdsim.run_scenario(fit.drive, "running_torque")`` runs the measured friction and
        ``hdsim.sobol(fit.drive, {"input_friction.coulomb_torque": (lo, hi)}, …)`` studies it.
        """
        return self.drive_for(self.unit)

    def drive_for(self, unit=None):
        """A drive whose input friction is the fitted law, and its inertia the fitted one.

        The drive is the one `hdsim.fit` starts a locked fit from: ``unit`` (a built-in name,
        a drive file or a `HarmonicDrive`; None: the default unit) with the record's ratio
        and rated torque where it gives them. Its ``input_friction`` becomes the fitted law, its
        ``drive.J_in`` the fitted inertia where the record determines it (`fit.with_fitted_inertia`).

        Torque side: the drive's input friction acts on the wave-generator (input) shaft, and
        so does the law: a record with ``torque_side: output`` was referred to the input when
        read, WG-shaft torque = file torque / ratio (`SweepRecord.side_factor`), so the law goes
        in unchanged, and the drive's running torque on the input times the ratio is the
        record's on the output (`metrics`). Two fields the sweep cannot determine keep the
        drive's values: the mesh-loss coefficient ``μ`` (no load: it would add to ``F_c``
        unseen) and the smoothing speed ``ω_ε`` of the direction switch (the fit's is a
        regularisation below its slowest rows, where ``tanh`` is 1 either way).

        Parameters
        ----------
        unit : str, os.PathLike or HarmonicDrive, optional
            The drive to start from; default the catalog's default unit.

        Returns
        -------
        HarmonicDrive
            That drive with ``input_friction`` = the fitted law [N·m on the WG shaft].
        """
        from hdsim.identification.fit import _unit_model, with_fitted_inertia  # same start as a locked fit's model

        base = _unit_model(unit, self.measurement)
        own = base.input_friction
        law = self.law.with_updates(load_coefficient=own.load_coefficient, velocity_scale=own.velocity_scale)
        sigma = self.uncertainty.get(f"{BASE_TERM.family}.inertia", math.inf)
        return with_fitted_inertia(base, self.inertia, sigma, self.measurement).with_input_friction(law)


def _design(rec: SweepRecord, terms: list[RunningTerm], nonlinear: dict, widened: tuple = (), keep=True) -> tuple:
    """Columns of every term (and the other shapes of the ``widened`` families) plus the inertia
    column: (owners, names, matrix, lower, upper); other shapes are owned by `SHAPE`. On a
    record that runs one way a term's direction columns are left out (held at 0): there they
    are the level's column, and a ramp's stray row of the other sign would pick their value."""
    owners, names, cols, lower, upper = [], [], [], [], []
    one_way = len(rec.directions) == 1
    for term in terms:
        own = rec.columns(term, nonlinear.get(term.family), keep=keep)
        parts = [(term, own.without(term.direction_columns) if one_way else own)]
        if term.family in widened:
            parts.append((SHAPE, rec.columns(term, nonlinear.get(term.family), other=True, keep=keep)))
        for owner, c in parts:
            if c is None:
                continue
            owners += [owner] * len(c.names)
            names += list(c.names)
            cols.append(c.matrix)
            lower += list(c.lower)
            upper += list(c.upper)
    owners.append(BASE_TERM)  # the base model holds the inertia of motor and WG
    names.append("inertia")
    cols.append(rec.accel[:, None])
    lower.append(0.0)
    upper.append(math.inf)
    return owners, names, np.hstack(cols), np.array(lower), np.array(upper)


def bounded_lsq(A, y, lower, upper) -> np.ndarray:
    """The bounded least-squares solution of ``A x = y`` (BVLS on the columns scaled to unit
    norm); round-off may leave it a hair past a bound (a sweep's and a breakaway's fit)."""
    # imported here: scipy.optimize costs about 0.2 s, which a command on a locked record
    # would pay only to register the running-torque kind
    from scipy.optimize import lsq_linear

    scale = np.sqrt(np.sum(A * A, axis=0))
    scale[scale == 0] = 1.0
    scaled = A / scale
    singular = np.linalg.svd(scaled, compute_uv=False)
    if singular.size and singular[-1] < DEGENERATE * singular[0]:
        # columns the record cannot tell apart (a level and its direction asymmetry on a
        # record turning one way): BVLS would pick any of their combinations, ±3e11 N·m that
        # cancel and lose their digits in the law; a ridge far below the data's own
        # directions picks the smallest
        ridge = DEGENERATE * singular[0] * np.eye(scaled.shape[1])
        scaled, y = np.vstack([scaled, ridge]), np.concatenate([y, np.zeros(scaled.shape[1])])
    sol = lsq_linear(scaled, y, bounds=(lower * scale, upper * scale), method="bvls")
    return sol.x / scale


def fit_running(record, families=(), rows=None, widened=(), refine: bool = True, unit=None) -> RunningFit:
    """Fit the running-torque law with the base and ``families`` to a sweep.

    Parameters
    ----------
    record : SweepRecord or Measurement
        A running-torque record.
    families : iterable of str
        Running-torque families (`hdsim.model.running_terms.RUNNING_FAMILIES`).
    rows : array_like of bool, optional
        Rows to fit (a hold-out fold); default every moving row.
    widened : iterable of str, optional
        Families that may also take their other shapes (`RunningTerm.other_shapes`): the
        diagnosis's test for proxies. The law written back holds the law's forms only;
        ``prediction`` and ``residual`` include the other shapes.
    refine : bool
        Refine the Stribeck speed between the grid's points (`hdsim.identification.sweep_nonlinear`);
        False keeps the best grid point, for a fit judged only by what it predicts (a hold-out fold).
    unit : str, os.PathLike or HarmonicDrive, optional
        The drive the fit is for, which its ``.drive`` starts from (default: the catalog default).

    Returns
    -------
    RunningFit
        The fit; ``prediction`` and ``residual`` cover every row.
    """
    rec = SweepRecord.of(record)
    chosen = {running_term(name).family: name for name in families}  # a family, or one of its forms by id
    families = [f for f in RUNNING_FAMILIES if f in chosen]
    terms = [BASE_TERM] + [rec.term(chosen[f]) for f in families]
    use = rec.moving if rows is None else rec.moving & np.asarray(rows, dtype=bool)
    if np.count_nonzero(use) < 10:
        raise InputError(f"{rec.measurement.source}: fewer than 10 rows at a steady running speed to fit")
    y = rec.torque
    plateau_speeds = np.array([abs(s.speed) for s in rec.segments])
    grids = {t.family: t.grid(plateau_speeds) for t in terms if t.grid(plateau_speeds)}
    choices = [dict(zip(grids, values)) for values in itertools.product(*grids.values())]

    def solve(nonlinear, keep=False):
        owners, names, A, lo, hi = _design(rec, terms, nonlinear, tuple(widened), keep)
        x = _held_solution(rec, terms, owners, names, A[use], y[use], lo, hi, nonlinear)
        r = y[use] - A[use] @ x
        return float(r @ r), nonlinear, owners, names, A, x

    best = min((solve(nonlinear, keep=True) for nonlinear in choices), key=lambda s: s[0])
    # between the grid's points: the grid's nearest point can bias the rise (sweep_nonlinear)
    rss, nonlinear, owners, names, A, x = refine_nonlinear(solve, grids, best) if refine else best
    law = _law_of(rec.velocity_scale, terms, owners, names, x, nonlinear)
    inertia = float(x[-1])
    side = rec.side_factor
    prediction = side * (law.torque(rec.speed, rec.measurement.wg_angle) + inertia * rec.accel)
    shapes = [j for j, o in enumerate(owners) if o is SHAPE]
    if shapes:  # the other shapes of widened families (not in the law)
        prediction = prediction + side * (A[:, shapes] @ x[shapes])
    residual = np.asarray(rec.measurement.torque, dtype=float) - prediction
    _check_law_holds(residual[use] / side, rss, y[use])
    n_params = len(names) + len(grids)
    keys = [f"{SHAPE if o is SHAPE else o.family}.{n}" for o, n in zip(owners, names)]  # ``family.name``
    fitted = {k: float(v) for k, v in zip(keys, x)}
    fitted.update({f"{f}.stribeck_speed": float(v) for f, v in nonlinear.items()})
    # the amplitudes and ln ω of each non-linear parameter: its Jacobian column joins the design
    jacobian = nonlinear_columns(lambda values: _design(rec, terms, values, tuple(widened), False)[2][use],
                                 nonlinear, x)
    try:  # the amplitudes' covariance (and the Stribeck speed's, in ln ω)
        cov = widened_inverse(np.column_stack([A[use], jacobian]) if nonlinear else A[use], y[use] - A[use] @ x)
    except np.linalg.LinAlgError:
        cov = None
    sd = [] if cov is None else np.sqrt(np.maximum(np.diag(cov), 0.0))  # 1-σ of each coordinate
    coordinates = None if cov is None else SweepCoordinates(
        tuple(terms), tuple(owners), tuple(names), dict(nonlinear), rec.velocity_scale,
        np.concatenate([x, np.log(list(nonlinear.values()))]), cov, tuple(nonlinear))
    uncertainty = {k: float(s) for k, s in zip(keys, sd)}
    # ω's own: σ(ln ω)·ω
    uncertainty.update({f"{f}.stribeck_speed": float(v * s) for (f, v), s in zip(nonlinear.items(), sd[len(keys):])})
    fit = RunningFit(rec, families, residual, use, n_params, fitted, uncertainty, unit, law, inertia, prediction,
                     {t.family: t.id for t in terms[1:]}, coordinates)
    for key in fit.held_at_zero:  # left out of the design: 0 in the law, not determined
        fitted[key], uncertainty[key] = 0.0, math.inf
    return fit


def _law_of(velocity_scale: float, terms, owners, names, x: np.ndarray, nonlinear: dict):
    """The law with the amplitudes ``x`` written back, or None when a term cannot hold its
    amplitudes (`RunningTerm.holds`)."""
    law = unit_law(velocity_scale)
    for term in terms:
        coefficients = {n: float(v) for o, n, v in zip(owners, names, x) if o is term}
        if not term.holds(law, coefficients):
            return None
        law = term.write_back(law, coefficients, nonlinear.get(term.family))
    return law


def _held_solution(rec, terms, owners, names, A, y, lower, upper, nonlinear) -> np.ndarray:
    """The bounded least-squares amplitudes on rows ``A``, ``y`` that the law holds.

    The columns span amplitudes the law may not hold (a ripple on a Coulomb level that
    fell to 0): written back, such a solution loses a term and fits worse than the model
    without it. Then each family in turn is set to its neutral value (its amplitudes 0)
    and the rest solved again, recursively, and the best held solution is kept: with the
    family just added neutral, that is the solution of the model it contains, so a larger
    model never fits worse. The base always holds, so the recursion ends.
    """
    x = np.clip(bounded_lsq(A, y, lower, upper), lower, upper)  # round-off may step a hair past a bound
    if _law_of(rec.velocity_scale, terms, owners, names, x, nonlinear) is not None:
        return x
    best = None
    for term in terms[1:]:  # the base level (first) is every model's
        keep = np.array([o is not term for o in owners])
        sub = np.zeros_like(x)
        sub[keep] = _held_solution(rec, [t for t in terms if t is not term], [o for o, k in zip(owners, keep) if k],
                                   [n for n, k in zip(names, keep) if k], A[:, keep], y, lower[keep], upper[keep],
                                   nonlinear)
        r = y - A @ sub
        if best is None or float(r @ r) < best[0]:
            best = (float(r @ r), sub)
    return best[1]


def _check_law_holds(residual: np.ndarray, rss: float, y: np.ndarray) -> None:
    """Raise `RuntimeError` (an internal error) when the law written back does not reproduce
    the fitted amplitudes: its residual on the fitted rows must have the least-squares RSS."""
    law_rss = float(residual @ residual)
    if not abs(law_rss - rss) <= 1e-6 * max(rss, 1e-12 * float(y @ y)):
        raise RuntimeError(f"internal error: the running-torque law written back leaves RSS {law_rss:.9g} N²·m², "
                           f"the fitted amplitudes {rss:.9g}: a term did not hold its amplitudes")


@dataclass(frozen=True)
class SweepCoordinates:
    """The fitted amplitudes of a law, their covariance, and what writes amplitudes back
    into a law: the fit's linear coordinates, where its uncertainty is propagated from
    (`hdsim.identification.predictions.sweep_predictions`)."""

    terms: tuple
    owners: tuple
    names: tuple
    nonlinear: dict
    velocity_scale: float
    x: np.ndarray
    covariance: np.ndarray
    #: the families whose ln ω follows the amplitudes in ``x`` (`hdsim.identification.sweep_nonlinear`)
    log_nonlinear: tuple = ()

    @property
    def keys(self) -> list[str]:
        """``family.name`` of each coordinate, in the order of ``x`` and the covariance."""
        return ([f"{SHAPE if o is SHAPE else o.family}.{n}" for o, n in zip(self.owners, self.names)]
                + [f"{f}.log_stribeck_speed" for f in self.log_nonlinear])

    def law(self, x) -> InputFriction | None:
        """The law with coordinates ``x``; None where a term cannot hold them."""
        k = len(self.names)
        nonlinear = {**self.nonlinear, **{f: math.exp(v) for f, v in zip(self.log_nonlinear, x[k:])}}
        return _law_of(self.velocity_scale, self.terms, self.owners, self.names, x[:k], nonlinear)
