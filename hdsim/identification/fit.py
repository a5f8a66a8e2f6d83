"""Fit the model to a bench measurement: least squares with bounds, uncertainties, write-back.

The measured torque drives the model and the measured angle is what it must predict
(``contracts.md`` §1). The model is a :class:`~hdsim.model.drive.HarmonicDrive` whose slots hold
the chosen effects; it is evaluated by the quasi-static bench evaluator
(:mod:`hdsim.simulation.quasistatic`: inertia dropped, the library's effect laws), so the fitted
model is an ordinary model that :mod:`hdsim.simulation.path` can simulate again.

Free parameters
---------------
``calibration.kappa_mesh`` (the base linear compliance) plus, per effect, the parameters
in :data:`FREE`. Bounds come from :meth:`HarmonicDrive.param_info`; inside the optimiser
each parameter is mapped to an unbounded coordinate (``p = lo + e^u`` for a one-sided
bound, ``p = lo + (hi − lo)·sigmoid(u)`` for two), so every trial model is valid.

The angle offset (and, for a kinematic-error test, the sine/cosine coefficients of the
kinematic-error harmonics) enter linearly: they are solved exactly for every trial by
linear least squares (variable projection), so the offset is always fitted and never
counted as error.

Optimiser
---------
Levenberg–Marquardt with forward-difference Jacobians. Many fits run *in lockstep*: at
every tick each active fit asks for its Jacobian columns and a few trial steps (three
damping values, using the Jacobian of the previous tick updated by Broyden's rule), and
all of them are evaluated in one batched pass of the quasi-static evaluator. A diagnosis
round (every candidate, every hold-out fold) therefore costs about as many passes as one
fit.

Uncertainty
-----------
The covariance ``s² (JᵀJ)⁻¹`` at the optimum (offset included), with ``s²`` the residual
variance, mapped to the physical parameters by the derivative of the transform; it is
widened by ``√(n/n_eff)``, ``n_eff = n (1 − ρ₁)/(1 + ρ₁)`` with ``ρ₁`` the lag-one
autocorrelation of the residual, because a correlated residual carries less information
than ``n`` independent samples.

Write-back
----------
:meth:`FitResult.save` writes a TOML file: the unit, the effect id of every slot, the
fitted values as dotted ``name = value`` overrides, the angle offset, uncertainties and
fit statistics. :func:`load_fitted` turns it back into a :class:`HarmonicDrive`; the
``[parameters]`` table is exactly what ``hdsim simulate --set name=value`` takes once the
same effects are switched on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hdsim.model import effects as fx
from hdsim.errors import InputError, unknown_name
from hdsim.io.measurement import Measurement
from hdsim.model.drive import SLOTS, HarmonicDrive
from hdsim.simulation.quasistatic import SUPPORTED, locked_twist, supports
from hdsim.identification.residuals import _direction

__all__ = ["FREE", "DEFAULT_EFFECT", "FitResult", "fit", "fit_many", "parse_effects",
           "build_model", "load_fitted", "Evaluator", "FitProblem", "bic"]

#: the effect each family gets when only the family is named
DEFAULT_EFFECT = {"hardening": "tanh", "backlash": "dead_zone", "friction": "dahl",
                  "damping": "viscous", "kinematic_error": "fourier"}

#: parameters fitted per effect (others keep their values). ``K_ratio`` is internal: the
#: tanh law's K∞/K0, mapped with K0 to ``calibration.kappa_mesh``, ``hardening.e_inf`` and,
#: when the nominal structure is too compliant for it, ``flexspline.E`` (see :func:`split_stiffness`).
FREE = {
    ("hardening", "tanh"): ("curvature", "K_ratio"),
    ("hardening", "three_segment"): ("T1", "T2", "e2", "e3"),
    ("backlash", "dead_zone"): ("gap",),
    ("friction", "dahl"): ("torque_max", "sigma"),
    # the stiffness share only shows with hardening (free_parameters drops it without)
    ("damping", "viscous"): ("coefficient", "stiffness_share"),
    # amplitudes and phases are solved linearly (sine/cosine pairs); load_gain stays 0
    ("kinematic_error", "fourier"): (),
}
#: the base model's free parameter: the low-load stiffness K0 [N·m/rad] (internal)
K0_NAME = "stiffness.K0"
#: tanh hardening, internal: K∞/K0 and the curvature (K∞/K0 − 1)/T_s² [1/(N·m)²], which
#: sets the tangent stiffness K0 (1 + curvature·T²) at small load; T_s follows
RATIO_NAME = "hardening.K_ratio"
CURVATURE_NAME = "hardening.curvature"
RATIO_BOUNDS = (1.0, 40.0)
#: engagement ratio used when the structure must be stiffened to reach K∞
E_INF_CAP = 100.0
KE_WG_ORDERS = (1, 2, 4)
KE_OUT_ORDERS = (1,)


# --------------------------------------------------------------------------- effects


def parse_effects(text) -> dict[str, str]:
    """``'friction,hardening'``, ``'dahl,tanh'`` or ``'friction=dahl'`` -> {family: effect id}.

    Family names take :data:`DEFAULT_EFFECT`; an effect id names its family; ``none`` and
    empty entries are ignored. Unknown names raise :class:`InputError` with close matches.
    """
    if text is None:
        return {}
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
            effect_id = DEFAULT_EFFECT[family]
        elif family in by_id:
            family, effect_id = by_id[family], family
        else:
            raise unknown_name("effect family or effect id", family,
                               list(fx.FAMILIES) + list(by_id))
        if family in chosen and chosen[family] != effect_id:
            raise InputError(f"--effects names two {family} effects: {chosen[family]} and {effect_id}")
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


def build_model(unit, effects: dict[str, str], meas: Measurement | None = None) -> HarmonicDrive:
    """The unit with exactly ``effects`` switched on (placeholder parameters), others none."""
    base = _unit_model(unit, meas)
    T_N = float(base.drive.rated_torque)
    K = float(base.base_stiffness)
    placeholders = {
        ("hardening", "tanh"): {"e_inf": 2.0, "T_s": 0.3 * T_N},
        ("hardening", "three_segment"): {"T1": 0.15 * T_N, "T2": 0.5 * T_N, "e2": 2.0, "e3": 3.0},
        ("backlash", "dead_zone"): {"gap": 1e-4},
        ("friction", "dahl"): {"torque_max": 0.03 * T_N, "sigma": 2.0 * K},
        ("damping", "viscous"): {"coefficient": 0.005 * K, "stiffness_share": 0.0},
        ("kinematic_error", "fourier"): {"a1": 0.0, "a2": 0.0, "a4": 0.0, "p1": 0.0, "p2": 0.0,
                                         "p4": 0.0, "a_out": 0.0, "p_out": 0.0, "load_gain": 0.0},
    }
    slots = {}
    for family in SLOTS:
        effect_id = effects.get(family, "none")
        if effect_id == "none":
            slots[family] = fx.NO_EFFECT[family]
            continue
        current = getattr(base, family)
        if current.id == effect_id:
            slots[family] = current
        elif (family, effect_id) in placeholders:
            slots[family] = fx.make_effect(family, effect_id, **placeholders[(family, effect_id)])
        else:
            raise InputError(f"the fit has no starting values for {family} effect '{effect_id}'; "
                             f"fit one of {', '.join(i for f, i in FREE if f == family)}")
    model = base.with_effects(**slots)
    if not supports(model):
        bad = [f"{f}={getattr(model, f).id}" for f in SLOTS
               if getattr(model, f).id not in SUPPORTED[f]]
        raise InputError(f"fit/diagnose cannot evaluate {', '.join(bad)} yet; "
                         f"use one of the effects in hdsim.identification.fit.FREE")
    return model


def free_parameters(model: HarmonicDrive) -> list[str]:
    """Internal names of the fitted parameters of ``model`` (K0 first)."""
    names = [K0_NAME]
    linear = model.hardening.id == "none"
    for family in SLOTS:
        effect = getattr(model, family)
        names += [f"{family}.{p}" for p in FREE.get((family, effect.id), ())
                  if not (linear and p == "stiffness_share")]  # no effect on a linear spring
    return names


def split_stiffness(model: HarmonicDrive, K0, ratio=1.0, e_cap: float = E_INF_CAP) -> dict:
    """Model parameters that give low-load stiffness ``K0`` and tanh-law ``K∞ = ratio·K0``.

    The unit's closed forms split the compliance into a structural part ``C_s`` and a
    mesh-zone part ``κ C_m``; hardening can only remove mesh-zone compliance
    (``K∞ = 1/(C_s + κ C_m/e_inf)``). With the nominal geometry ``κ`` sets K0 and
    ``e_inf`` sets K∞. When K∞ (or K0) is beyond what the nominal structure allows, the
    flexspline modulus ``E`` is raised (``C_s ∝ 1/E``) so that ``e_inf = e_cap``. The
    bench response depends on K0, K∞ (and T_s) only, so this choice is a convention of
    the write-back, not a fit assumption. Returns dotted updates (arrays).
    """
    from hdsim.model.drive import compliance_chain

    K0 = np.asarray(K0, dtype=float)
    ratio = np.broadcast_to(np.asarray(ratio, dtype=float), K0.shape)
    g, wg = model.geometry, model.wave_generator
    chain = compliance_chain(g, wg, 1.0)
    cs0, cm0 = float(np.asarray(chain.structure)), float(np.asarray(chain.mesh_zone))
    E0 = float(np.asarray(g.E))
    C0 = 1.0 / K0
    Cinf = 1.0 / (ratio * K0)
    hard = ratio > 1.0 + 1e-12
    kappa_a = (C0 - cs0) / cm0
    with np.errstate(divide="ignore", invalid="ignore"):
        e_a = np.where(hard, kappa_a * cm0 / (Cinf - cs0), 1.0)
    ok = (kappa_a > 1e-3) & (~hard | ((Cinf > cs0) & (e_a >= 1.0) & (e_a <= e_cap)))
    # stiffen the structure: e_inf = e_cap (or the structure takes half of C0 without hardening)
    share = np.where(hard, (1.0 - 1.0 / ratio) / (1.0 - 1.0 / e_cap), 0.5)
    cs_target = C0 * (1.0 - share)
    E_b = E0 * cs0 / cs_target
    from dataclasses import replace as _replace
    chain_b = compliance_chain(_replace(g, E=np.where(ok, E0, E_b)), wg, 1.0)
    cm_b = np.asarray(chain_b.mesh_zone, dtype=float)
    kappa_b = share * C0 / cm_b
    out = {"calibration.kappa_mesh": np.where(ok, kappa_a, kappa_b)}
    if not np.all(ok):
        out["flexspline.E"] = np.where(ok, E0, E_b)
    e = np.where(ok, e_a, np.where(hard, e_cap, 1.0))
    return out, np.clip(e, 1.0, 100.0)


# --------------------------------------------------------------------------- transforms


@dataclass(frozen=True)
class _Transform:
    lo: float
    hi: float

    def to_phys(self, u):
        u = np.asarray(u, dtype=float)
        if math.isfinite(self.hi):
            return self.lo + (self.hi - self.lo) / (1.0 + np.exp(-np.clip(u, -700, 700)))
        return self.lo + np.exp(np.clip(u, -700, 700))

    def to_internal(self, p):
        p = float(p)
        span = self.hi - self.lo
        if math.isfinite(self.hi):
            f = min(max((p - self.lo) / span, 1e-12), 1.0 - 1e-9)
            return math.log(f / (1.0 - f))
        return math.log(max(p - self.lo, 1e-300))

    def dphys_du(self, u):
        u = np.asarray(u, dtype=float)
        if math.isfinite(self.hi):
            s = 1.0 / (1.0 + np.exp(-np.clip(u, -700, 700)))
            return (self.hi - self.lo) * s * (1.0 - s)
        return np.exp(np.clip(u, -700, 700))


#: bounds of parameters whose metadata has none, as factors of the unit's value
GEOMETRY_RANGE = (0.2, 5.0)


def _transform(model: HarmonicDrive, name: str) -> _Transform:
    if name == K0_NAME:
        from hdsim.model.drive import compliance_chain

        chain = compliance_chain(model.geometry, model.wave_generator, 1.0)
        cs0, cm0 = float(np.asarray(chain.structure)), float(np.asarray(chain.mesh_zone))
        return _Transform(1.0 / (cs0 + 900.0 * cm0), math.inf)
    if name == RATIO_NAME:
        return _Transform(*RATIO_BOUNDS)
    if name == CURVATURE_NAME:
        return _Transform(0.0, math.inf)
    info = model.param_info(name)
    if "bounds" not in info:
        nominal = float(np.asarray(model.params()[name]).reshape(-1)[0])
        return _Transform(GEOMETRY_RANGE[0] * nominal, GEOMETRY_RANGE[1] * nominal)
    lo, hi = info["bounds"]
    lo = float(lo)
    if info.get("positive") and lo <= 0.0:
        lo = 0.0
    return _Transform(lo, float(hi))


# --------------------------------------------------------------------------- evaluator


class Evaluator:
    """Model predictions and the linear (projected) part for one measurement.

    Stiffness test: predicted angle = offset + quasi-static twist under the measured
    torque. Kinematic-error test: predicted output angle = offset + wg/ratio + twist under
    the measured load torque + kinematic error (sine/cosine of the wave-generator angle at
    orders 1, 2, 4 and of the output angle at order 1, linear in their coefficients).
    """

    def __init__(self, meas: Measurement, max_steps: int = 4000):
        self.meas = meas
        self.test = meas.test
        self.t = np.asarray(meas.time, dtype=float)
        self.T = np.asarray(meas.torque, dtype=float)
        self.y = np.asarray(meas.angle, dtype=float)
        self.n = self.t.size
        # all samples up to max_steps, else a step budget (the grid adapts to each batch)
        self.grid = None if self.n <= max_steps else int(max_steps)
        if self.test == "kinematic_error":
            wg = np.asarray(meas.wg_angle, dtype=float)
            self.ideal = wg / float(meas.ratio)
            out = self.ideal
            cols = []
            for k in KE_WG_ORDERS:
                cols += [np.sin(k * wg), np.cos(k * wg)]
            for k in KE_OUT_ORDERS:
                cols += [np.sin(k * out), np.cos(k * out)]
            self.ke_basis = np.column_stack(cols)
        else:
            self.ideal = np.zeros(self.n)
            self.ke_basis = np.zeros((self.n, 0))
        self.y_rel = self.y - self.ideal

    def basis(self, with_ke: bool) -> np.ndarray:
        ones = np.ones((self.n, 1))
        return np.hstack([ones, self.ke_basis]) if with_ke and self.ke_basis.size else ones

    def twist(self, models) -> np.ndarray:
        """(M, n) quasi-static twist of the stacked models."""
        return locked_twist(models, self.t, self.T, grid=self.grid)


def _project(target: np.ndarray, basis: np.ndarray, rows: np.ndarray):
    """Least-squares coefficients of ``basis[rows]`` for every row of ``target[:, rows]``."""
    B = basis[rows]
    pinv = np.linalg.pinv(B)
    coef = target[:, rows] @ pinv.T
    return coef


# --------------------------------------------------------------------------- problems


@dataclass
class FitProblem:
    """One least-squares fit: a model structure, its free parameters and the rows it fits."""

    model: HarmonicDrive
    names: list[str]
    rows: np.ndarray  # bool (n,): the rows whose residual is minimised
    u: np.ndarray  # internal coordinates, current
    with_ke: bool
    label: str = ""
    max_iter: int = 25
    # optimiser state
    transforms: list = field(default_factory=list)
    cost: float = np.inf
    lam: float = 1e-2
    J: np.ndarray | None = None
    r: np.ndarray | None = None
    done: bool = False
    iterations: int = 0
    stalls: int = 0

    def __post_init__(self):
        self.transforms = [_transform(self.model, name) for name in self.names]

    def phys(self, U: np.ndarray) -> dict[str, np.ndarray]:
        """Internal parameter values (K0, K_ratio, dotted effect parameters) for rows of U."""
        U = np.atleast_2d(U)
        return {name: tr.to_phys(U[:, j]) for j, (name, tr) in enumerate(zip(self.names, self.transforms))}

    def updates(self, U: np.ndarray) -> dict[str, np.ndarray]:
        """Dotted model updates for rows of U (K0 and K_ratio mapped by split_stiffness)."""
        values = self.phys(U)
        K0 = values.pop(K0_NAME)
        ratio = values.pop(RATIO_NAME, 1.0)
        base, e_inf = split_stiffness(self.model, K0, ratio)
        if self.model.hardening.id == "tanh":
            base["hardening.e_inf"] = e_inf
            curvature = values.pop(CURVATURE_NAME)
            base["hardening.T_s"] = np.sqrt((ratio - 1.0) / curvature)
        base.update(values)
        return base

    def batch_model(self, U: np.ndarray) -> HarmonicDrive:
        if not self.names:
            return self.model
        return self.model.with_updates(self.updates(U))

    def fd_steps(self) -> np.ndarray:
        return 1e-5 * np.maximum(1.0, np.abs(self.u)) if self.u.size else self.u


def _residuals(ev: Evaluator, prob: FitProblem, twist: np.ndarray):
    """(residual on the problem's rows (M, n_rows), full residual (M, n), linear coefficients)."""
    basis = ev.basis(prob.with_ke)
    target = ev.y_rel[None, :] - twist
    coef = _project(target, basis, prob.rows)
    full = target - coef @ basis.T
    return full[:, prob.rows], full, coef


def fit_many(ev: Evaluator, problems: list[FitProblem], *, tol: float = 1e-3, log=None) -> int:
    """Run the Levenberg–Marquardt fits of ``problems`` in lockstep (in place).

    A fit stops after two iterations in a row that lower its cost by less than ``tol``
    (relative; 1e-3 of the RSS is a BIC change of n·1e-3, below any decision threshold),
    after ``max_iter`` iterations, or when no damping value gives a lower cost.
    Returns the number of batched passes (ticks) it took.
    """
    pending = [p for p in problems if not p.done]
    ticks = 0
    while pending:
        requests = []
        for p in pending:
            k = p.u.size
            steps = p.fd_steps()
            trials = np.zeros((0, k))
            if p.J is None:  # first tick: the start and its Jacobian
                U = np.vstack([p.u[None, :], p.u[None, :] + np.diag(steps)]) if k else p.u[None, :]
                kind = "start"
            else:  # Jacobian at the current point and trial steps from the previous one
                trials = _trial_points(p)
                U = np.vstack([p.u[None, :] + np.diag(steps), trials])
                kind = "iterate"
            requests.append((p, kind, steps, U, trials))
        models = [p.batch_model(U) for p, _, _, U, _ in requests]
        twist = ev.twist(models)
        ticks += 1
        row = 0
        for p, kind, steps, U, trials in requests:
            size = U.shape[0] if p.names else 1
            block = twist[row:row + size]
            row += size
            r_rows, _, _ = _residuals(ev, p, block)
            _update(p, r_rows, kind == "start", steps, trials, tol)
        pending = [p for p in pending if not p.done]
        if log:
            log(f"pass {ticks}: {len(pending)} fits still running")
    return ticks


def _trial_points(p: FitProblem) -> np.ndarray:
    """Trial steps from the current Jacobian for three damping values."""
    J, r = p.J, p.r
    A = J.T @ J
    g = J.T @ r
    D = np.maximum(np.diag(A), 1e-12 * max(np.max(np.diag(A)), 1e-300))
    out = []
    for factor in (0.1, 1.0, 10.0):
        lam = p.lam * factor
        try:
            step = -np.linalg.solve(A + lam * np.diag(D), g)
        except np.linalg.LinAlgError:
            step = -g / (D * (1 + lam))
        step = np.clip(step, -5.0, 5.0)
        out.append(p.u + step)
    return np.array(out)


def _update(p: FitProblem, r_rows: np.ndarray, has_base: int, steps, trials, tol) -> None:
    k = p.u.size
    if has_base:  # first tick: base point and Jacobian
        r0 = r_rows[0]
        p.r = r0
        p.cost = float(r0 @ r0)
        p.J = ((r_rows[1:1 + k] - r0) / steps[:, None]).T if k else np.zeros((r0.size, 0))
        if k == 0:
            p.done = True
        return
    Jcols = r_rows[:k]
    trial_r = r_rows[k:]
    # the Jacobian at the current point (evaluated around p.u); base residual is p.r
    J_new = ((Jcols - p.r) / steps[:, None]).T
    costs = np.einsum("ij,ij->i", trial_r, trial_r)
    best = int(np.argmin(costs))
    p.iterations += 1
    if costs[best] < p.cost:
        du = trials[best] - p.u
        r_best = trial_r[best]
        # Broyden update of the fresh Jacobian to the accepted point
        pred = p.r + J_new @ du
        denom = float(du @ du)
        if denom > 0:
            J_new = J_new + np.outer(r_best - pred, du) / denom
        rel = (p.cost - costs[best]) / max(p.cost, 1e-300)
        p.u = trials[best]
        p.r = r_best
        p.cost = float(costs[best])
        p.lam = max(p.lam * (0.1, 1.0, 10.0)[best] * 0.5, 1e-9)
        p.stalls = p.stalls + 1 if rel < tol else 0
    else:
        p.lam = min(p.lam * 100.0, 1e10)
        p.stalls += 1
    p.J = J_new
    if p.stalls >= 2 or p.iterations >= p.max_iter or p.lam >= 1e10:
        p.done = True


# --------------------------------------------------------------------------- results


def bic(rss: float, n: float, k: int) -> float:
    """Bayesian information criterion ``n ln(RSS/n) + k ln n`` (Gaussian errors)."""
    return n * math.log(max(rss, 1e-300) / n) + k * math.log(n)


def lag1(r: np.ndarray) -> float:
    r = np.asarray(r, dtype=float) - np.mean(r)
    den = float(r @ r)
    return float(r[1:] @ r[:-1]) / den if den > 0 else 0.0


def effective_n(r: np.ndarray) -> float:
    """``n (1 − ρ₁)/(1 + ρ₁)``: samples worth of independent information in a residual."""
    rho = min(max(lag1(r), 0.0), 0.999)
    return max(r.size * (1.0 - rho) / (1.0 + rho), 2.0)


@dataclass
class FitResult:
    """A fitted model and what the fit says about it (``params``: dotted model overrides;
    ``internal``: the fitted coordinates K0, K_ratio, …; ``uncertainty`` keyed like
    ``internal``, plus ``offset_rad``).

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
    iterations: int = 0
    unit: str = ""
    internal: dict = field(default_factory=dict)
    derived: dict = field(default_factory=dict)

    @property
    def families(self) -> list[str]:
        return [f for f in SLOTS if f in self.effects]

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
    def rss(self) -> float:
        r = self.residual[self.rows]
        return float(r @ r)

    @property
    def n(self) -> int:
        return int(np.count_nonzero(self.rows))

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
            "uncertainty": {k: float(v) for k, v in self.uncertainty.items()},
            "derived": {k: float(v) for k, v in self.derived.items()},
            "iterations": self.iterations,
        }

    def to_toml(self) -> str:
        """The fitted parameter set as TOML (see the module doc and :func:`load_fitted`)."""
        import tomli_w

        doc = {
            "format": "hdsim-fit-1",
            "unit": self.unit,
            "test": self.measurement.test,
            "source": str(self.measurement.source),
            "effects": {f: getattr(self.model, f).id for f in SLOTS},
            "parameters": {k: float(v) for k, v in self.params.items()},
            "offset": {"angle_offset_rad": float(self.offset)},
            "uncertainty": {k: float(v) for k, v in self.uncertainty.items()},
            "fit": {"rows": self.n, "rmse_rad": self.rmse_rad, "max_abs_error_rad": self.max_abs_rad,
                    "bic": self.bic, "n_params": self.n_params},
        }
        head = ("# hdsim fitted parameter set. Load with hdsim.identification.fit.load_fitted(path); the\n"
                "# [parameters] table holds dotted overrides of the unit, in SI units.\n")
        return head + tomli_w.dumps(doc)

    def save(self, path) -> Path:
        from hdsim.io.atomic import write_text_atomic

        path = Path(path)
        write_text_atomic(path, self.to_toml())
        return path


def load_fitted(path) -> HarmonicDrive:
    """A :class:`HarmonicDrive` from a file written by :meth:`FitResult.save`."""
    from hdsim.model.catalog import load_unit
    from hdsim.scenarios.scenario import read_toml

    path = Path(path)
    doc = read_toml(path, "fit")
    if doc.get("format") != "hdsim-fit-1":
        raise InputError(f"{path}: not an hdsim fit file (format = 'hdsim-fit-1' expected)")
    model = load_unit(doc.get("unit") or None)
    params = dict(doc.get("parameters", {}))
    slots = {}
    for family, effect_id in doc.get("effects", {}).items():
        if effect_id == "none":
            slots[family] = fx.NO_EFFECT[family]
            continue
        cls = fx.effect_class(family, effect_id)
        current = getattr(model, family)
        values = {}
        for f in cls.param_meta():
            key = f"{family}.{f}"
            if key in params:
                values[f] = params.pop(key)
            elif current.id == effect_id:
                values[f] = getattr(current, f)
        slots[family] = fx.make_effect(family, effect_id, **values)
    model = model.with_effects(**slots)
    return model.with_updates({k: v for k, v in params.items()}) if params else model


# --------------------------------------------------------------------------- start values


def _relative_angle(meas: Measurement) -> np.ndarray:
    """Angle relative to the kinematic ideal [rad] (stiffness test: the angle itself)."""
    if meas.test == "kinematic_error":
        return meas.kinematic_error
    return np.asarray(meas.angle, dtype=float)


def loading_slope(meas: Measurement, lo: float = 0.1, hi: float = 0.5) -> float:
    """Secant stiffness [N·m/rad] from angle vs torque for lo < |T|/max|T| < hi."""
    T = np.asarray(meas.torque, dtype=float)
    y = _relative_angle(meas)
    a = np.abs(T) / max(np.max(np.abs(T)), 1e-12)
    m = (a > lo) & (a < hi)
    if np.count_nonzero(m) < 5 or np.ptp(T[m]) <= 0:
        m = np.ones_like(T, dtype=bool)
    if np.ptp(T[m]) <= 0:
        return float("nan")
    slope = np.polyfit(T[m], y[m], 1)[0]
    return 1.0 / slope if slope > 0 else float("nan")


def zero_torque_signatures(meas: Measurement) -> dict:
    """Loop width and step at zero torque [rad], median |dT/dt| [N·m/s]."""
    T = np.asarray(meas.torque, dtype=float)
    y = _relative_angle(meas)
    Tmax = max(np.max(np.abs(T)), 1e-12)
    sign, speed = _direction(meas.time, T)
    out = {"loop_width": 0.0, "step": 0.0, "rate": float(np.median(speed))}
    near = (np.abs(T) < 0.15 * Tmax) & (np.abs(T) > 0.02 * Tmax)
    values = {}
    for direction in (+1, -1):
        on = near & (sign == direction)
        pos, neg = on & (T > 0), on & (T < 0)
        if np.count_nonzero(pos) >= 3 and np.count_nonzero(neg) >= 3:
            cp = np.polyfit(T[pos], y[pos], 1)
            cn = np.polyfit(T[neg], y[neg], 1)
            values[direction] = (cp[1], cn[1])
    if len(values) == 2:
        up_mid = 0.5 * sum(values[+1])
        down_mid = 0.5 * sum(values[-1])
        out["loop_width"] = float(max(down_mid - up_mid, 0.0))
        out["step"] = float(max(0.5 * ((values[+1][0] - values[+1][1]) + (values[-1][0] - values[-1][1])), 0.0))
    return out


def start_values(meas: Measurement, model: HarmonicDrive, names, given: dict | None = None) -> dict:
    """Starting values from the data: loading-branch slope, loop width, step at zero."""
    given = given or {}
    start = {}
    has_h = model.hardening.id != "none"
    K = loading_slope(meas, 0.05, 0.3) if has_h else loading_slope(meas, 0.1, 0.6)
    T_max = float(np.max(np.abs(meas.torque)))
    sig = zero_torque_signatures(meas)
    if not np.isfinite(K):
        K = float(model.base_stiffness)
    for name in names:
        if name in given:
            start[name] = given[name]
        elif name == K0_NAME:
            start[name] = K
        elif name == RATIO_NAME:
            start[name] = 4.0
        elif name == CURVATURE_NAME:
            start[name] = 3.0 / (0.6 * T_max) ** 2
        elif name == "hardening.T1":
            start[name] = 0.15 * T_max
        elif name == "hardening.T2":
            start[name] = 0.5 * T_max
        elif name in ("hardening.e2", "hardening.e3"):
            start[name] = 1.5 if name.endswith("e2") else 2.5
        elif name == "backlash.gap":
            start[name] = float(np.clip(sig["step"], 2e-5, 1e-2))
        elif name == "friction.torque_max":
            start[name] = float(np.clip(0.5 * K * max(sig["loop_width"], 1e-5), 1e-3 * T_max, 0.5 * T_max))
        elif name == "friction.sigma":
            start[name] = 2.0 * K
        elif name == "damping.stiffness_share":
            start[name] = 0.5
        elif name == "damping.coefficient":
            width = max(sig["loop_width"], 2e-5)
            start[name] = float(np.clip(0.5 * width * K * K / (2.0 * max(sig["rate"], 1e-9)), 1e-3, 5e5))
        else:
            start[name] = float(np.asarray(model.params()[name]).reshape(-1)[0])
    return start


def make_problem(model: HarmonicDrive, meas: Measurement, rows=None, start: dict | None = None,
                 label: str = "") -> FitProblem:
    names = free_parameters(model)
    values = start_values(meas, model, names, given=start)
    u = np.array([_transform(model, n).to_internal(values[n]) for n in names], dtype=float)
    rows = np.ones(len(meas), dtype=bool) if rows is None else np.asarray(rows, dtype=bool)
    with_ke = model.kinematic_error.id != "none" and meas.test == "kinematic_error"
    return FitProblem(model=model, names=names, rows=rows, u=u, with_ke=with_ke, label=label)


def result_of(ev: Evaluator, prob: FitProblem, unit: str = "") -> FitResult:
    """Evaluate a finished problem once more and package it as a :class:`FitResult`."""
    internal = {k: float(np.asarray(v).reshape(-1)[0]) for k, v in prob.phys(prob.u[None, :]).items()}
    updates = {k: float(np.asarray(v).reshape(-1)[0]) for k, v in prob.updates(prob.u[None, :]).items()} \
        if prob.names else {}
    model = prob.model.with_updates(updates) if updates else prob.model
    twist = ev.twist(model)
    r_rows, full, coef = _residuals(ev, prob, twist)
    coef = coef[0]
    offset = float(coef[0])
    ke = {}
    if prob.with_ke:
        ke, model = _ke_effect(model, coef[1:])
        updates.update({f"kinematic_error.{k}": v for k, v in ke.items()})
    n_lin = 1 + (len(coef) - 1 if prob.with_ke else 0)
    unc = _uncertainty(ev, prob, r_rows[0])
    prediction = ev.y - full[0]
    effects = {f: getattr(model, f).id for f in SLOTS if getattr(model, f).id != "none"}
    derived = {"K0_Nm_per_rad": float(model.base_stiffness)}
    if model.hardening.id == "tanh":
        derived["K_inf_Nm_per_rad"] = internal.get(RATIO_NAME, 1.0) * internal[K0_NAME]
    return FitResult(measurement=ev.meas, model=model, effects=effects, params=updates,
                     uncertainty=unc, offset=offset, prediction=prediction, residual=full[0],
                     rows=prob.rows.copy(), n_params=len(prob.names) + n_lin,
                     ke_coefficients=ke, iterations=prob.iterations, unit=unit or prob.model.name,
                     internal=internal, derived=derived)


def _ke_effect(model: HarmonicDrive, coef: np.ndarray):
    """Linear sine/cosine coefficients -> FourierKinematicError amplitudes and phases."""
    pairs = coef.reshape(-1, 2)
    amps, phases = np.hypot(pairs[:, 0], pairs[:, 1]), np.arctan2(pairs[:, 1], pairs[:, 0])
    names = [f"a{k}" for k in KE_WG_ORDERS] + ["a_out"]
    pnames = [f"p{k}" for k in KE_WG_ORDERS] + ["p_out"]
    values = {"load_gain": 0.0}
    for a, p, an, pn in zip(amps, phases, names, pnames):
        values[an] = float(min(a, 0.01))
        values[pn] = float(p)
    effect = fx.make_effect("kinematic_error", "fourier", **values)
    return values, model.with_effects(kinematic_error=effect)


def _uncertainty(ev: Evaluator, prob: FitProblem, r: np.ndarray) -> dict:
    """1-sigma uncertainties from the Jacobian (offset column included), n_eff-widened."""
    out = {}
    if prob.J is None:
        return out
    n = r.size
    k = prob.u.size
    ones = np.ones((n, 1))
    J = np.hstack([prob.J, ones]) if k else ones
    dof = max(n - J.shape[1], 1)
    s2 = float(r @ r) / dof
    try:
        cov = np.linalg.pinv(J.T @ J) * s2
    except np.linalg.LinAlgError:
        return out
    widen = math.sqrt(n / effective_n(r))
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0)) * widen
    for j, (name, tr) in enumerate(zip(prob.names, prob.transforms)):
        out[name] = float(abs(tr.dphys_du(prob.u[j])) * sd[j])
    out["offset_rad"] = float(sd[-1])
    return out


# --------------------------------------------------------------------------- API


def fit(meas: Measurement, effects=None, *, unit=None, rows=None, start: dict | None = None,
        max_steps: int = 4000) -> FitResult:
    """Fit the base model plus ``effects`` to a measurement.

    Parameters
    ----------
    meas : Measurement
        From :func:`hdsim.io.measurement.load_measurement`.
    effects : str, list or dict, optional
        Families or effect ids (see :func:`parse_effects`); none means the base model
        (linear compliance and the angle offset).
    unit : str or HarmonicDrive, optional
        Built-in unit name (default: the catalog default) or a model to start from.
    rows : array_like of bool, optional
        Fit only these rows (hold-out fits); the residual is reported everywhere.
    start : dict, optional
        Starting values by dotted name (others from the data).
    max_steps : int
        Quasi-static steps at most (longer records are stepped on a sub-grid).

    Returns
    -------
    FitResult
    """
    chosen = effects if isinstance(effects, dict) else parse_effects(effects)
    model = build_model(unit, chosen, meas)
    ev = Evaluator(meas, max_steps=max_steps)
    prob = make_problem(model, meas, rows=rows, start=start)
    fit_many(ev, [prob])
    return result_of(ev, prob, unit=model.name)
