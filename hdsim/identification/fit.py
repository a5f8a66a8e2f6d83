"""Fit the model to a bench measurement: least squares with bounds, uncertainties, write-back.

The measured torque drives the model and the measured angle is what it must predict.
The problem (free parameters, transforms, evaluator) is `hdsim.identification.problem`;
the optimiser and the statistics are `hdsim.identification.optimizer`. Every effect
supplies its own free parameters, start values and write-back (`Effect.free_parameters`,
`Effect.fit_updates`), so any registered effect, including one defined outside the
package, can be fitted.

Write-back
----------
`FitResult.save` writes a TOML file: the unit, the effect id of every slot, the
fitted values as dotted ``name = value`` overrides, the angle offset, uncertainties and
fit statistics. `load_fitted` turns it back into a `HarmonicDrive`; the
``[parameters]`` table is exactly what ``hdsim simulate --set name=value`` takes once the
same effects are switched on.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hdsim.errors import InputError, SolverError, unknown_name
from hdsim.identification.optimizer import (FittedRows, bic, check_nested, covariance, effective_n, fit_many,
                                           json_finite, linear_covariance, residuals, uncertainty)
from hdsim.identification.problem import K0_NAME, Evaluator, FitProblem, make_problem, other_starts
from hdsim.io.measurement import Measurement
from hdsim.model import effects as fx
from hdsim.model.drive import SLOTS, HarmonicDrive

#: Newton iterations per sample when a fitted model is evaluated for its result
RESULT_NEWTON_ITERATIONS = 400

__all__ = ["FitResult", "fit", "parse_effects", "build_model", "load_fitted", "result_of",
           "Evaluator", "FitProblem", "make_problem", "fit_many", "bic", "effective_n", "check_nested"]


# --------------------------------------------------------------------------- effects


def parse_effects(text) -> dict[str, str]:
    """``'friction,hardening'``, ``'dahl,tanh'``, ``'friction=dahl'`` or ``{'friction': 'dahl'}``
    -> {family: effect id}.

    Family names take the family's default effect (`hdsim.model.effects.default_effect`); an
    effect id names its family; ``none`` and empty entries are ignored. Unknown names raise
    `InputError` with close matches.
    """
    if text is None:
        return {}
    if isinstance(text, dict):  # {family: effect id}, checked as 'family=id' is
        text = [family if effect_id is None else f"{family}={effect_id}" for family, effect_id in text.items()]
    items = text if isinstance(text, (list, tuple, set)) else str(text).split(",")
    by_id = {}
    for family, classes in fx.FAMILIES.items():
        for effect_id in classes:
            if effect_id != "none":
                by_id.setdefault(effect_id, family)
    chosen: dict[str, str] = {}
    for raw in items:
        item = str(raw).strip()
        if not item or item == "none":
            continue
        family, sep, effect_id = item.partition("=")
        family, effect_id = family.strip(), effect_id.strip()
        if sep:
            if family not in fx.FAMILIES:
                raise unknown_name("effect family", family, fx.FAMILIES)
            if effect_id not in fx.FAMILIES[family]:
                raise unknown_name(f"{family} effect", effect_id, fx.FAMILIES[family])
            if effect_id == "none":
                continue
        elif family in fx.FAMILIES:
            effect_id = fx.default_effect(family)
        elif family in by_id:
            family, effect_id = by_id[family], family
        else:
            raise unknown_name("effect family or effect id", family,
                               list(fx.FAMILIES) + list(by_id))
        if family in chosen and chosen[family] != effect_id:
            raise InputError(f"the effects name two {family} effects, {chosen[family]} and {effect_id}; give one "
                             "per family")
        chosen[family] = effect_id
    return {family: chosen[family] for family in SLOTS if family in chosen}


def _unit_model(unit: str | HarmonicDrive | None, meas: Measurement | None) -> HarmonicDrive:
    from hdsim.model.catalog import load_unit

    model = unit if isinstance(unit, HarmonicDrive) else load_unit(unit)
    updates = {}
    if meas is not None and meas.rated_torque is not None:
        updates["drive.rated_torque"] = float(meas.rated_torque)
    if meas is not None and meas.ratio is not None and abs(meas.ratio) >= 1.0:
        updates["drive.ratio"] = float(meas.ratio)
    return model.with_updates(updates) if updates else model


def with_fitted_inertia(drive, inertia: float, sigma: float, meas: Measurement):
    """``drive`` with ``drive.J_in`` (motor + WG) the fitted inertia on the WG shaft (1-σ
    ``sigma``) less the output's ``J_out/N²``, which turned with it: the drive's rigid inertia
    is then the fitted one. Unchanged where the record does not determine the input's: a
    torque on the output shaft (the motor turned the output), an inertia under twice its
    uncertainty or under the output's share."""
    ratio = float(np.asarray(drive.drive.ratio).reshape(-1)[0])
    own = inertia - float(np.asarray(drive.drive.J_out).reshape(-1)[0]) / ratio ** 2
    if meas.torque_side == "output" or not (inertia > 2.0 * sigma and own > 0.0):
        return drive
    return drive.with_updates({"drive.J_in": own})


