"""Running torque of the drive: friction on the wave-generator shaft (the one law).

The friction families of `hdsim.model.effects` act across the elastic path (the
flexspline and its mesh); this module is the *running* friction of the drive as the
motor feels it: WG bearing, lip seals, churning of the grease, the sliding of the
flexspline over the wave-generator bearing and the mesh losses that grow with the
transmitted torque. It acts on the WG shaft, not in the elastic path, so it changes
the motor torque a drive needs and, under speed control, the WG motion; it does not
twist the flexspline. The driven bench (`hdsim.simulation.driven`) and the fit of a
running-torque test (`hdsim.identification.running_fit`) both evaluate
`InputFriction.torque`; there is no second copy of the law.

Law (Armstrong-Hélouvry, 1991; position-periodic term after Ghorbel, Gandhi &
Alpeter, ASME JMD 123, 2001, and Tuttle & Seering, 1996)::

    T_f(ω, θ, T_m) = s(ω) [F_c m(θ) + (F_s − F_c) exp(−(ω/ω_s)²) + Δ s(ω) + μ |T_m|] + b ω
    m(θ)           = 1 + Σ_k r_k cos(k θ + φ_k)      (θ the WG angle, k orders of WG rotation)
    s(ω)           = tanh(ω/ω_ε)

- ``F_c`` Coulomb level, ``Δ`` its direction asymmetry (forward ``F_c + Δ``, reverse
  ``F_c − Δ``), ``F_s`` the breakaway level and ``ω_s`` the Stribeck speed;
- ``b`` viscous (churning) loss;
- ``r_k`` the position ripple of the Coulomb level at orders ``k`` of the WG angle (1×
  run-out, 2× the two lobes, 4×; the output's 1× is the order ``1/N``);
- ``μ`` the load-dependent (mesh) friction: ``T_m`` is the torque the mesh transmits,
  referred to the WG shaft, so ``μ`` is the share of the transmitted torque lost to
  friction and sets the efficiency under load, ``η ≈ 1/(1 + μ + T_nl/T_m)``.

The ripple *modulates the Coulomb level* instead of adding ``Σ a_k sin(kθ + φ_k)`` as
Ghorbel et al. write it: an additive term of fixed sign is a conservative cogging torque
(it returns in one half-turn what it takes in the other) and would make the friction
deliver power; the modulated form is dissipative while the level stays positive,
``F_c (1 − Σ|r_k|) ≥ |Δ|`` (`InputFriction.dissipative`; docs/physics.md, running
torque). Every term is linear in its amplitude (``F_c``, ``F_s − F_c``, ``Δ``, ``b``,
``F_c r_k cos φ_k``, ``F_c r_k sin φ_k``, ``μ``), which the fit uses. The law is
memoryless (the Stribeck curve is a function of speed), so it adds no ODE state;
``ω_ε`` is the only regularisation.

**Where the parameters live.** `hdsim.model.drive.HarmonicDrive` has no slot for
input friction, so it is *not* a model parameter: `for_unit` builds an
`InputFriction` from the catalog numbers in ``hdsim/data/input_friction.toml``
(starting torque and no-load running torque at 2000 rpm from the Schaeffler RT1-H-CS
catalog, i = 100, +20 °C, and one mesh-loss coefficient ``μ`` for all sizes, set by the
catalog efficiency at rated torque), and a driven scenario may override any field in its
``[input_friction]`` table (``model = "none"`` switches it off). Temperature is not
modelled: the catalog figures are those at +20 °C.
"""

from __future__ import annotations

import functools
import tomllib
from dataclasses import dataclass, fields, replace
from importlib import resources

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.units import rpm_to_rad_per_s

#: reference speed of the catalog's no-load running torque [rad/s]
CATALOG_SPEED = rpm_to_rad_per_s(2000.0)


