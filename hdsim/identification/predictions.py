"""What a fitted drive predicts for the catalog tests, with a 95 % band from the fit.

A fit on a bench record gives a drive (`hdsim.identification.fit.FitResult.model`) and the
covariance of its own coordinates ``u`` (``coordinates``: the fitted parameters through
log and logistic transforms, where the fit's Gaussian approximation is made and every
value stays in its bounds). Here that drive is put through the maker's tests: the
±4 % T_N lost-motion test and the ±T_N stiffness test (K1, K2, K3, torsion at T_N,
hysteresis loss). Each prediction carries a 95 % band propagated from the covariance Σ:

*linearised* (the default)
    Each coordinate is moved by ±1 standard deviation, the metrics are read by central
    differences ``g``, and the band is ``±1.96 √(g Σ gᵀ)``.
*sampled*
    Where the linearisation does not hold (a metric's second difference is more than a
    fifth of its first for some coordinate), 200 draws of ``u`` from ``N(u, Σ)``: the band
    is the 2.5–97.5 % quantiles of the metric.

A friction sweep's fit is a law on the wave-generator shaft, linear in its amplitudes:
`sweep_predictions` gives its no-load running torque at the catalog's 2000 rpm (each
direction, averaged over a turn) and its starting torque, each with the band
``±1.96 √(g Σ gᵀ)``, exact for a law linear in the amplitudes. The starting torque is
given each way when the law has a direction asymmetry, and without a band when the record
holds no plateaus slow enough to determine it (`hdsim.identification.sweep_start`): the
covariance takes the assumed shape of the Stribeck rise as known below the slowest plateau.

A coordinate the record does not determine (an infinite variance,
`hdsim.identification.optimizer.inverse_gram`, or, for a twist test's drive, a standard
uncertainty larger than the value it stands for: the parameters the plausibility checks
name) is outside the Gaussian approximation: draws of it would run drives the record never saw (a negative K1, a loss
band that excludes the fitted value). A figure that moves with such a coordinate has no
band (``"not determined by the record"``); one that does not is propagated from the others.
A sweep's figures are linear in the amplitudes, so there only an infinite variance
withholds a band: an amplitude zero within its uncertainty (a direction asymmetry of
2·10⁻⁵ ± 2·10⁻⁵ N·m) widens the band by exactly what it may be.

The covariance is the fit's own (`hdsim.identification.optimizer.covariance`): ``s² (JᵀJ)⁻¹``
with ``s²`` the residual's variance, not the noise floor's, widened by ``n/n_eff`` for a
correlated residual, so a band already grows with whatever the model leaves unexplained.
What no band holds is the error of a wrong form: where the model leaves structure above the
noise floor (the verdict's judgement, `hdsim.identification.residuals.whiteness`), a page
says so beside the bands (`misfit_caveat`).

Every set of parameters of one test runs as one batch (`hdsim.scenarios.run.run_scenario`
on a batch model) through the quasi-static evaluator: the drive was identified by
quasi-static fits (`hdsim.simulation.quasistatic`), so its parameters mean what that
model says, and the dynamic model would add the bench's output inertia, which no fit
determined (it moves K1 and the hysteresis loss by 1–2 %, docs/sensitivity.md §11). A
report pays milliseconds for it. docs/tutorial-find-missing-effect.md, "What the
fitted drive predicts", shows the table.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hdsim.errors import InputError, SolverError

#: the catalog tests and the metrics read from each: (scenario, metric, label, unit)
CATALOG_TESTS = (
    ("lost_motion", "lost_motion_arcmin", "lost motion, ±4 % T_N", "arcmin"),
    ("stiffness", "K1_Nm_per_rad", "K1", "N·m/rad"),
    ("stiffness", "K2_Nm_per_rad", "K2", "N·m/rad"),
    ("stiffness", "K3_Nm_per_rad", "K3", "N·m/rad"),
    ("stiffness", "torsion_at_rated_arcmin", "torsion at T_N", "arcmin"),
    ("stiffness", "hysteresis_loss_arcmin", "hysteresis loss", "arcmin"),
)
#: datasheet figures a built-in unit's catalog entry gives, by metric
DATASHEET_KEYS = {"K1_Nm_per_rad": "K1", "K2_Nm_per_rad": "K2", "K3_Nm_per_rad": "K3"}
#: z of a two-sided 95 % band
Z95 = 1.959964
#: draws of the sampled band
SAMPLES = 200
#: the linearisation is trusted while |second difference| <= this × |first difference|
NONLINEARITY = 0.2
#: the method of a band that rests on a coordinate the record does not determine
UNDETERMINED = "not determined by the record"


def _steps(covariance, undetermined, undetermined_step) -> tuple[np.ndarray, np.ndarray]:
    """(the step of each coordinate, the covariance of the determined ones): an ``undetermined``
    coordinate steps by ``undetermined_step`` (enough to see whether a figure moves with it),
    a determined one by its standard deviation."""
    variance = np.where(undetermined, 0.0, np.diag(covariance))
    steps = np.where(undetermined, undetermined_step, np.sqrt(np.maximum(variance, 0.0)))
    return steps, np.where(undetermined[:, None] | undetermined[None, :], 0.0, covariance)


def _band(value: float, g: np.ndarray, undetermined: np.ndarray, covariance: np.ndarray) -> tuple[float, float]:
    """``value ± 1.96 √(g Σ gᵀ)`` for the gradient ``g``, taken as zero along the undetermined
    coordinates (``covariance``: of the determined ones)."""
    g = np.where(undetermined, 0.0, g)
    half = Z95 * float(np.sqrt(max(g @ covariance @ g, 0.0)))
    return value - half, value + half


def _moves(first: np.ndarray, undetermined: np.ndarray, value: float) -> bool:
    """Whether a figure with central differences ``first`` moves with an undetermined coordinate."""
    return bool(np.any(np.abs(first[undetermined]) > 1e-9 * abs(value) + 1e-300))


@dataclass(frozen=True)
class Prediction:
    """One catalog metric of the fitted drive.

    Attributes
    ----------
    label, unit : str
        What it is, and its unit.
    value : float
        The fitted drive's value.
    low, high : float
        The 95 % band (NaN when the fit gives no covariance).
    datasheet : float or None
        The catalog's figure for the unit, where it gives one.
    method : str
        ``"linearised"``, ``"sampled (N of 200 draws)"`` or ``"no covariance"``.
    """

    label: str
    unit: str
    value: float
    low: float
    high: float
    datasheet: float | None
    method: str


def catalog_predictions(result, *, samples: int = SAMPLES, seed: int = 0) -> list[Prediction]:
    """The catalog tests of ``result``'s fitted drive, each with its 95 % band.

    Parameters
    ----------
    result : hdsim.identification.fit.FitResult
        A fit of a twist test (stiffness or kinematic error).
    samples : int
        Draws of the sampled band, where the linearisation does not hold.
    seed : int
        Seed of the draws.

    Returns
    -------
    list of Prediction
        In the order of `CATALOG_TESTS`; a test the drive cannot run is left out.
    """
    model, coordinates = result.model, result.coordinates
    catalog = model.provenance.get("catalog") or {}
    if coordinates is None:
        rows, sd = None, np.zeros(0)
    else:  # a standard deviation above one unit of u (the size of a log coordinate's relative change,
        # NaN and infinity included) is undetermined, and steps by that unit
        undetermined = ~(np.diag(coordinates.covariance) <= 1.0)
        sd, covariance = _steps(coordinates.covariance, undetermined, 1.0)
        rows = np.vstack([coordinates.u, coordinates.u + np.diag(sd), coordinates.u - np.diag(sd)])
    k = sd.size
    out = []
    for scenario in dict.fromkeys(test[0] for test in CATALOG_TESTS):
        wanted = [t for t in CATALOG_TESTS if t[0] == scenario]
        values = _metrics(model, coordinates, rows, scenario, [t[1] for t in wanted])
        if values is None:
            continue
        bands, nonlinear = {}, []
        for (_, metric, *_), v in zip(wanted, values):
            if not k or not np.all(np.isfinite(v)):
                bands[metric] = (np.nan, np.nan, "no covariance")
                continue
            first = (v[1:k + 1] - v[k + 1:]) / 2.0
            if _moves(first, undetermined, v[0]):
                bands[metric] = (np.nan, np.nan, UNDETERMINED)
                continue
            second = np.where(undetermined, 0.0, v[1:k + 1] + v[k + 1:] - 2.0 * v[0])
            if np.all(np.abs(second) <= NONLINEARITY * np.abs(first) + 1e-12 * abs(v[0])):
                low, high = _band(v[0], first / np.where(sd > 0, sd, 1.0), undetermined, covariance)
                bands[metric] = (low, high, "linearised")
            else:
                nonlinear.append(metric)
        if nonlinear:  # one batch of draws for every metric of the test that needs them
            bands.update(_sampled_bands(model, coordinates, covariance, scenario, nonlinear, samples, seed))
        for (_, metric, label, unit), v in zip(wanted, values):
            low, high, method = bands[metric]
            out.append(Prediction(label, unit, float(v[0]), low, high, catalog.get(DATASHEET_KEYS.get(metric, "")),
                                  method))
    return out


def _sampled_bands(model, coordinates, covariance, scenario, metrics, samples, seed) -> dict:
    """``{metric: (low, high, method)}`` from the 2.5-97.5 % quantiles of ``samples`` draws of
    the coordinates (``covariance``: of the determined ones), run as one batch."""
    draws = np.random.default_rng(seed).multivariate_normal(coordinates.u, covariance,
                                                           size=samples, method="eigh")
    sampled = _metrics(model, coordinates, draws, scenario, metrics)
    out = {}
    for i, metric in enumerate(metrics):
        kept = sampled[i][np.isfinite(sampled[i])] if sampled is not None else np.zeros(0)
        if kept.size < samples // 2:
            out[metric] = (np.nan, np.nan, f"sampled ({kept.size} of {samples} draws ran: no band)")
        else:
            low, high = np.quantile(kept, [0.025, 0.975])
            out[metric] = (float(low), float(high), f"sampled ({kept.size} of {samples} draws)")
    return out


def _metrics(model, coordinates, rows, scenario, metrics):
    """The metrics of ``scenario`` for each row of coordinates (one batched run; the fitted
    drive alone without rows): arrays in the order of ``metrics``; None when the drive
    cannot run the scenario."""
    from hdsim.scenarios.run import run_scenario

    size = 1 if rows is None else len(rows)
    batch = model if rows is None else model.with_updates(coordinates.updates(rows))
    if rows is not None and not _consistent(batch):
        # a draw whose values contradict each other (a hardening's T1 drawn above its T2) is no
        # drive: run_scenario refuses the whole batch for it, so it is left out (NaN) instead;
        # the draws are judged one by one only when the batch holds such a draw
        kept = np.array([_consistent(model.with_updates(coordinates.updates(rows[i:i + 1]))) for i in range(size)])
        values = _metrics(model, coordinates, rows[kept], scenario, metrics) if 0 < kept.sum() < size else None
        if values is None:
            return None
        out = [np.full(size, np.nan) for _ in metrics]
        for full, part in zip(out, values):
            full[kept] = part
        return out
    try:
        run = run_scenario(batch, scenario, evaluator="quasistatic")
    except (InputError, SolverError):
        return None
    # a figure the test's cycle does not reach is absent from its metrics (`locked_metrics`)
    return [np.broadcast_to(np.asarray(run.metrics.get(m, np.nan), dtype=float).reshape(-1), (size,))
            for m in metrics]


def _consistent(drive) -> bool:
    """Whether ``drive``'s values agree with each other (`HarmonicDrive.require_consistent`)."""
    try:
        drive.require_consistent()
    except InputError:
        return False
    return True