def build_model(unit, effects: dict[str, str], meas: Measurement | None = None) -> HarmonicDrive:
    """The unit with exactly ``effects`` switched on, others "none".

    An effect the unit already holds keeps its values; another starts from its class's
    placeholder values for this drive's rating and stiffness (`Effect.placeholder`).
    """
    base = _unit_model(unit, meas)
    T_N = float(np.asarray(base.drive.rated_torque).reshape(-1)[0])
    K = float(np.asarray(base.base_stiffness).reshape(-1)[0])
    slots = {}
    for family in SLOTS:
        effect_id = effects.get(family, "none")
        current = getattr(base, family)
        if current.id == effect_id:
            slots[family] = current
        elif effect_id == "none":
            slots[family] = fx.NO_EFFECT[family]
        else:
            cls = fx.effect_class(family, effect_id)
            try:
                slots[family] = cls.placeholder(T_N, K)
            except NotImplementedError as exc:
                raise InputError(f"cannot fit {family} effect '{effect_id}': {exc}") from None
    return base.with_effects(**slots)


@dataclass
class FitResult(FittedRows):
    """A fitted model and what the fit says about it (``params``: dotted model overrides;
    ``internal``: the fitted coordinates K0, the hardening's curvature and T_s, …;
    ``uncertainty`` keyed like ``internal``, plus ``offset_rad``).

    Attributes
    ----------
    model : HarmonicDrive
        The unit with the fitted effects and parameter values.
    effects : dict
        Effect id per family (only the families switched on).
    params : dict
        Fitted values by dotted name [SI].
    uncertainty : dict
        One-standard-deviation uncertainty by dotted name (and ``offset_rad``).
    offset : float
        Angle offset [rad] (encoder zero), fitted, not counted as error.
    prediction, residual : numpy.ndarray
        Predicted and measured-minus-predicted angle [rad] at every sample.
    rows : numpy.ndarray
        Boolean mask of the rows the fit minimised (all rows unless a hold-out fit).
    coordinates : FittedCoordinates or None
        The fit's own coordinates and their covariance, for propagating its uncertainty;
        None when the fit has no free parameter or no covariance.
    """

    measurement: Measurement
    model: HarmonicDrive
    effects: dict
    params: dict
    uncertainty: dict
    offset: float
    prediction: np.ndarray
    residual: np.ndarray
    rows: np.ndarray
    n_params: int
    ke_coefficients: dict = field(default_factory=dict)
    #: the cost of the model this one contains, evaluated in this one's structure (its nested
    #: start, `hdsim.identification.problem.NestedStart`); None without one
    contained_cost: float | None = None
    iterations: int = 0
    unit: str = ""
    internal: dict = field(default_factory=dict)
    derived: dict = field(default_factory=dict)
    converged: bool = True
    message: str = ""
    coordinates: "FittedCoordinates | None" = None

    @property
    def families(self) -> list[str]:
        return [f for f in SLOTS if f in self.effects]

    @property
    def drive(self) -> HarmonicDrive:
        """The fitted drive, which `hdsim.run_scenario` and `hdsim.sobol` take as it is."""
        return self.model

    def rmse(self, rows=None) -> float:
        r = self.residual if rows is None else self.residual[rows]
        return float(np.sqrt(np.mean(r * r)))

    @property
    def rmse_rad(self) -> float:
        return self.rmse(self.rows)

    @property
    def max_abs_rad(self) -> float:
        return float(np.max(np.abs(self.residual[self.rows])))

    @property
    def bic(self) -> float:
        return bic(self.rss, self.n, self.n_params)

    def summary(self) -> dict:
        """JSON-ready summary (the ``hdsim fit --json`` object)."""
        return {
            "test": self.measurement.test,
            "unit": self.unit,
            "effects": self.families,
            "effect_ids": dict(self.effects),
            "rows": self.n,
            "rmse_rad": self.rmse_rad,
            "max_abs_error_rad": self.max_abs_rad,
            "bic": self.bic,
            "n_params": self.n_params,
            "offset_rad": self.offset,
            "params": {k: float(v) for k, v in self.params.items()},
            "fitted": {k: float(v) for k, v in self.internal.items()},
            "uncertainty": json_finite(self.uncertainty),  # None: the record does not determine it
            "derived": {k: float(v) for k, v in self.derived.items()},
            "iterations": self.iterations,
            "converged": self.converged,
            "message": self.message,
        }

    def to_toml(self) -> str:
        """The fitted parameter set as TOML (see the module doc and `load_fitted`)."""
        import tomli_w

        from hdsim.model.drive_file import drive_table

        summary = self.summary()
        doc = {
            "format": "hdsim-fit-1",
            "unit": self.unit,
            "test": self.measurement.test,
            "source": str(self.measurement.source),
            "effects": {f: getattr(self.model, f).id for f in SLOTS},
            # the record's rated torque and ratio, which the fit put on the unit (`_unit_model`),
            # travel with the fitted values: reloaded without them, a fit on another unit's
            # record gave another stiffness law (its breakpoints scale with the rated torque)
            "parameters": {**{name: float(np.ravel(self.model.params()[name])[0])
                              for name in ("drive.rated_torque", "drive.ratio")}, **summary["params"]},
            "offset": {"angle_offset_rad": float(self.offset)},
            "uncertainty": {k: v for k, v in summary["uncertainty"].items() if v is not None},
            "fit": {key: summary[key] for key in ("rows", "rmse_rad", "max_abs_error_rad", "bic", "n_params")},
        }
        table = drive_table(self.model)
        if table:  # a drive that is no built-in unit: the file's table rebuilds it
            doc["drive"] = table
        head = ("# hdsim fitted parameter set. Load with hdsim.identification.fit.load_fitted(path); the\n"
                "# [parameters] table holds dotted overrides of the unit, in SI units.\n")
        return head + tomli_w.dumps(doc)


