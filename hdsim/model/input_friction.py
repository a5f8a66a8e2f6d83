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

**Where the parameters live.** `hdsim.model.drive.HarmonicDrive` carries its law as
``drive.input_friction``; its scalar fields are model parameters named
``input_friction.<field>`` (``input_friction.coulomb_torque`` …), so ``with_updates``,
``--set`` and Sobol studies address them like any other, and the drive of a
running-torque fit carries the fitted law. A drive built without one gets the catalog law
of its unit (`catalog_friction`: the catalog numbers in
``hdsim/data/input_friction.toml``, starting torque and no-load running torque at 2000 rpm
from the Schaeffler RT1-H-CS catalog, i = 100, +20 °C, and one mesh-loss coefficient ``μ``
for all sizes, set by the catalog efficiency at rated torque). A driven scenario runs the
drive's law with its ``[input_friction]`` table applied on top (`for_unit`; ``model =
"none"`` switches it off, ``model = "catalog"`` starts from the unit's catalog law
instead). Temperature is not modelled: the catalog figures are those at +20 °C.
"""

from __future__ import annotations

import functools
import math
import tomllib
from dataclasses import dataclass, fields, replace
from importlib import resources
from typing import ClassVar

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.model.parameters import Parameters, _as_float_array, checked_fields, param
from hdsim.physics.elementary import cos, exp, tanh
from hdsim.units import rpm_to_rad_per_s

#: reference speed of the catalog's no-load running torque [rad/s]
CATALOG_SPEED = rpm_to_rad_per_s(2000.0)


@dataclass(frozen=True)
class InputFriction(Parameters):
    """Friction torque on the WG shaft [N·m] as a function of WG speed, angle and mesh torque.

    The scalar fields are parameters (`hdsim.model.parameters.param`: unit, bounds, meaning)
    and may hold 1-D arrays, a batch of laws evaluated at once; the ripple tuples are
    not parameters (their length is the number of orders).
    """

    starting_torque: float = param("breakaway level F_s", "N·m")
    coulomb_torque: float = param("Coulomb level F_c after the Stribeck dip", "N·m")
    viscous: float = param("viscous (churning) coefficient b", "N·m·s/rad")
    stribeck_speed: float = param("Stribeck speed ω_s", "rad/s", positive=True)
    velocity_scale: float = param("speed ω_ε of the smooth direction switch tanh(ω/ω_ε)", "rad/s",
                                  positive=True, default=0.01)
    ripple_orders: tuple = ()      # k [-], orders of the WG angle
    ripple_amplitudes: tuple = ()  # r_k [-], relative to F_c
    ripple_phases: tuple = ()      # φ_k [rad]
    position_orders: tuple = ()      # k [-], orders of the WG angle of the position torque
    position_amplitudes: tuple = ()  # g_k [N·m]: a torque that does not reverse with the motion
    position_phases: tuple = ()      # ψ_k [rad]
    coulomb_asymmetry: float = param("direction asymmetry Δ: forward level F_c + Δ, reverse F_c − Δ", "N·m",
                                     -np.inf, default=0.0)
    #: at most 0.9: at μ → 1 the drive would lock itself (the back-driving torque N F_s / (1 − μ)
    #: grows without bound, and turns negative beyond), which a harmonic drive does not; 0.9
    #: is already an efficiency under 53 % at rated torque (the catalog's is 67-77 %)
    load_coefficient: float = param("mesh friction μ per unit of mesh torque on the WG shaft", "-", 0.0, 0.9,
                                    default=0.0)

    prefix: ClassVar[str] = "input_friction"

    def __post_init__(self):
        # NaN fails every comparison and inf is refused by name: "finite" says which was wrong
        for name, lower, upper, positive, _ in checked_fields(type(self)):
            raw = getattr(self, name)
            if (type(raw) is float and math.isfinite(raw) and (raw > lower if positive else raw >= lower)
                    and raw <= upper):
                continue  # one law's float (the common case, without numpy)
            value = _as_float_array(self.prefix, name, raw)
            ok = np.isfinite(value) & ((value > lower) if positive else (value >= lower)) & (value <= upper)
            if not np.all(ok):
                limit = "" if lower == -np.inf else f" {'>' if positive else '>='} {lower:g}"
                limit += "" if upper == np.inf else f"{' and' if limit else ''} <= {upper:g}"
                first = np.atleast_1d(value)[np.argmin(np.atleast_1d(ok))]
                raise InputError(f"input_friction.{name} must be a finite number{limit}, got {first:g}")
        if not len(self.ripple_orders) == len(self.ripple_amplitudes) == len(self.ripple_phases):
            raise InputError("input_friction ripple_orders, ripple_amplitudes and ripple_phases "
                             "must have the same length")
        if not len(self.position_orders) == len(self.position_amplitudes) == len(self.position_phases):
            raise InputError("input_friction position_orders, position_amplitudes and position_phases "
                             "must have the same length")
        ripple = [*self.ripple_orders, *self.ripple_amplitudes, *self.ripple_phases, *self.position_orders,
                  *self.position_amplitudes, *self.position_phases]
        try:
            finite = np.all(np.isfinite(np.asarray(ripple, dtype=float)))
        except (TypeError, ValueError):
            finite = False
        if not finite:
            raise InputError("input_friction ripple and position-torque orders, amplitudes and phases "
                             "must be finite numbers")

    @property
    def batch_size(self) -> int:
        """1 for one law, else the common length of its array parameters."""
        sizes = {np.size(v) for v in self.params().values()} - {1}
        return max(sizes, default=1)

    def sample(self, m: int) -> "InputFriction":
        """Law ``m`` of a batch (the law itself when it is a single one)."""
        return replace(self, **{k: np.atleast_1d(v)[m] for k, v in self.params().items() if np.size(v) > 1})

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
            m = m + r * cos(k * angle + p)
        return m

    def position_torque(self, angle):
        """The additive position torque ``Σ g_k cos(kθ + ψ_k)`` [N·m]: periodic in the WG angle
        and the same in both directions (a motor's cogging, an unbalance), so conservative: it
        takes over a turn what it gives back, and a running torque averages it out.

        Parameters
        ----------
        angle : float or array
            WG angle θ [rad].
        """
        g = 0.0 * (angle if isinstance(angle, float) else np.asarray(angle, dtype=float))
        for k, a, p in zip(self.position_orders, self.position_amplitudes, self.position_phases):
            g = g + a * cos(k * angle + p)
        return g

    def ripple_torques(self) -> tuple:
        """The ripple amplitudes as torques on the WG shaft [N·m]: ``F_c r_k`` (the law keeps
        them as fractions ``r_k`` of the Coulomb level; this is the one conversion)."""
        return tuple(float(np.max(np.asarray(self.coulomb_torque))) * float(r) for r in self.ripple_amplitudes)

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
        sign = tanh(speed / self.velocity_scale)
        excess = (self.starting_torque - self.coulomb_torque) * exp(-(speed / self.stribeck_speed) ** 2)
        level = (self.coulomb_torque * self.modulation(angle) + excess + self.coulomb_asymmetry * sign
                 + self.load_coefficient * abs(mesh_torque))
        return level * sign + self.viscous * speed + self.position_torque(angle)

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
        return self.with_updates(ripple_orders=(), ripple_amplitudes=(), ripple_phases=(), position_orders=(),
                                 position_amplitudes=(), position_phases=()).torque(speed, 0.0, mesh_torque)

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


def assumed_stribeck_speed() -> float:
    """The Stribeck speed ω_s [rad/s] the catalog laws assume (``[shape]`` of
    hdsim/data/input_friction.toml; no catalog gives it)."""
    return float(_data()["shape"]["stribeck_speed"])


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


def catalog_friction(model) -> InputFriction:
    """The catalog law of a model's unit: what a drive carries unless it is given another.

    Parameters
    ----------
    model : HarmonicDrive
        The model; its name and rated torque select the catalog values (`catalog_values`).

    Returns
    -------
    InputFriction
        `from_catalog` of the unit's starting torque and running torque at 2000 rpm.
    """
    values = catalog_values(model)
    return from_catalog(values["starting_torque"], values["running_torque_2000rpm"])


#: keys of a scenario's [input_friction] table that re-derive F_s, F_c and b as `from_catalog` does
_CATALOG_KEYS = ("starting_torque_Nm", "running_torque_Nm", "coulomb_share")
#: keys that replace one field each: key -> (field, conversion to SI)
_FIELD_KEYS = {"stribeck_speed_rpm": ("stribeck_speed", rpm_to_rad_per_s), "viscous_Nms": ("viscous", float),
               "coulomb_asymmetry_Nm": ("coulomb_asymmetry", float), "load_coefficient": ("load_coefficient", float)}
#: the ripple lists by table key -> law field: the amplitudes are fractions of the Coulomb level,
#: and the key says so (``ripple_amplitudes``, the field's own name, is still read)
_RIPPLE_KEYS = {"ripple_orders": "ripple_orders", "ripple_amplitudes_of_level": "ripple_amplitudes",
                "ripple_amplitudes": "ripple_amplitudes", "ripple_phases": "ripple_phases",
                "position_torque_orders": "position_orders", "position_torque_amplitudes_Nm": "position_amplitudes",
                "position_torque_phases": "position_phases"}
TABLE_KEYS = ("model", *_CATALOG_KEYS, *_FIELD_KEYS, *_RIPPLE_KEYS)


def _number_or_array(value):
    """A float for a single value, the array for a batch (laws of a batch drive)."""
    return float(value) if np.ndim(value) == 0 else np.asarray(value, dtype=float)


def _catalog_changes(law: InputFriction, table: dict) -> dict:
    """F_s, F_c and b from the table's catalog keys, each key left out taken from ``law``.

    The law's Coulomb share is ``F_c/F_s`` (1 without breakaway excess) and its running
    torque at 2000 rpm ``F_c + b·ω``; with none of the keys in the table nothing changes.
    """
    if not any(key in table for key in _CATALOG_KEYS):
        return {}
    F_s = np.asarray(table.get("starting_torque_Nm", law.starting_torque), dtype=float)
    own = np.asarray(law.starting_torque, dtype=float)
    share = table.get("coulomb_share",
                      np.where(own > 0, np.asarray(law.coulomb_torque) / np.where(own > 0, own, 1.0), 1.0))
    if not np.all((np.asarray(share) >= 0.0) & (np.asarray(share) <= 1.0)):
        raise InputError("input_friction.coulomb_share must be in [0, 1]")
    running = table.get("running_torque_Nm", np.asarray(law.coulomb_torque) + np.asarray(law.viscous) * CATALOG_SPEED)
    F_c = share * F_s
    # the running torque at 2000 rpm cannot be below the Coulomb level: no negative viscous loss
    b = np.maximum(np.asarray(running, dtype=float) - F_c, 0.0) / CATALOG_SPEED
    return {"starting_torque": _number_or_array(F_s), "coulomb_torque": _number_or_array(F_c),
            "viscous": _number_or_array(b)}


def apply_table(law: InputFriction, table: dict) -> InputFriction:
    """A scenario's ``[input_friction]`` table (without its ``model`` key) applied on top of ``law``.

    The catalog keys ``starting_torque_Nm`` [N·m], ``running_torque_Nm`` [N·m] (at 2000 rpm)
    and ``coulomb_share`` [-] re-derive ``F_s``, ``F_c`` and ``b`` as `from_catalog` does,
    a key left out keeping the law's own value; then ``stribeck_speed_rpm`` [rpm],
    ``viscous_Nms`` [N·m·s/rad], ``coulomb_asymmetry_Nm`` [N·m], ``load_coefficient`` [-] and
    the ripple lists ``ripple_orders`` [-], ``ripple_amplitudes_of_level`` [-, fractions of
    the Coulomb level; ``ripple_amplitudes`` is read too], ``ripple_phases`` [rad], and the
    position torque's ``position_torque_orders`` [-], ``position_torque_amplitudes_Nm`` [N·m],
    ``position_torque_phases`` [rad] replace one field each. An empty table returns ``law`` itself.

    Raises
    ------
    InputError
        On an unknown key or a value out of range.
    """
    for key in table:
        if key not in TABLE_KEYS[1:]:
            raise unknown_name("input_friction key", key, TABLE_KEYS[1:])
    changes = _catalog_changes(law, table)
    for key, (name, convert) in _FIELD_KEYS.items():
        if key in table:
            changes[name] = convert(table[key])
    for key, name in _RIPPLE_KEYS.items():
        if key in table:
            value = table[key]
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
                raise InputError(f"input_friction.{key} must be a list of numbers")
            changes[name] = tuple(float(v) for v in value)
    return law.with_updates(**changes) if changes else law


def for_unit(model, overrides: dict | None = None) -> InputFriction:
    """The input friction a driven scenario runs: the drive's law with the scenario's table on top.

    Parameters
    ----------
    model : HarmonicDrive
        The model; its ``input_friction`` is the law the table changes.
    overrides : dict, optional
        The scenario's ``[input_friction]`` table: ``model`` (``"drive"``, the default: the
        drive's law; ``"catalog"``: the unit's catalog law, `catalog_friction`; ``"none"``:
        no friction) and the keys of `apply_table`.

    Returns
    -------
    InputFriction
        The friction law; `NO_INPUT_FRICTION` for ``model = "none"``.

    Raises
    ------
    InputError
        On an unknown key or model, a value out of range, or a table that makes a
        dissipative law deliver power (ripple and asymmetry larger than the Coulomb level;
        a drive's own law, a fitted one, may do so and runs as it is).
    """
    overrides = dict(overrides or {})
    for key in overrides:
        if key not in TABLE_KEYS:
            raise unknown_name("input_friction key", key, TABLE_KEYS)
    kind = overrides.pop("model", "drive")
    if kind == "none":
        return NO_INPUT_FRICTION
    if kind not in ("drive", "catalog"):
        raise InputError(f"input_friction.model must be 'drive', 'catalog' or 'none', got {kind!r}")
    base = catalog_friction(model) if kind == "catalog" else model.input_friction
    friction = apply_table(base, overrides)
    if base.dissipative and not friction.dissipative:
        raise InputError("input_friction: the ripple amplitudes and the asymmetry must leave the Coulomb "
                         "level positive, F_c (1 - sum |r_k|) >= |asymmetry| (else the friction delivers power)")
    return friction
