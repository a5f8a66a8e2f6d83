"""Friction on the wave-generator shaft while the drive runs (driven set-up only).

The friction families of `hdsim.model.effects` act across the elastic path (the
flexspline and its mesh); this module is the *running* friction of the input: WG
bearing, lip seals, churning of the grease and the sliding of the flexspline over the
wave-generator bearing. It acts on the WG shaft, not in the elastic path, so it
changes the motor torque a drive needs and, under speed control, the WG motion; it
does not twist the flexspline.

Law (Armstrong-Hélouvry, 1991; position-periodic term after Ghorbel, Gandhi &
Alpeter, ASME JMD 123, 2001, and Tuttle & Seering, 1996)::

    T_f(ω, θ) = m(θ) [F_c + (F_s − F_c) exp(−(ω/ω_s)²)] tanh(ω/ω_ε) + b ω
    m(θ)      = 1 + Σ_k r_k cos(k θ + φ_k)        (θ the WG angle, k orders of WG rotation)

The periodic part *modulates the magnitude* of the Coulomb/Stribeck level instead of
adding ``Σ a_k sin(kθ + φ_k)`` as Ghorbel et al. write it: an additive term of fixed
sign is a conservative cogging torque (it returns in one half-turn what it takes in
the other) and would make the friction deliver power; the modulated form is
dissipative for ``Σ|r_k| < 1`` (docs/tutorial-kinematic-error.md, section 6).
The law is memoryless (the Stribeck curve is a function of speed), so it adds no ODE
state; ``ω_ε`` is the only regularisation.

**Where the parameters live.** `hdsim.model.drive.HarmonicDrive` has no slot for
input friction, so it is *not* a model parameter: `for_unit` builds an
`InputFriction` from the catalog numbers in ``hdsim/data/input_friction.toml``
(starting torque and no-load running torque at 2000 rpm, from the Schaeffler
RT1-H-CS catalog, i = 100, +20 °C), and a driven scenario may override any field in
its ``[input_friction]`` table (``model = "none"`` switches it off). Efficiency under
load (the mesh losses that grow with torque) is not modelled: the no-load running
torque is the only loss on the input.
"""

from __future__ import annotations

import functools
import tomllib
from dataclasses import dataclass, fields, replace
from importlib import resources

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.physics.friction import stribeck
from hdsim.units import rpm_to_rad_per_s

#: reference speed of the catalog's no-load running torque [rad/s]
CATALOG_SPEED = rpm_to_rad_per_s(2000.0)


@dataclass(frozen=True)
class InputFriction:
    """Friction torque on the WG shaft [N·m] as a function of WG speed and angle."""

    starting_torque: float  # F_s [N·m], breakaway
    coulomb_torque: float   # F_c [N·m], level after the Stribeck dip
    viscous: float          # b [N·m·s/rad]
    stribeck_speed: float   # ω_s [rad/s]
    velocity_scale: float = 0.01  # ω_ε [rad/s]
    ripple_orders: tuple = ()
    ripple_amplitudes: tuple = ()
    ripple_phases: tuple = ()

    def __post_init__(self):
        # NaN fails every comparison, so "not >= 0" refuses it; inf is refused by name
        for name in ("starting_torque", "coulomb_torque", "viscous"):
            value = np.asarray(getattr(self, name), dtype=float)
            if not np.all((value >= 0.0) & (value < np.inf)):
                raise InputError(f"input_friction.{name} must be a finite number >= 0")
        for name in ("stribeck_speed", "velocity_scale"):
            value = np.asarray(getattr(self, name), dtype=float)
            if not np.all((value > 0.0) & (value < np.inf)):
                raise InputError(f"input_friction.{name} must be a finite number > 0")
        if not len(self.ripple_orders) == len(self.ripple_amplitudes) == len(self.ripple_phases):
            raise InputError("input_friction ripple_orders, ripple_amplitudes and ripple_phases "
                             "must have the same length")
        ripple = [*self.ripple_orders, *self.ripple_amplitudes, *self.ripple_phases]
        if not np.all(np.isfinite(np.asarray(ripple, dtype=float))):
            raise InputError("input_friction ripple_orders, ripple_amplitudes and ripple_phases "
                             "must be finite numbers")
        if sum(abs(float(r)) for r in self.ripple_amplitudes) >= 1.0:
            raise InputError("input_friction: the ripple amplitudes must sum to less than 1 "
                             "(the friction level must stay positive)")

    def modulation(self, angle):
        """Position factor ``m(θ) = 1 + Σ r_k cos(kθ + φ_k)`` of the Coulomb/Stribeck level.

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

    def torque(self, speed, angle):
        """Friction torque opposing the WG speed.

        Parameters
        ----------
        speed : float or array
            WG speed ω [rad/s].
        angle : float or array
            WG angle θ [rad].

        Returns
        -------
        float or array
            Friction torque [N·m].
        """
        level = stribeck(speed, self.coulomb_torque, self.starting_torque, self.stribeck_speed, 0.0,
                         self.velocity_scale)
        return self.modulation(angle) * level + self.viscous * speed

    def running_torque(self, speed):
        """Mean friction over a WG revolution at constant speed (the ripple averages out).

        Parameters
        ----------
        speed : float or array
            WG speed [rad/s].

        Returns
        -------
        float or array
            Running torque [N·m].
        """
        return stribeck(speed, self.coulomb_torque, self.starting_torque, self.stribeck_speed,
                        self.viscous, self.velocity_scale)

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
        ``ripple_orders`` [-], ``ripple_amplitudes`` [-], ``ripple_phases`` [rad].

    Returns
    -------
    InputFriction
        The friction law.
    """
    defaults = dict(_data()["shape"])
    defaults.update(shape)
    F_s = float(starting_torque)
    F_c = defaults["coulomb_share"] * F_s
    b = max(float(running_torque) - F_c, 0.0) / running_speed
    return InputFriction(
        starting_torque=F_s, coulomb_torque=F_c, viscous=b, stribeck_speed=defaults["stribeck_speed"],
        velocity_scale=defaults["velocity_scale"], ripple_orders=tuple(defaults["ripple_orders"]),
        ripple_amplitudes=tuple(defaults["ripple_amplitudes"]), ripple_phases=tuple(defaults["ripple_phases"]))


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
        ``ripple_amplitudes`` [-], ``ripple_phases`` [rad].

    Returns
    -------
    InputFriction
        The friction law; `NO_INPUT_FRICTION` for ``model = "none"``.

    Raises
    ------
    InputError
        On an unknown key or model, or a value out of range.
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
    if overrides:
        raise unknown_name("input_friction key", next(iter(overrides)),
                           ["model", "starting_torque_Nm", "running_torque_Nm", "coulomb_share",
                            "stribeck_speed_rpm", "viscous_Nms", "ripple_orders", "ripple_amplitudes",
                            "ripple_phases"])
    return friction