#: the top-level keys of a fit file (`FitResult.to_toml`)
FIT_FILE_KEYS = ("format", "unit", "test", "source", "effects", "parameters", "offset", "uncertainty", "fit", "drive")


def load_fitted(path) -> HarmonicDrive:
    """A `HarmonicDrive` from a file written by `FitResult.save`."""
    from hdsim.model.catalog import load_unit
    from hdsim.model.drive_file import require_number
    from hdsim.scenarios.scenario import read_toml

    path = Path(path)
    doc = read_toml(path, "fit")
    if doc.get("format") == "hdsim-running-fit-1":
        raise InputError(f"{path}: a running-torque fit holds the friction law of the wave-generator shaft, not a "
                         "drive: paste its [input_friction] table into a driven scenario")
    if doc.get("format") != "hdsim-fit-1":
        raise InputError(f"{path}: not an hdsim fit file (format = 'hdsim-fit-1' expected)")
    # the file may have been edited by hand: check its shape before using it. A file missing
    # what `FitResult.to_toml` always writes is refused, not read as the stock unit (a
    # truncated file had loaded as the catalog drive with its default effects)
    unknown = sorted(set(doc) - set(FIT_FILE_KEYS))
    if unknown:
        raise unknown_name(f"key in {path}", unknown[0], FIT_FILE_KEYS)
    missing = [key for key in ("unit", "effects", "parameters") if key not in doc]
    if missing:
        raise InputError(f"{path}: an incomplete fit file: no {', '.join(missing)} (a file written by hdsim fit "
                         "has unit, [effects] and [parameters])")
    unit, effects, params = doc["unit"], doc["effects"], doc["parameters"]
    if not isinstance(unit, str):
        raise InputError(f"{path}: unit must be a unit name, got {unit!r}")
    for table, value in (("effects", effects), ("parameters", params)):
        if not isinstance(value, dict):
            raise InputError(f"{path}: [{table}] must be a table, got {value!r}")
    drive = doc.get("drive")
    if drive is None:
        model = load_unit(unit or None)
    elif isinstance(drive, dict):
        from hdsim.model.drive_file import drive_from_table

        model = drive_from_table(drive, str(path))
    else:
        raise InputError(f"{path}: [drive] must be a table of a drive file's keys, got {drive!r}")
    params = dict(params)
    for key, value in params.items():  # as a drive file's
        require_number(path, f"parameters.{key}", value)
    slots = {}
    for family, effect_id in effects.items():
        if family not in fx.FAMILIES:
            raise unknown_name(f"effect family in {path}", family, fx.FAMILIES)
        if not isinstance(effect_id, str):
            raise InputError(f"{path}: effects.{family} must be an effect id, got {effect_id!r}")
        if effect_id == "none":
            slots[family] = fx.NO_EFFECT[family]
            continue
        cls = fx.effect_class(family, effect_id)
        current = getattr(model, family)
        fields = list(cls.param_meta())
        for key in params:  # a misspelt field had surfaced as "needs <field>", without the file
            if key.startswith(family + ".") and key.split(".", 1)[1] not in fields:
                raise unknown_name(f"parameter of {family}.{effect_id} in {path}", key,
                                   [f"{family}.{f}" for f in fields])
        values = {}
        for f in fields:
            key = f"{family}.{f}"
            if key in params:
                values[f] = params.pop(key)
            elif current.id == effect_id:
                values[f] = getattr(current, f)
        slots[family] = fx.make_effect(family, effect_id, **values)
    model = model.with_effects(**slots)
    return model.with_updates(params) if params else model


