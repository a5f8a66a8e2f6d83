"""The least-squares problem of a fit: free parameters, transforms, start values, evaluator.

The measured torque drives the model and the measured angle is what it must predict.
The model is a `HarmonicDrive` whose slots hold the chosen effects; it is evaluated
by the quasi-static bench evaluator (`hdsim.simulation.quasistatic`: inertia
dropped, the library's effect laws), so the fitted model is an ordinary model that
the dynamic simulator can run again.

Free parameters
---------------
The base model's low-load stiffness ``K0`` plus what each effect declares
(`Effect.free_parameters`: names, bounds, start values from the data). Inside the
optimiser each parameter is mapped to an unbounded coordinate (``p = lo + e^u`` for a
one-sided bound, ``p = lo + (hi − lo)·sigmoid(u)`` for two), so every trial model is
valid. ``K0`` (and a hardening law's high-load stiffness ratio) is turned into model
parameters by `split_stiffness`; each effect maps its own fitted values back onto its
fields (`Effect.fit_updates`).

A start that holds a fitted model's values (``stiffness.K0`` and its families') also
gives the point where the families that model lacks are at their neutral values
(`Effect.neutral_start`, mapped exactly, bounds included): there the cost is the fitted
model's, and the optimiser never ends above it (`NestedStart`), so a larger model is
never fitted worse than the model it contains.

The angle offset and, for a kinematic-error test, the coefficients of the
kinematic-error effect's linear basis (`KinematicError.linear_basis`) are solved exactly
for every trial by linear least squares (variable projection), so the offset is
always fitted and never counted as error.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from hdsim.errors import InputError
from hdsim.io.measurement import Measurement
from hdsim.model.drive import SLOTS, Calibration, HarmonicDrive, compliance_chain
from hdsim.model.effects import FitContext
from hdsim.signals import loading_direction
from hdsim.simulation.quasistatic import locked_twist, stackable_groups

__all__ = ["K0_NAME", "Evaluator", "FitProblem", "NestedStart", "fit_context", "make_problem", "nested_start",
           "split_stiffness"]

#: the base model's free parameter: the low-load stiffness K0 [N·m/rad] (internal)
K0_NAME = "stiffness.K0"
#: engagement ratio used when the structure must be stiffened to reach K∞
E_INF_CAP = 100.0
#: the stiffened structure's modulus is at most this multiple of the nominal one
E_MAX_FACTOR = 1e6


# --------------------------------------------------------------------------- data signatures


def relative_angle(meas: Measurement) -> np.ndarray:
    """Angle relative to the kinematic ideal [rad] (stiffness test: the angle itself)."""
    if meas.wg_driven:
        return meas.kinematic_error
    return np.asarray(meas.angle, dtype=float)


def loading_slope(meas: Measurement, lo: float = 0.1, hi: float = 0.5) -> float:
    """Secant stiffness [N·m/rad] from angle vs torque for lo < |T|/max|T| < hi."""
    T = np.asarray(meas.torque, dtype=float)
    y = relative_angle(meas)
    a = np.abs(T) / max(np.max(np.abs(T)), 1e-12)
    m = (a > lo) & (a < hi)
    if np.count_nonzero(m) < 5 or np.ptp(T[m]) <= 0:
        m = np.ones_like(T, dtype=bool)
    if np.ptp(T[m]) <= 0:
        return float("nan")
    slope = np.polyfit(T[m], y[m], 1)[0]
    return 1.0 / slope if slope > 0 else float("nan")


@functools.lru_cache(maxsize=16)  # a diagnosis asks once per candidate and fold: same records
def zero_torque_signatures(meas: Measurement) -> dict:
    """Loop width and step at zero torque [rad], median |dT/dt| [N·m/s] (cached: read, never
    change, the dict it returns)."""
    T = np.asarray(meas.torque, dtype=float)
    y = relative_angle(meas)
    Tmax = max(np.max(np.abs(T)), 1e-12)
    sign, speed = loading_direction(meas.time, T)
    out = {"loop_width": 0.0, "step": 0.0, "rate": float(np.median(speed))}
    near = (np.abs(T) < 0.15 * Tmax) & (np.abs(T) > 0.02 * Tmax)
    values = {}
    for direction in (+1, -1):
        on = near & (sign == direction)
        pos, neg = on & (T > 0), on & (T < 0)
        if np.count_nonzero(pos) >= 3 and np.count_nonzero(neg) >= 3:
            values[direction] = (np.polyfit(T[pos], y[pos], 1)[1], np.polyfit(T[neg], y[neg], 1)[1])
    if len(values) == 2:
        out["loop_width"] = float(max(0.5 * sum(values[-1]) - 0.5 * sum(values[+1]), 0.0))
        out["step"] = float(max(0.5 * ((values[+1][0] - values[+1][1]) + (values[-1][0] - values[-1][1])), 0.0))
    return out


def fit_context(meas: Measurement, model: HarmonicDrive) -> FitContext:
    """What the record says before any fit (loading slope, loop width, step, rate)."""
    linear = model.hardening.is_null
    K = loading_slope(meas, 0.1, 0.6) if linear else loading_slope(meas, 0.05, 0.3)
    if not np.isfinite(K):
        K = float(model.base_stiffness)
    sig = zero_torque_signatures(meas)
    return FitContext(stiffness=float(K), max_torque=float(np.max(np.abs(meas.torque))),
                      loop_width=sig["loop_width"], step=sig["step"], rate=sig["rate"], linear_spring=linear,
                      test=meas.test)


# --------------------------------------------------------------------------- stiffness split


@functools.lru_cache(maxsize=32)  # an optimiser asks for the same structure at every pass
def _nominal_split(geometry, wave_generator) -> tuple[float, float]:
    """(structural, mesh-zone) compliance of the nominal structure with κ = 1 [rad/(N·m)]."""
    chain = compliance_chain(geometry, wave_generator, 1.0)
    return float(np.asarray(chain.structure)), float(np.asarray(chain.mesh_zone))


def split_stiffness(model: HarmonicDrive, K0, ratio=1.0, e_cap: float = E_INF_CAP):
    """Model parameters that give low-load stiffness ``K0`` and high-load ``K∞ = ratio·K0``.

    The unit's closed forms split the compliance into a structural part ``C_s`` and a
    mesh-zone part ``κ C_m``; hardening can only remove mesh-zone compliance
    (``K∞ = 1/(C_s + κ C_m/e)``). With the nominal geometry ``κ`` sets K0 and the
    engagement ratio ``e`` sets K∞. When K∞ (or K0) is beyond what the nominal structure
    allows, the flexspline modulus ``E`` is raised (``C_s ∝ 1/E``) so that ``e = e_cap``.
    The bench response depends on K0 and K∞ only, so this choice is a convention of the
    write-back, not a fit assumption.

    Returns
    -------
    tuple
        (dotted updates {name: array}, engagement ratio array in [1, 100]).
    """
    K0 = np.asarray(K0, dtype=float)
    ratio = np.broadcast_to(np.asarray(ratio, dtype=float), K0.shape)
    g, wg = model.geometry, model.wave_generator
    try:
        cs0, cm0 = _nominal_split(g, wg)
    except TypeError:  # a batch geometry (arrays) cannot be a cache key
        cs0, cm0 = _nominal_split.__wrapped__(g, wg)
    E0 = float(np.asarray(g.E))
    C0 = 1.0 / K0
    Cinf = 1.0 / (ratio * K0)
    hard = ratio > 1.0 + 1e-12
    kappa_a = (C0 - cs0) / cm0
    with np.errstate(divide="ignore", invalid="ignore"):
        e_a = np.where(hard, kappa_a * cm0 / (Cinf - cs0), 1.0)
    ok = (kappa_a > 1e-3) & (~hard | ((Cinf > cs0) & (e_a >= 1.0) & (e_a <= e_cap)))
    # stiffen the structure: e = e_cap (or the structure takes half of C0 without hardening)
    share = np.clip(np.where(hard, (1.0 - 1.0 / ratio) / (1.0 - 1.0 / e_cap), 0.5), 0.0, 1.0 - 1e-9)
    cs_target = C0 * (1.0 - share)
    # an optimiser's far trial (K0 → ∞, K∞/K0 beyond the cap) would ask for an infinite or
    # negative modulus; it is held at a finite one, a valid model whose cost sends it back
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        E_b = np.clip(np.nan_to_num(E0 * cs0 / cs_target, nan=E0, posinf=E_MAX_FACTOR * E0), E0,
                      E_MAX_FACTOR * E0)
    if np.all(ok):  # the nominal structure serves every row (the common case): no second chain
        cm_b = cm0
    else:
        cm_b = np.asarray(compliance_chain(replace(g, E=np.where(ok, E0, E_b)), wg, 1.0).mesh_zone, dtype=float)
    kappa_b = share * C0 / cm_b
    # an extreme trial (K∞ barely above K0 on the stiffened branch) may ask for a κ outside its
    # physical range; the trial is then held at the bound instead of failing the whole batch
    lo, hi = Calibration.param_meta()["kappa_mesh"]["bounds"]
    with np.errstate(invalid="ignore"):
        kappa = np.nan_to_num(np.where(ok, kappa_a, kappa_b), nan=hi, posinf=hi, neginf=lo)
    out = {"calibration.kappa_mesh": np.clip(kappa, lo, hi)}
    if not np.all(ok):
        out["flexspline.E"] = np.where(ok, E0, E_b)
    e = np.where(ok, e_a, np.where(hard, e_cap, 1.0))
    return out, np.clip(e, 1.0, 100.0)


# --------------------------------------------------------------------------- transforms

#: the ends of an optimiser coordinate: e^±700 is as far as a float reaches without overflow,
#: so a bound maps to its value within 1e-304 of the parameter's range
U_END = 700.0


@dataclass(frozen=True)
class Transform:
    """Bounded physical parameter ↔ unbounded optimiser coordinate."""

    lo: float
    hi: float

    def to_phys(self, u):
        u = np.asarray(u, dtype=float)
        if math.isfinite(self.hi):
            return self.lo + (self.hi - self.lo) / (1.0 + np.exp(-np.clip(u, -U_END, U_END)))
        return self.lo + np.exp(np.clip(u, -U_END, U_END))

    def to_internal(self, p, exact: bool = False):
        """The coordinate of ``p``. A start is kept a little inside the bounds, where the
        optimiser can move it; ``exact`` maps a point to reproduce (a fitted optimum, a
        neutral value on a bound) to the coordinate whose value it is, a bound to the
        end of the coordinate (±`U_END`)."""
        p = float(p)
        span = self.hi - self.lo
        if math.isfinite(self.hi):
            f = (p - self.lo) / span
            if exact:
                return -U_END if f <= 0.0 else U_END if f >= 1.0 else math.log(f) - math.log1p(-f)
            f = min(max(f, 1e-12), 1.0 - 1e-9)
            return math.log(f / (1.0 - f))
        if exact and p <= self.lo:
            return -U_END
        return math.log(max(p - self.lo, 1e-300))

    def dphys_du(self, u):
        u = np.asarray(u, dtype=float)
        if math.isfinite(self.hi):
            s = 1.0 / (1.0 + np.exp(-np.clip(u, -U_END, U_END)))
            return (self.hi - self.lo) * s * (1.0 - s)
        return np.exp(np.clip(u, -U_END, U_END))


def _k0_transform(model: HarmonicDrive) -> Transform:
    """K0 > the stiffness with a mesh zone 900 times softer than the unit's calibrated one.

    The bound sits two to three orders of magnitude below any stiffness the unit's record
    can show, so the fit's path (``log(K0 − bound)``) is shaped by the record, not the unit.
    """
    chain = model.compliance()
    cs, cm = float(np.asarray(chain.structure)), float(np.asarray(chain.mesh_zone))
    return Transform(1.0 / (cs + 900.0 * cm), math.inf)


# --------------------------------------------------------------------------- evaluator


#: quasi-static steps per pass at most on a long record (`hdsim.simulation.quasistatic.sample_grid`).
#: Not lower: at 2500 the interpolated twist of a friction-and-hardening record is off by
#: a visible part of the encoder noise, and a diagnosis of hidden hardening behind friction
#: scored it −533 instead of −1825 and then added backlash for the rest
STEP_BUDGET = 4000


class Evaluator:
    """Model predictions and the linear (projected) part for one measurement.

    Stiffness test: predicted angle = offset + quasi-static twist under the measured
    torque. Kinematic-error test: predicted output angle = offset + wg/ratio + twist under
    the measured load torque + kinematic error (the kinematic-error effect's linear basis).
    """

    def __init__(self, meas: Measurement, max_steps: int | None = None):
        max_steps = STEP_BUDGET if max_steps is None else int(max_steps)
        self.meas = meas
        self.t = np.asarray(meas.time, dtype=float)
        self.T = np.asarray(meas.torque, dtype=float)
        self.y = np.asarray(meas.angle, dtype=float)
        self.n = self.t.size
        if not np.ptp(self.T) > 0.0:
            raise InputError(f"{meas.source}: the torque never changes (it is {self.T[0]:g} N·m throughout): "
                             "there is nothing to fit")
        # all samples up to max_steps, else a step budget (the grid adapts to each batch)
        self.grid = None if self.n <= max_steps else int(max_steps)
        if meas.wg_driven:
            self.wg = np.asarray(meas.wg_angle, dtype=float)
            self.ideal = self.wg / float(meas.ratio)
        else:
            self.wg = None
            self.ideal = np.zeros(self.n)
        self.y_rel = self.y - self.ideal

    def basis(self, model: HarmonicDrive) -> np.ndarray:
        """The columns solved linearly: the offset, then the kinematic error's basis."""
        ones = np.ones((self.n, 1))
        if self.wg is None:
            return ones
        extra = model.kinematic_error.linear_basis(self.wg, self.ideal)
        return ones if extra is None else np.hstack([ones, extra])

    def twist(self, models, max_iter: int = 60) -> np.ndarray:
        """(M, n) quasi-static twist of the stacked models; NaN rows where the balance
        could not be solved within ``max_iter`` Newton iterations per sample (the optimiser
        treats them as failed trials)."""
        models = [models] if isinstance(models, HarmonicDrive) else list(models)
        # models with different effect classes in one slot (a family tried in another
        # form) cannot share a batch: one pass per group, rows put back in order
        first = np.concatenate([[0], np.cumsum([m.batch_size for m in models])])
        out = np.empty((first[-1], self.n))
        for group in stackable_groups(models):
            part = locked_twist([models[i] for i in group], self.t, self.T, grid=self.grid, on_failure="nan",
                                max_iter=max_iter)
            rows = np.concatenate([np.arange(first[i], first[i + 1]) for i in group])
            out[rows] = part
        return out


# --------------------------------------------------------------------------- problems


@dataclass
class NestedStart:
    """The start of a fit that adds families to a fitted model: that model's optimum with
    the added families at their neutral values (`Effect.neutral_start`), whose cost is the
    fitted model's. The optimiser evaluates it on its first pass and goes back to it if
    the fit ends above it (`hdsim.identification.optimizer.fit_many`), so a larger model
    is never fitted worse than the model it contains."""

    u: np.ndarray  # internal coordinates
    families: tuple  # the families at their neutral values
    cost: float = math.nan  # RSS on the problem's rows [rad²], once evaluated
    r: np.ndarray | None = None  # residual on the problem's rows, once evaluated
    twist: np.ndarray | None = None  # twist (n,) at ``u``, once evaluated
    kept: bool = False  # the fit ended above it and went back to it


@dataclass
class FitProblem:
    """One least-squares fit: a model structure, its free parameters and the rows it fits."""

    model: HarmonicDrive
    names: list[str]
    transforms: list[Transform]
    rows: np.ndarray  # bool (n,): the rows whose residual is minimised
    u: np.ndarray  # internal coordinates, current
    basis: np.ndarray  # (n, k) columns solved linearly (offset first)
    label: str = ""
    max_iter: int = 25
    # optimiser state
    cost: float = np.inf
    lam: float = 1e-2
    J: np.ndarray | None = None
    r: np.ndarray | None = None
    done: bool = False
    iterations: int = 0
    stalls: int = 0
    message: str = ""
    #: the twist (n,) at ``u``, kept from the pass that evaluated it (`result_of` reuses it)
    twist_at_u: np.ndarray | None = None
    #: the contained fitted model's optimum, when the start is one (`make_problem`)
    nested: NestedStart | None = None

    def phys(self, U: np.ndarray) -> dict[str, np.ndarray]:
        """Fitted coordinates (K0 and the effects' dotted free parameters) for rows of U."""
        U = np.atleast_2d(U)
        return {name: tr.to_phys(U[:, j]) for j, (name, tr) in enumerate(zip(self.names, self.transforms))}

    def updates(self, U: np.ndarray) -> dict[str, np.ndarray]:
        """Dotted model updates for rows of U (K0 and stiffness ratios mapped by `split_stiffness`)."""
        values = self.phys(U)
        K0 = values.pop(K0_NAME)
        per_family = {family: {} for family in SLOTS}
        for name, value in values.items():
            family, _, local = name.partition(".")
            per_family[family][local] = value
        ratio = self.model.hardening.stiffness_ratio(per_family["hardening"])
        out, engagement = split_stiffness(self.model, K0, ratio)
        for family in SLOTS:
            if per_family[family]:
                out.update(getattr(self.model, family).fit_updates(per_family[family], engagement=engagement))
        return out

    def batch_model(self, U: np.ndarray) -> HarmonicDrive:
        return self.model.with_updates(self.updates(U))

    @functools.cached_property
    def row_index(self) -> np.ndarray | None:
        """Indices of the fitted rows, None when they are all (no copy needed)."""
        return None if bool(np.all(self.rows)) else np.flatnonzero(self.rows)

    @functools.cached_property
    def basis_pinv(self) -> np.ndarray:
        """Pseudo-inverse of the basis on the fitted rows, (k, n_rows): the linear part's
        least-squares solution, the same at every pass."""
        return np.linalg.pinv(self.basis[self.rows])

    def fd_steps(self) -> np.ndarray:
        return 1e-5 * np.maximum(1.0, np.abs(self.u))


def other_starts(model: HarmonicDrive, meas: Measurement) -> list[dict]:
    """Start values by dotted name worth a fit of their own (`Effect.other_starts`)."""
    context = fit_context(meas, model)
    return [{f"{family}.{name}": float(v) for name, v in values.items()}
            for family in SLOTS for values in getattr(model, family).other_starts(context)]


def make_problem(model: HarmonicDrive, meas: Measurement, ev: Evaluator, rows=None, start: dict | None = None,
                 label: str = "", max_iter: int = FitProblem.max_iter) -> FitProblem:
    """The fit of ``model`` to ``meas``: K0 plus each effect's free parameters.

    ``start`` overrides start values by name (``stiffness.K0``, ``family.parameter``);
    ``max_iter`` caps the optimiser's iterations.
    """
    context = fit_context(meas, model)
    start = start or {}
    names, transforms, values = [K0_NAME], [_k0_transform(model)], [context.stiffness]
    for family in SLOTS:
        for fp in getattr(model, family).free_parameters(context):
            names.append(f"{family}.{fp.name}")
            transforms.append(Transform(fp.lower, fp.upper))
            values.append(fp.start)
    # a start value that is not finite (from a fit that failed) falls back to the data's
    values = [start[n] if np.isfinite(start.get(n, np.nan)) else v for n, v in zip(names, values)]
    u = np.array([tr.to_internal(v) for tr, v in zip(transforms, values)], dtype=float)
    rows = np.ones(len(meas), dtype=bool) if rows is None else np.asarray(rows, dtype=bool)
    return FitProblem(model=model, names=names, transforms=transforms, rows=rows, u=u,
                      basis=ev.basis(model), label=label, max_iter=max_iter,
                      nested=nested_start(model, context, names, transforms, values, start))


def nested_start(model: HarmonicDrive, context: FitContext, names: list, transforms: list, values: list,
                 start: dict) -> NestedStart | None:
    """The start at the fitted model ``start`` holds (its ``stiffness.K0`` and its families'
    values) with every family it lacks at its neutral values; None when ``start`` is no
    fitted model, lacks no family, or a family it lacks declares no neutral values.

    The data's start values of an added family are a guess, and the optimiser may stop
    above the contained model's cost from there (its stopping rule, the iteration limit, a
    local minimum); from this start it cannot.
    """
    if K0_NAME not in start:
        return None
    point = dict(zip(names, values))
    added = []
    for family in SLOTS:
        effect = getattr(model, family)
        own = [f"{family}.{fp.name}" for fp in effect.free_parameters(context)]
        if not own or any(name in start for name in own):
            continue
        neutral = effect.neutral_start(context)
        if neutral is None:
            return None
        point.update({f"{family}.{name}": value for name, value in neutral.items()})
        added.append(family)
    if not added:
        return None
    # exactly the fitted values: a start kept inside the bounds would not be the model's optimum
    u = np.array([tr.to_internal(point[name], exact=True) for name, tr in zip(names, transforms)], dtype=float)
    return NestedStart(u=u, families=tuple(added))
