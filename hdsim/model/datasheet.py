"""Datasheet figures to a calibrated drive: the catalog table and the one recipe.

The catalog table of the built-in units (hdsim/data/units.toml: `unit_names`,
`catalog_entry`, `default_unit`, the assumed proportions and defaults), and the recipe
that turns a datasheet into a model, `assemble_unit`. Both kinds of unit go through it:
the built-in units (`hdsim.model.catalog`) and the drive files that describe any other
drive by its datasheet (`hdsim.model.drive_file`), so this module sits below both and
imports neither.

Calibration (documented in docs/physics.md): at the nominal geometry the closed
forms give a structural compliance ``C_s`` and a mesh-zone compliance ``C_m``.
``kappa_mesh`` scales ``C_m`` so that ``1/(C_s + κ C_m) = K1``; the engagement ratios
``e_i = κ C_m / (1/K_i − C_s)`` make the three-segment law hit K2 and K3. These
numbers are then frozen into the unit: changing a dimension later changes ``C_s``
and ``C_m`` through the closed forms while κ and e_i stay put.
"""

from __future__ import annotations

import functools
import tomllib
from importlib import resources

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.model import effects as fx
from hdsim.model.drive import Calibration, DriveData, HarmonicDrive, WaveGenerator, compliance_chain
from hdsim.model.geometry import DEDENDUM_MODULES, FlexsplineGeometry
from hdsim.units import arcmin_to_rad

__all__ = ["unit_names", "default_unit", "catalog_entry", "nominal_geometry", "nominal_wave_generator",
           "calibrate", "assemble_unit"]


@functools.cache
def _data() -> dict:
    return tomllib.loads(resources.files("hdsim").joinpath("data/units.toml").read_text())


def unit_names() -> list[str]:
    """Names of the built-in units, as the catalog names them.

    Returns
    -------
    list of str
        E.g. ``['CSG-14-100', ..., 'CSG-32-100']``.
    """
    return list(_data()["units"])


def default_unit() -> str:
    """The unit used when none is named.

    Returns
    -------
    str
        ``'CSG-25-100'``.
    """
    return _data()["default"]


def catalog_entry(name: str) -> dict:
    """Catalog data of a built-in unit.

    Parameters
    ----------
    name : str
        Unit name, e.g. ``'CSG-25-100'``.

    Returns
    -------
    dict
        ``size`` [-], ``ratio`` [-], ``rated_torque``, ``T1``, ``T2`` [N·m],
        ``K1``, ``K2``, ``K3`` [N·m/rad] and the ``status`` of the numbers.

    Raises
    ------
    InputError
        On an unknown name, with the closest known ones.
    """
    units = _data()["units"]
    if name not in units:
        raise unknown_name("unit", name, units)
    return dict(units[name])


def nominal_geometry(size: float, ratio: float) -> FlexsplineGeometry:
    """Nominal flexspline of a catalog size from the assumed proportions.

    The pitch diameter is the size in tenths of an inch; every dimension is a fixed
    fraction of it (``[proportions]`` in hdsim/data/units.toml).

    Parameters
    ----------
    size : float
        Catalog size, e.g. 25 [-].
    ratio : float
        Transmission ratio [-]; the flexspline has ``2 |ratio|`` teeth.

    Returns
    -------
    FlexsplineGeometry
        The geometry [m, Pa].
    """
    data = _data()
    d = size * 2.54e-3  # pitch diameter [m]: size = tenths of an inch
    p = data["proportions"]
    teeth = 2.0 * abs(ratio)  # two-lobe WG: N = z_fs / (z_cs − z_fs) with z_cs − z_fs = 2
    module = d / teeth
    h_pz = p["h_pz"] * d
    return FlexsplineGeometry(
        h_pz=h_pz, h_c=p["h_c"] * d, R_v=p["R_v"] * d, R_k=p["R_k"] * d, h_p=p["h_p"] * d,
        R_i=0.5 * d - DEDENDUM_MODULES * module - h_pz, face_width=p["face_width"] * d,
        cup_length=p["cup_length"] * d, undercut_width=p["undercut_width"] * d, t_d=p["t_d"] * d,
        r_hub=p["r_hub"] * d, module=module, teeth=teeth,
        pressure_angle=np.radians(data["gearing"]["pressure_angle_deg"]),
        E=data["material"]["E"], nu=data["material"]["nu"])


def nominal_wave_generator(size: float) -> WaveGenerator:
    """Wave generator of a catalog size, geometrically similar to the size-25 one.

    Parameters
    ----------
    size : float
        Catalog size, e.g. 25 [-].

    Returns
    -------
    WaveGenerator
        Ball count as at size 25; support width and bearing stiffness in proportion to
        the size (``[wave_generator]`` in hdsim/data/units.toml).
    """
    wg = _data()["wave_generator"]
    d = size * 2.54e-3  # pitch diameter [m]
    return WaveGenerator(k_bearing=wg["k_bearing_size25"] * size / 25.0, balls=float(wg["balls"]),
                         support_width=wg["support_width"] * d,
                         engagement_fraction=wg["engagement_fraction"])