# --------------------------------------------------------------------------- results


def result_of(ev: Evaluator, prob: FitProblem, unit: str = "") -> FitResult:
    """Evaluate a finished problem once more and package it as a `FitResult`."""
    internal = {k: float(np.asarray(v).reshape(-1)[0]) for k, v in prob.phys(prob.u[None, :]).items()}
    updates = {k: float(np.asarray(v).reshape(-1)[0]) for k, v in prob.updates(prob.u[None, :]).items()}
    model = prob.model.with_updates(updates)
    # the optimiser keeps the twist of the point it ended on: evaluating it again would
    # cost a whole pass over the record per fit (a fifth of a diagnosis)
    twist = prob.twist_at_u if prob.twist_at_u is not None else ev.twist(model)
    if not np.all(np.isfinite(twist)):
        # a very stiff friction law (σ ~ 1e8) can need more bisections of its bracket than the
        # optimiser's trials are given; the result is evaluated once, so it may take them
        twist = ev.twist(model, max_iter=RESULT_NEWTON_ITERATIONS)
    if not np.all(np.isfinite(twist)):
        raise SolverError(f"the model {', '.join(prob.names)} cannot be evaluated on "
                          f"this record: {prob.message or 'the torque balance has no solution'}")
    r_rows, full, coef = residuals(ev, prob, twist)
    if prob.nested is not None and prob.nested.r is not None:  # the optimiser never ends above it
        check_nested(float(r_rows[0] @ r_rows[0]), prob.nested.cost, prob.label or ", ".join(prob.names))
    coef = coef[0]
    offset = float(coef[0])
    linear = {}
    if prob.basis.shape[1] > 1:
        effect, linear = model.kinematic_error.from_linear(coef[1:])
        model = model.with_effects(kinematic_error=effect)
        updates.update({f"kinematic_error.{k}": v for k, v in linear.items()})
    cov = covariance(prob, r_rows[0])
    unc = uncertainty(prob, cov)
    if linear:
        kinematic = model.kinematic_error.linear_uncertainty(coef[1:], linear_covariance(prob, r_rows[0])[1:, 1:])
        unc.update({f"kinematic_error.{k}": v for k, v in kinematic.items()})
    coordinates = fitted_coordinates(prob, cov)
    prediction = ev.y - full[0]
    effects = {f: getattr(model, f).id for f in SLOTS if not getattr(model, f).is_null}
    derived = {"K0_Nm_per_rad": float(np.asarray(model.base_stiffness).reshape(-1)[0])}
    hardening_values = {k.partition(".")[2]: v for k, v in internal.items() if k.startswith("hardening.")}
    ratio = model.hardening.stiffness_ratio(hardening_values) if hardening_values else 1.0
    if ratio != 1.0:
        derived["K_inf_Nm_per_rad"] = float(ratio) * internal[K0_NAME]
    return FitResult(measurement=ev.meas, model=model, effects=effects, params=updates,
                     uncertainty=unc, offset=offset, prediction=prediction, residual=full[0],
                     rows=prob.rows.copy(), n_params=len(prob.names) + prob.basis.shape[1],
                     ke_coefficients=linear, iterations=prob.iterations, unit=unit or prob.model.name,
                     internal=internal, derived=derived, converged=prob.message.startswith("converged"),
                     message=prob.message, coordinates=coordinates)