@dataclass(frozen=True)
class InputFriction:
    """Friction torque on the WG shaft [N·m] as a function of WG speed, angle and mesh torque."""

    starting_torque: float  # F_s [N·m], breakaway
    coulomb_torque: float   # F_c [N·m], level after the Stribeck dip
    viscous: float          # b [N·m·s/rad]
    stribeck_speed: float   # ω_s [rad/s]
    velocity_scale: float = 0.01  # ω_ε [rad/s]
    ripple_orders: tuple = ()      # k [-], orders of the WG angle
    ripple_amplitudes: tuple = ()  # r_k [-], relative to F_c
    ripple_phases: tuple = ()      # φ_k [rad]
    coulomb_asymmetry: float = 0.0  # Δ [N·m]: forward level F_c + Δ, reverse F_c − Δ
    load_coefficient: float = 0.0   # μ [-]: friction per unit of mesh torque on the WG shaft

    def __post_init__(self):
        # NaN fails every comparison, so "not >= 0" refuses it; inf is refused by name
        for name in ("starting_torque", "coulomb_torque", "viscous", "load_coefficient"):
            value = np.asarray(getattr(self, name), dtype=float)
            if not np.all((value >= 0.0) & (value < np.inf)):
                raise InputError(f"input_friction.{name} must be a finite number >= 0")
        for name in ("stribeck_speed", "velocity_scale"):
            value = np.asarray(getattr(self, name), dtype=float)
            if not np.all((value > 0.0) & (value < np.inf)):
                raise InputError(f"input_friction.{name} must be a finite number > 0")
        if not np.all(np.isfinite(np.asarray(self.coulomb_asymmetry, dtype=float))):
            raise InputError("input_friction.coulomb_asymmetry must be a finite number")
        if not len(self.ripple_orders) == len(self.ripple_amplitudes) == len(self.ripple_phases):
            raise InputError("input_friction ripple_orders, ripple_amplitudes and ripple_phases "
                             "must have the same length")
        ripple = [*self.ripple_orders, *self.ripple_amplitudes, *self.ripple_phases]
        if not np.all(np.isfinite(np.asarray(ripple, dtype=float))):
            raise InputError("input_friction ripple_orders, ripple_amplitudes and ripple_phases "
                             "must be finite numbers")

    @property
    def dissipative(self) -> bool:
        """True when the level stays positive, ``F_c (1 − Σ|r_k|) ≥ |Δ|``, so the friction never
        delivers power (a fitted law may break it; a scenario's may not)."""
        floor = np.asarray(self.coulomb_torque) * (1.0 - sum(abs(float(r)) for r in self.ripple_amplitudes))
        return bool(np.all(floor >= np.abs(np.asarray(self.coulomb_asymmetry)) - 1e-15))

    def modulation(self, angle):
        """Position factor ``m(θ) = 1 + Σ r_k cos(kθ + φ_k)`` of the Coulomb level.

        Parameters
        ----------
        angle : float or array
            WG angle θ [rad].

        Returns
        -------
        float or array
            m(θ) [-].
        """
        m = 1.0
        for k, r, p in zip(self.ripple_orders, self.ripple_amplitudes, self.ripple_phases):
            m = m + r * np.cos(k * angle + p)
        return m

    def torque(self, speed, angle, mesh_torque=0.0):
        """Friction torque opposing the WG speed.

        Parameters
        ----------
        speed : float or array
            WG speed ω [rad/s].
        angle : float or array
            WG angle θ [rad].
        mesh_torque : float or array
            Torque the mesh transmits, referred to the WG shaft [N·m] (0: unloaded).

        Returns
        -------
        float or array
            Friction torque [N·m].
        """
        sign = np.tanh(speed / self.velocity_scale)
        excess = (self.starting_torque - self.coulomb_torque) * np.exp(-(speed / self.stribeck_speed) ** 2)
        level = (self.coulomb_torque * self.modulation(angle) + excess + self.coulomb_asymmetry * sign
                 + self.load_coefficient * abs(mesh_torque))
        return level * sign + self.viscous * speed

    def running_torque(self, speed, mesh_torque=0.0):
        """Mean friction over a WG revolution at constant speed (the ripple averages out).

        Parameters
        ----------
        speed : float or array
            WG speed [rad/s].
        mesh_torque : float or array
            Torque the mesh transmits, referred to the WG shaft [N·m].

        Returns
        -------
        float or array
            Running torque [N·m], signed like the speed.
        """
        return self.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=()).torque(
            speed, 0.0, mesh_torque)

    def with_updates(self, **changes) -> "InputFriction":
        """A copy with fields changed (names checked).

        Parameters
        ----------
        **changes
            Field name -> new value, in the field's unit.

        Returns
        -------
        InputFriction
            The new friction law.

        Raises
        ------
        InputError
            On an unknown field name or a value out of range.
        """
        known = {f.name for f in fields(self)}
        for name in changes:
            if name not in known:
                raise unknown_name("input_friction field", name, known)
        return replace(self, **changes)


NO_INPUT_FRICTION = InputFriction(0.0, 0.0, 0.0, 1.0)


@functools.cache
def _data() -> dict:
    return tomllib.loads(resources.files("hdsim").joinpath("data/input_friction.toml").read_text())


def from_catalog(starting_torque: float, running_torque: float, running_speed: float = CATALOG_SPEED,
                 **shape) -> InputFriction:
    """Input friction that reproduces a catalog starting torque and no-load running torque.

    ``F_s`` = starting torque; ``F_c = coulomb_share·F_s``; the viscous coefficient makes
    ``F_c + b·ω`` equal the running torque at ``running_speed`` (the Stribeck term has
    died out there).

    Parameters
    ----------
    starting_torque : float
        Catalog starting torque on the input [N·m].
    running_torque : float
        Catalog no-load running torque on the input at ``running_speed`` [N·m].
    running_speed : float
        WG speed of the running torque [rad/s]; default 2000 rpm.
    **shape
        Overrides of the assumed shape (``[shape]`` in hdsim/data/input_friction.toml):
        ``coulomb_share`` [-], ``stribeck_speed`` [rad/s], ``velocity_scale`` [rad/s],
        ``ripple_orders`` [-], ``ripple_amplitudes`` [-], ``ripple_phases`` [rad], and of
        the mesh loss ``load_coefficient`` [-] (``[mesh]``).

    Returns
    -------
    InputFriction
        The friction law.
    """
    defaults = {**_data()["shape"], **_data()["mesh"]}
    defaults.update(shape)
    F_s = float(starting_torque)
    F_c = defaults["coulomb_share"] * F_s
    b = max(float(running_torque) - F_c, 0.0) / running_speed
    return InputFriction(
        starting_torque=F_s, coulomb_torque=F_c, viscous=b, stribeck_speed=defaults["stribeck_speed"],
        velocity_scale=defaults["velocity_scale"], ripple_orders=tuple(defaults["ripple_orders"]),
        ripple_amplitudes=tuple(defaults["ripple_amplitudes"]), ripple_phases=tuple(defaults["ripple_phases"]),
        load_coefficient=defaults["load_coefficient"])