def calibrate(geometry, wave_generator, K1, K2, K3):
    """The calibration numbers that make the nominal chain reproduce K1, K2, K3.

    Parameters
    ----------
    geometry : FlexsplineGeometry
        Nominal geometry.
    wave_generator : WaveGenerator
        Wave-generator data.
    K1, K2, K3 : float
        Catalog stiffness of the three segments [N·m/rad].

    Returns
    -------
    tuple of float
        ``(kappa_mesh, e2, e3)`` [-]: the mesh-zone factor and the engagement ratios.

    Raises
    ------
    InputError
        If the structural compliance alone exceeds 1/K3.
    """
    chain = compliance_chain(geometry, wave_generator, 1.0)
    c_s, c_m = float(chain.structure), float(chain.mesh_zone)
    if c_s >= 1.0 / K3:
        raise InputError(f"the structural compliance alone ({c_s:.3g} rad/N·m) exceeds 1/K3: "
                         "the nominal geometry is too soft for the catalog stiffness")
    kappa = (1.0 / K1 - c_s) / c_m
    e2 = kappa * c_m / (1.0 / K2 - c_s)
    e3 = kappa * c_m / (1.0 / K3 - c_s)
    return kappa, e2, e3


class _ReadOnlyDict(dict):
    """A dict that refuses changes and pickles (`types.MappingProxyType` does not pickle,
    and the units travel to worker processes in studies)."""

    def _refuse(self, *args, **kwargs):
        raise TypeError("the provenance of a unit is read-only; build a new unit instead")

    __setitem__ = __delitem__ = __ior__ = _refuse
    clear = pop = popitem = setdefault = update = _refuse

    def __reduce__(self):
        return type(self), (dict(self),)

    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self


def _read_only(value):
    """A deep read-only copy: dicts become `_ReadOnlyDict`, lists tuples."""
    if isinstance(value, dict):
        return _ReadOnlyDict({k: _read_only(v) for k, v in value.items()})
    if isinstance(value, (list, tuple)):
        return tuple(_read_only(v) for v in value)
    return value


def assemble_unit(name: str, size: float, entry: dict, *, accuracy_arcmin: float,
                  backlash_arcmin: float, slip_arcmin: float, provenance: dict,
                  geometry: FlexsplineGeometry | None = None) -> HarmonicDrive:
    """A calibrated unit from its catalog figures: the one recipe of every unit.

    The built-in units and the drive files (`hdsim.model.drive_file`) are both built
    here: wave generator and bench inertias from the size, the nominal geometry from
    the assumed proportions (unless ``geometry`` is given), the calibration against
    K1, K2, K3 (`calibrate`) and the default effects.

    Parameters
    ----------
    name : str
        Unit name.
    size : float
        Catalog size [-] (pitch diameter in tenths of an inch); need not be a whole number.
    entry : dict
        ``ratio`` [-], ``rated_torque``, ``T1``, ``T2`` [N·m], ``K1``, ``K2``, ``K3`` [N·m/rad].
    accuracy_arcmin : float
        Transmission-accuracy class [arcmin] that sets the kinematic-error amplitudes.
    backlash_arcmin : float
        Dead-zone width seen at the output [arcmin].
    slip_arcmin : float
        Micro-slip range to each stop of the default friction [arcmin].
    provenance : dict
        Notes kept with the unit; the calibration numbers are added under ``calibration``.
    geometry : FlexsplineGeometry, optional
        The geometry to calibrate at (default `nominal_geometry` of ``size``).

    Returns
    -------
    HarmonicDrive
        The calibrated model with the default effects; its provenance is read-only.
    """
    data = _data()
    ratio = entry["ratio"]
    scale = size / 25.0
    wave_generator = nominal_wave_generator(size)
    if geometry is None:
        geometry = nominal_geometry(size, ratio)
    kappa, e2, e3 = calibrate(geometry, wave_generator, entry["K1"], entry["K2"], entry["K3"])
    bench = data["bench"]
    J_out = bench["J_out_size25"] * scale**5
    drive = DriveData(ratio=float(ratio), rated_torque=entry["rated_torque"],
                      J_in=bench["J_in_size25"] * scale**5, J_out=J_out)
    K1 = entry["K1"]
    fxd = data["effects"]
    ke = data["kinematic_error"]  # amplitudes: shares of the catalog accuracy class (units.toml)
    ke_class = arcmin_to_rad(accuracy_arcmin)
    kinematic_error = fx.FourierKinematicError(**{k: v * ke_class for k, v in ke["share"].items()},
                                               **ke["phases"], load_gain=ke["load_gain"])
    notes = dict(provenance)
    notes["calibration"] = {"kappa_mesh": kappa, "e2": e2, "e3": e3}
    return HarmonicDrive(
        name=name, geometry=geometry, wave_generator=wave_generator, drive=drive,
        calibration=Calibration(kappa_mesh=kappa),
        hardening=fx.ThreeSegmentHardening(T1=entry["T1"], T2=entry["T2"], e2=e2, e3=e3),
        backlash=fx.DeadZoneBacklash(gap=arcmin_to_rad(backlash_arcmin)),
        friction=fx.DahlSlip(slip_torque=fxd["slip_torque_per_TN"] * entry["rated_torque"],
                             slip_max=arcmin_to_rad(slip_arcmin)),
        damping=fx.ViscousDamping(coefficient=2.0 * bench["damping_ratio"] * np.sqrt(K1 * J_out)),
        kinematic_error=kinematic_error,
        # the unit is cached and every model derived from it shares this mapping
        provenance=_read_only(notes),
    )