@dataclass(frozen=True)
class FittedCoordinates:
    """The fit's own coordinates ``u`` (log and logistic transforms of the parameters, which
    keep every value in its bounds) and their covariance: where the fit's Gaussian
    approximation is made, so where its uncertainty is propagated from
    (`hdsim.identification.predictions`).

    Attributes
    ----------
    problem : FitProblem
        The fit's structure, without its record (the map from ``u`` to the model).
    u : numpy.ndarray
        The fitted coordinates.
    covariance : numpy.ndarray
        Their covariance, widened for a correlated residual (`optimizer.covariance`).
    """

    problem: FitProblem
    u: np.ndarray
    covariance: np.ndarray

    def updates(self, U) -> dict:
        """Dotted model updates (arrays) for rows of coordinates ``U``."""
        return self.problem.updates(np.atleast_2d(U))


def fitted_coordinates(prob: FitProblem, cov) -> FittedCoordinates | None:
    """`FittedCoordinates` of a finished problem, None without a covariance."""
    if cov is None:
        return None
    k = prob.u.size
    bare = dataclasses.replace(prob, rows=prob.rows[:0], basis=prob.basis[:0], J=None, r=None, twist_at_u=None,
                               nested=None)
    return FittedCoordinates(bare, prob.u.copy(), np.asarray(cov[:k, :k], dtype=float))


# --------------------------------------------------------------------------- API


def fit(meas: Measurement, effects=None, *, unit=None, rows=None, start: dict | None = None,
        max_steps: int | None = None) -> FitResult:
    """Fit the base model plus ``effects`` to a measurement.

    Parameters
    ----------
    meas : Measurement
        From `hdsim.io.measurement.load_measurement`.
    effects : str, list or dict, optional
        Families or effect ids, or {family: effect id} (see `parse_effects`); none means the
        base model (linear compliance and the angle offset).
    unit : str or HarmonicDrive, optional
        Built-in unit name (default: the catalog default) or a model to start from.
    rows : array_like of bool, optional
        Fit only these rows (hold-out fits); the residual is reported everywhere.
    start : dict, optional
        Starting values by dotted name (others from the data).
    max_steps : int, optional
        Quasi-static steps at most (longer records are stepped on a sub-grid); default
        `hdsim.identification.problem.STEP_BUDGET`.

    Returns
    -------
    FitResult
        A twist test's fit (`hdsim.fit` fits a record of any test kind).
    """
    model = build_model(unit, parse_effects(effects), meas)
    ev = Evaluator(meas, max_steps=max_steps)
    # the effects' other start values run in the same lockstep (about free); the lowest cost wins
    starts = [start] + [{**(start or {}), **alt} for alt in other_starts(model, meas)]
    probs = [make_problem(model, meas, ev, rows=rows, start=s) for s in starts]
    fit_many(ev, probs)
    return result_of(ev, min(probs, key=lambda p: p.cost), unit=model.name)