def misfit_caveat(whiteness: dict) -> str:
    """The sentence a page shows beside the bands of a model whose residual the verdict does
    not call explained (``whiteness``: the dict the verdict reads,
    `hdsim.identification.residuals.whiteness`: neither white nor within
    `hdsim.identification.residuals.EXPLAINED_RATIO` of the noise floor); "" for one it does."""
    if whiteness.get("explained", True):
        return ""
    ratio = whiteness.get("rms_over_noise")
    told = f"rms {ratio:.1f}× the noise floor" if ratio is not None and np.isfinite(ratio) else "above the noise floor"
    # not "too narrow by that much": s² is the residual's variance (structure included), so the
    # band is already that much wider than the noise alone would make it; what it lacks is the
    # error of the missing effect, which the fit gives no size for
    return (f"The model leaves structure in the residual ({told}): these bands assume its form is right, "
            "and the effect it misses can put the drive's true figures outside them.")


#: the catalog's no-load running-torque speed of the input [rad/s] (2000 rpm)
CATALOG_SPEED = 2000.0 * np.pi / 30.0


def sweep_predictions(fit, scale) -> list[Prediction]:
    """The catalog figures of a friction sweep's fitted law, with 95 % bands.

    Parameters
    ----------
    fit : hdsim.identification.running_fit.RunningFit
        The fit of a running-torque record.
    scale : hdsim.io.data_checks.DriveScale or None
        The drive's datasheet numbers (running torque at 2000 rpm and starting torque on
        the input shaft).

    Returns
    -------
    list of Prediction
        Running torque forward and reverse at 2000 rpm and the starting torque (each way
        for a law with a direction asymmetry or a record that runs one way, else one), on
        the input (wave-generator) shaft [N·m]; a starting torque the record does not
        determine has no band (`hdsim.identification.sweep_start`), nor has a figure of a
        direction the record never runs.
    """
    from hdsim.identification.sweep_start import BREAKAWAY_TEST, starting_level, starting_levels, \
        starting_torque_undetermined

    running, starting = getattr(scale, "running_torque", 0.0), getattr(scale, "starting_torque", 0.0)
    figures = [("running torque at 2000 rpm, forward", lambda law: float(law.running_torque(CATALOG_SPEED)), running),
               ("running torque at 2000 rpm, reverse", lambda law: float(-law.running_torque(-CATALOG_SPEED)), running)]
    # the level at rest each way where the law is asymmetric, one figure where it has one level
    # (`hdsim.identification.sweep_start`); below the slowest plateau the record may not determine it
    figures += [(f"starting torque, {'both directions (one level)' if way == 'both' else way}",
                 lambda law, way=way: starting_level(law, way), starting) for way in starting_levels(fit)]
    extrapolated = starting_torque_undetermined(fit) is not None
    # a direction without a plateau: the law's value there is its assumption (no asymmetry)
    never = fit.record.never_run
    coordinates = fit.coordinates
    if coordinates is not None:  # the figures are linear in the amplitudes: one step of each
        # and only an infinite (or NaN) variance is undetermined (the module text); it steps by the
        # amplitude's own size (a micro-unit at 0)
        undetermined = ~np.isfinite(np.diag(coordinates.covariance))
        sd, covariance = _steps(coordinates.covariance, undetermined, np.maximum(np.abs(coordinates.x), 1e-6))
        moved = {j: coordinates.law(coordinates.x + sd[j] * np.eye(sd.size)[j]) for j in np.flatnonzero(sd > 0)}
    out = []
    for label, figure, datasheet in figures:
        value = figure(fit.law)
        low, high, method = np.nan, np.nan, "no covariance"
        if any(label.endswith(way) for way in never):
            method = f"{UNDETERMINED}: it never runs {never[0]} (the law has no direction asymmetry)"
        elif extrapolated and label.startswith("starting torque"):
            method = f"{UNDETERMINED}: the law below the slowest plateau; {BREAKAWAY_TEST}"
        elif coordinates is not None:
            g = np.zeros(sd.size)
            for j, law in moved.items():
                g[j] = np.nan if law is None else (figure(law) - value) / sd[j]
            if np.all(np.isfinite(g)) and _moves(g * sd, undetermined, value):
                method = UNDETERMINED
            elif np.all(np.isfinite(g)):
                (low, high), method = _band(value, g, undetermined, covariance), "linear in the amplitudes"
        out.append(Prediction(label, "N·m", value, low, high, datasheet or None, method))
    return out