def catalog_values(model) -> dict:
    """Starting and running torque for a model's unit.

    Built-in units use their table; any other model (a fitted or renamed unit) takes
    the size-25 values scaled by its rated torque relative to 87 N·m (the catalog values
    grow roughly in proportion with T_N), and is marked so.

    Parameters
    ----------
    model : HarmonicDrive
        The model; its ``name`` selects the table row.

    Returns
    -------
    dict
        ``starting_torque`` and ``running_torque_2000rpm`` [N·m], ``source`` and, for a
        derived entry, ``status``.
    """
    units = _data()["units"]
    if model.name in units:
        entry = dict(units[model.name])
        entry["source"] = f"hdsim/data/input_friction.toml [{model.name}]"
        return entry
    base = units["CSG-25-100"]
    scale = float(np.max(np.asarray(model.drive.rated_torque))) / 87.0
    return {"starting_torque": base["starting_torque"] * scale,
            "running_torque_2000rpm": base["running_torque_2000rpm"] * scale,
            "source": "CSG-25-100 values scaled by rated torque", "status": "derived"}


def for_unit(model, overrides: dict | None = None) -> InputFriction:
    """The input friction of a model's unit, with a scenario's ``[input_friction]`` overrides.

    Parameters
    ----------
    model : HarmonicDrive
        The model whose catalog values are used (`catalog_values`).
    overrides : dict, optional
        ``model`` (``"catalog"`` or ``"none"``), ``starting_torque_Nm`` [N·m],
        ``running_torque_Nm`` [N·m] (at 2000 rpm), ``coulomb_share`` [-],
        ``stribeck_speed_rpm`` [rpm], ``viscous_Nms`` [N·m·s/rad], ``ripple_orders`` [-],
        ``ripple_amplitudes`` [-], ``ripple_phases`` [rad], ``coulomb_asymmetry_Nm`` [N·m],
        ``load_coefficient`` [-].

    Returns
    -------
    InputFriction
        The friction law; `NO_INPUT_FRICTION` for ``model = "none"``.

    Raises
    ------
    InputError
        On an unknown key or model, a value out of range, or a law that would deliver
        power (ripple and asymmetry larger than the Coulomb level).
    """
    overrides = dict(overrides or {})
    kind = overrides.pop("model", "catalog")
    if kind == "none":
        return NO_INPUT_FRICTION
    if kind != "catalog":
        raise InputError(f"input_friction.model must be 'catalog' or 'none', got {kind!r}")
    values = catalog_values(model)
    shape = {}
    if "coulomb_share" in overrides:
        share = overrides.pop("coulomb_share")
        if not 0.0 <= share <= 1.0:
            raise InputError("input_friction.coulomb_share must be in [0, 1]")
        shape["coulomb_share"] = share
    if "stribeck_speed_rpm" in overrides:
        shape["stribeck_speed"] = rpm_to_rad_per_s(overrides.pop("stribeck_speed_rpm"))
    if "load_coefficient" in overrides:
        shape["load_coefficient"] = float(overrides.pop("load_coefficient"))
    for key in ("ripple_orders", "ripple_amplitudes", "ripple_phases"):
        if key in overrides:
            value = overrides.pop(key)
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
                raise InputError(f"input_friction.{key} must be a list of numbers")
            shape[key] = [float(v) for v in value]
    friction = from_catalog(overrides.pop("starting_torque_Nm", values["starting_torque"]),
                            overrides.pop("running_torque_Nm", values["running_torque_2000rpm"]), **shape)
    if "viscous_Nms" in overrides:
        friction = friction.with_updates(viscous=float(overrides.pop("viscous_Nms")))
    if "coulomb_asymmetry_Nm" in overrides:
        friction = friction.with_updates(coulomb_asymmetry=float(overrides.pop("coulomb_asymmetry_Nm")))
    if overrides:
        raise unknown_name("input_friction key", next(iter(overrides)),
                           ["model", "starting_torque_Nm", "running_torque_Nm", "coulomb_share",
                            "stribeck_speed_rpm", "viscous_Nms", "ripple_orders", "ripple_amplitudes",
                            "ripple_phases", "coulomb_asymmetry_Nm", "load_coefficient"])
    if not friction.dissipative:
        raise InputError("input_friction: the ripple amplitudes and the asymmetry must leave the Coulomb "
                         "level positive, F_c (1 - sum |r_k|) >= |asymmetry| (else the friction delivers power)")
    return friction
