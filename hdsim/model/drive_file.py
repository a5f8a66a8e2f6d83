"""Drive files: any harmonic drive from the figures of its datasheet.

A drive file is a small TOML file; `hdsim.model.catalog.load_unit` reads one wherever
it is given a path instead of a built-in unit name::

    name = "ZXF17-50"
    ratio = 50                      # required, 30-320
    rated_torque_Nm = 16.0          # required
    T1_Nm = 3.9                     # the catalog three-segment stiffness law: any subset
    T2_Nm = 12.0
    K1_Nm_per_rad = 1.0e4
    K2_Nm_per_rad = 1.4e4
    K3_Nm_per_rad = 1.6e4
    lost_motion_arcmin = 1.0        # optional: sets the backlash gap
    hysteresis_loss_arcmin = 1.0    # optional: sets the micro-slip range
    [flexspline]                    # optional: dimensions [m] as in the model (flexspline.h_pz ...)
    h_pz = 0.5e-3

The unit is built by the recipe of the built-in units (`hdsim.model.datasheet.assemble_unit`);
what the file does not give comes from the built-in units (`reference`):

1. **Rating at ratio 100.** The rated torque of a size falls with the ratio: fewer,
   larger teeth and a larger radial deflection of the flexspline (one module = d/2N)
   leave less fatigue margin for torque. The file's rating is referred to ratio 100,
   ``T_100 = T_N / f(N)``, with ``f`` from the Harmonic Drive CSG/HFUC rating tables
   (`rating_factor`: 0.32 at N = 30, 0.63 at 50, 0.92 at 80, 1 from 100). The **nearest
   built-in unit** is the one whose rated torque is closest to ``T_100`` on a log scale.
2. **Size.** Geometrically similar drives at the same stress carry a torque that grows
   with the pitch diameter cubed, ``T ∝ d³``. Between two built-in sizes the size is
   interpolated as a power law of ``T_100`` (the catalog's own local exponent, 0.17-0.43
   against the cube law's 1/3); beyond the built-in range the end unit is scaled by the cube law,
   ``s = s_ref (T_100 / T_N,ref)^(1/3)``. Geometry, wave generator and bench inertias
   follow from the size as for the built-ins (assumed proportions, bearing stiffness
   ∝ s, inertias ∝ s⁵).
3. **Stiffness law.** The breakpoints T1, T2 are torques at which more teeth engage, so
   they scale like the torque capacity (∝ d³); the torsional stiffness of geometrically
   similar bodies of one material grows with the pitch diameter cubed as well
   (``K ∝ G d³``, a thin tube's ``2π G R³ t / L`` with t, L ∝ R). Between built-in sizes
   T1, T2 and K1-K3 are interpolated as power laws of ``T_100`` like the size (so they
   rise steadily with the rating and equal the catalog at a catalog rating); beyond the
   range they are the end unit's figures × ``(s/s_ref)³``. Figures the file gives are
   kept as given and the missing ones keep the reference's shape: a breakpoint from the
   other through the reference's T2/T1, a missing K beside a given one through the
   reference's ratio to it, a missing K2 between given K1 and K3 where the reference's
   K2 lies between its K1 and K3 on a log scale. The reference stiffness is that of ratio
   100 (the makers list other K1-K3 for low ratios: give them for a drive below ratio 80).
   Breakpoints above T_N are kept: the makers list one T1, T2 per size for every ratio
   while the rating falls with the ratio, so at ratio 30 T2 lies above T_N.
4. **Lost motion** L (the ±4 % T_N test, full span) is the elastic span ``0.08 T_N/K1``
   plus the dead zone plus a small micro-slip share (docs/physics.md §13); a given L
   sets the dead zone: the gap whose quasi-static angle at ±0.04 T_N adds
   ``L − 0.08 T_N/K1`` (a little more than that difference, since the dead zone's
   rounded corners keep a share of the gap at this small load). Without it the gap is the
   built-ins' Oldham-coupling clearance seen at the output, ``0.07 arcmin × N_ref/N``
   (the clearance sits on the input side, so the output sees it divided by the ratio).
5. **Hysteresis loss** H (zero-torque width of the ±T_N loop) is about twice the
   micro-slip range of the default friction (the ±T_N loop slides to both stops), so a
   given H sets ``friction.slip_max = H/2``; without it the built-ins' 0.4 arcmin.
6. **Kinematic error** takes the nearest unit's transmission-accuracy class; the slip
   torque of the friction is ``0.06 T_N`` as for the built-ins.

**Calibration.** As for a built-in unit, `hdsim.model.datasheet.calibrate` makes the
closed-form chain reproduce K1, K2, K3. When the file gives any K together with
``[flexspline]`` dimensions, the datasheet's stiffness belongs to the datasheet's
geometry, so the calibration is made with those dimensions in place. When every K is
scaled, the calibration is made at the assumed proportions and the ``[flexspline]``
dimensions are applied afterwards, so they change the stiffness through the closed
forms exactly as ``--set flexspline.h_pz=…`` does.

The unit's ``provenance["drive_file"]`` says which figures were given, which were
scaled and from which built-in unit; ``provenance["catalog"]`` holds the effective
``ratio``, ``rated_torque``, ``T1``, ``T2``, ``K1``–``K3`` like a built-in unit's entry.

References: Harmonic Drive LLC, CSF/CSG series catalog (torsional stiffness p. 48,
hysteresis loss and Oldham coupling p. 49, rating tables); docs/physics.md.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import fields, replace
from pathlib import Path

import numpy as np

from hdsim.errors import InputError, unknown_name
from hdsim.model import datasheet
from hdsim.model.drive import HarmonicDrive
from hdsim.model.drive_file_checks import check_teeth_and_material, refuse_other_file_kinds
from hdsim.model.geometry import FlexsplineGeometry
from hdsim.model.parameters import not_whole
from hdsim.units import arcmin_to_rad, rad_to_arcmin

#: top-level keys: (unit, required, meaning); the datasheet figures in catalog order
KEYS = {
    "name": ("", True, "name of the drive, as its maker names it"),
    "ratio": ("-", True, "transmission ratio N (30-320; 2N flexspline teeth)"),
    "rated_torque_Nm": ("N·m", True, "rated output torque T_N"),
    "T1_Nm": ("N·m", False, "first breakpoint torque of the three-segment stiffness law"),
    "T2_Nm": ("N·m", False, "second breakpoint torque (may exceed T_N at low ratios)"),
    "K1_Nm_per_rad": ("N·m/rad", False, "torsional stiffness from 0 to T1"),
    "K2_Nm_per_rad": ("N·m/rad", False, "torsional stiffness from T1 to T2"),
    "K3_Nm_per_rad": ("N·m/rad", False, "torsional stiffness above T2"),
    "lost_motion_arcmin": ("arcmin", False, "lost motion of the ±4 % T_N test (full span)"),
    "hysteresis_loss_arcmin": ("arcmin", False, "hysteresis loss of the ±T_N loop"),
}
#: datasheet key -> field of a catalog entry (hdsim/data/units.toml)
CATALOG_FIELDS = {"ratio": "ratio", "rated_torque_Nm": "rated_torque", "T1_Nm": "T1", "T2_Nm": "T2",
                  "K1_Nm_per_rad": "K1", "K2_Nm_per_rad": "K2", "K3_Nm_per_rad": "K3"}
STIFFNESS_KEYS = ("K1_Nm_per_rad", "K2_Nm_per_rad", "K3_Nm_per_rad")
#: the lost-motion test load, a fraction of T_N each way (scenarios/lost_motion.toml)
LOST_MOTION_LOAD = 0.04


def flexspline_keys() -> tuple[str, ...]:
    """Names a ``[flexspline]`` table may hold: the fields of `FlexsplineGeometry`.

    Returns
    -------
    tuple of str
        ``('h_pz', 'h_c', 'R_v', 'R_k', 'h_p', 'R_i', ...)``, in [m] except ``teeth`` [-],
        ``E`` [Pa] and ``nu`` [-].
    """
    return tuple(f.name for f in fields(FlexsplineGeometry))


# --------------------------------------------------------------------------- reading


def read_drive_file(path: str | os.PathLike) -> dict:
    """The checked table of a drive file.

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file.

    Returns
    -------
    dict
        The file's keys with numbers as floats [units in the key names]; ``flexspline``
        (if present) maps dimension names to values [m, Pa or -].

    Raises
    ------
    InputError
        One line naming the file (and the key) for a missing file, malformed TOML, a fit
        or scenario file, an unknown key, a wrong type, a value that is not a positive
        finite number, a ratio outside 30-320 (``ratio_range`` in hdsim/data/units.toml)
        or whose 2N teeth are not a whole number, ``[flexspline]`` teeth other than 2N, a
        modulus above 500 GPa, ``T1 >= T2`` or a stiffness that falls with load (K1 > K2
        or K2 > K3).
    """
    source = _label(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")  # a Windows editor's BOM is no statement
    except FileNotFoundError:
        raise InputError(f"{source}: drive file not found") from None
    except IsADirectoryError:
        raise InputError(f"{source}: is a directory, expected a drive file (.toml)") from None
    except (UnicodeDecodeError, OSError, ValueError) as exc:  # no permission, a NUL byte, a name too long
        raise InputError(f"{source}: cannot read the drive file "
                         f"({getattr(exc, 'strerror', None) or exc})") from None
    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: not valid TOML: {exc}") from None
    return check_table(table, source)


def _label(path) -> str:
    """The path as messages show it: as it is, or quoted if it holds a line break or the like."""
    text = os.fspath(path) if isinstance(path, os.PathLike) else str(path)
    return text if text.isprintable() else repr(text)


def require_number(source, key: str, value) -> None:
    """InputError unless ``value`` is a TOML number (a string, a list or true is none)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{source}: {key} must be a number, got {type(value).__name__} {value!r}")


def _number(source: str, key: str, value) -> float:
    require_number(source, key, value)
    try:
        value = float(value)
    except OverflowError:  # an integer beyond the float range
        value = math.inf
    if not math.isfinite(value) or value <= 0.0:
        raise InputError(f"{source}: {key} must be a positive finite number, got {value:g}")
    return value


def check_table(table: dict, source: str) -> dict:
    """Check the table of a drive file (as `tomllib` gives it).

    Parameters
    ----------
    table : dict
        Key -> value.
    source : str
        The file, for the messages.

    Returns
    -------
    dict
        A copy with every number as a float.

    Raises
    ------
    InputError
        As `read_drive_file`.
    """
    refuse_other_file_kinds(table, source)
    known = list(KEYS) + ["flexspline"]
    for key in table:
        if key not in known:
            raise InputError(f"{source}: {unknown_name('drive file key', key, known)}")
    for key, (_, required, meaning) in KEYS.items():
        if required and key not in table:
            raise InputError(f"{source}: missing key '{key}' ({meaning}); required: "
                             + ", ".join(k for k, v in KEYS.items() if v[1]))
    name = table["name"]
    if not isinstance(name, str) or not name.strip() or not name.strip().isprintable():
        raise InputError(f"{source}: name must be a non-empty one-line string, got {name!r}")
    out = {"name": name.strip()}
    out.update({key: _number(source, key, table[key]) for key in KEYS if key != "name" and key in table})
    low, high = datasheet._data()["drive_file"]["ratio_range"]
    if not low <= out["ratio"] <= high:
        raise InputError(f"{source}: ratio = {out['ratio']:g} is outside {low:g}-{high:g}, the ratios strain-wave "
                         "gears are made in (fewer teeth deflect the flexspline too far: one module = d/2N)")
    if not_whole(2.0 * out["ratio"]):  # the assumed proportions have 2N teeth (two-lobe wave generator)
        raise InputError(f"{source}: ratio = {out['ratio']:.12g} means {2.0 * out['ratio']:.12g} flexspline teeth (2N), "
                         "not a whole number; expected a ratio in steps of 0.5")
    if "flexspline" in table:
        dims = table["flexspline"]
        if not isinstance(dims, dict):
            raise InputError(f"{source}: flexspline must be a table ([flexspline]), got {dims!r}")
        allowed = flexspline_keys()
        for key in dims:
            if key not in allowed:
                raise InputError(f"{source}: {unknown_name('flexspline dimension', key, allowed)}")
        out["flexspline"] = {key: _number(source, f"flexspline.{key}", v) for key, v in dims.items()}
        check_teeth_and_material(out, source)
    if "T1_Nm" in out and "T2_Nm" in out and out["T1_Nm"] >= out["T2_Nm"]:
        raise InputError(f"{source}: T1_Nm = {out['T1_Nm']:g} must be below T2_Nm = {out['T2_Nm']:g} N·m")
    given = [k for k in STIFFNESS_KEYS if k in out]
    for low, high in zip(given[:-1], given[1:]):
        if out[low] > out[high]:
            raise InputError(f"{source}: {low} = {out[low]:g} exceeds {high} = {out[high]:g} N·m/rad; "
                             "the three-segment law needs K1 <= K2 <= K3 (stiffness rises with load)")
    return out


# --------------------------------------------------------------------------- scaling


def rating_factor(ratio: float) -> float:
    """Rated torque of a size at ratio N over its rated torque at ratio 100.

    Parameters
    ----------
    ratio : float
        Transmission ratio [-].

    Returns
    -------
    float
        ``f(N)`` [-]: linear between the tabulated ratios (``[drive_file]`` in
        hdsim/data/units.toml, from the Harmonic Drive CSG and HFUC ratings), constant
        outside them (1 above ratio 100).
    """
    data = datasheet._data()["drive_file"]
    return float(np.interp(abs(ratio), data["rating_ratio"], data["rating_factor"]))


def reference(rated_torque: float, ratio: float) -> dict:
    """The catalog figures a drive of this rating would have, from the built-in units.

    Parameters
    ----------
    rated_torque : float
        Rated torque T_N of the drive [N·m].
    ratio : float
        Its ratio [-].

    Returns
    -------
    dict
        ``size`` [-], ``T1``, ``T2`` [N·m], ``K1``, ``K2``, ``K3`` [N·m/rad] at the drive's
        rated torque at ratio 100, ``T_100 = T_N / f(N)`` (`rating_factor`); ``nearest``,
        the built-in unit whose rated torque is closest to ``T_100`` on a log scale;
        ``between``, the two built-in units the figures come from; ``rule``, how.

    Notes
    -----
    Between two built-in sizes every figure is interpolated as a power law of ``T_100``
    (straight lines on log-log axes), so the figures rise steadily with the rating and
    equal the catalog at a catalog rating. Outside the built-in range the end unit is
    scaled by the cube law: size ∝ ``T_100^(1/3)``, T1, T2 and K1-K3 ∝ size³.
    """
    t100 = rated_torque / rating_factor(ratio)
    names = datasheet.unit_names()
    entries = sorted((datasheet.catalog_entry(n)["rated_torque"], n) for n in names)
    rated = np.array([t for t, _ in entries])
    nearest = entries[int(np.argmin(np.abs(np.log(t100 / rated))))][1]
    figures = ("size", "T1", "T2", "K1", "K2", "K3")
    if rated[0] <= t100 <= rated[-1]:
        i = int(np.clip(np.searchsorted(rated, t100), 1, len(rated) - 1))
        (ta, a), (tb, b) = entries[i - 1], entries[i]
        w = math.log(t100 / ta) / math.log(tb / ta)
        ea, eb = datasheet.catalog_entry(a), datasheet.catalog_entry(b)
        out = {k: ea[k] ** (1.0 - w) * eb[k] ** w for k in figures}
        out.update(between=(a, b), rule=f"power law in rated torque between {a} and {b}")
    else:
        end = entries[0] if t100 < rated[0] else entries[-1]
        e = datasheet.catalog_entry(end[1])
        cube = t100 / end[0]  # (s / s_ref)³
        out = {k: e[k] * (cube if k != "size" else cube ** (1.0 / 3.0)) for k in figures}
        out.update(between=(end[1], end[1]), rule=f"{end[1]} × (s/s_ref)³ (cube law)")
    out.update(nearest=nearest, T_100=t100)
    return out


def fill_datasheet(values: dict, ref: dict) -> tuple[dict, dict]:
    """T1, T2, K1, K2, K3 of a drive: the given ones, the others from ``ref``.

    Parameters
    ----------
    values : dict
        The drive file's checked table (`check_table`).
    ref : dict
        The reference figures for its rating (`reference`).

    Returns
    -------
    tuple of dict
        ``({key: value}, {filled key: how})``: the five figures under their file keys
        [N·m, N·m/rad] and, for each one not given, the rule that gave it.
    """
    out, how = {}, {}
    t1, t2 = values.get("T1_Nm"), values.get("T2_Nm")
    if t1 is None and t2 is None:
        t1, t2 = ref["T1"], ref["T2"]
        how["T1_Nm"] = how["T2_Nm"] = ref["rule"]
    elif t1 is None:
        t1 = t2 * ref["T1"] / ref["T2"]
        how["T1_Nm"] = f"T2 × T1/T2 of the reference ({ref['rule']})"
    elif t2 is None:
        t2 = t1 * ref["T2"] / ref["T1"]
        how["T2_Nm"] = f"T1 × T2/T1 of the reference ({ref['rule']})"
    out["T1_Nm"], out["T2_Nm"] = t1, t2
    k_ref = [ref["K1"], ref["K2"], ref["K3"]]
    given = [i for i, key in enumerate(STIFFNESS_KEYS) if key in values]
    for i, key in enumerate(STIFFNESS_KEYS):
        if i in given:
            out[key] = values[key]
        elif not given:
            out[key] = k_ref[i]
            how[key] = ref["rule"]
        elif min(given) < i < max(given):  # K2 between given K1 and K3: the reference's shape
            w = math.log(k_ref[1] / k_ref[0]) / math.log(k_ref[2] / k_ref[0])
            k1, k3 = values[STIFFNESS_KEYS[0]], values[STIFFNESS_KEYS[2]]
            out[key] = k1 * (k3 / k1) ** w
            how[key] = f"between K1 and K3 where the reference's K2 lies (log scale; {ref['rule']})"
        else:
            j = min(given, key=lambda g: (abs(g - i), g))
            out[key] = values[STIFFNESS_KEYS[j]] * k_ref[i] / k_ref[j]
            how[key] = f"K{j + 1} × K{i + 1}/K{j + 1} of the reference ({ref['rule']})"
    return out, how


# --------------------------------------------------------------------------- building


def load_drive_file(path: str | os.PathLike) -> HarmonicDrive:
    """The unit a drive file describes (see the module description).

    Parameters
    ----------
    path : str or os.PathLike
        The drive file.

    Returns
    -------
    HarmonicDrive
        The calibrated model with the default effects.

    Raises
    ------
    InputError
        One line naming the file for a file `read_drive_file` refuses, or figures no
        drive of this size can have (see `drive_from_table`).
    """
    return drive_from_table(read_drive_file(path), _label(path))


#: the model parameter a drive file's key sets, for a refusal that names the parameter
#: (the user wrote the key, not the parameter)
SET_BY = {"friction.slip_max": ("hysteresis_loss_arcmin",), "backlash.gap": ("lost_motion_arcmin", "ratio"),
          "calibration.kappa_mesh": STIFFNESS_KEYS, "calibration.kappa_struct": STIFFNESS_KEYS,
          "hardening.": STIFFNESS_KEYS + ("T1_Nm", "T2_Nm")}


def _set_by(message: str, values: dict) -> str:
    """'' or ", set by the file's KEY = VALUE": the keys of ``values`` behind the parameter a
    refusal names."""
    for parameter, keys in SET_BY.items():
        if parameter in message:
            shown = [f"{k} = {values[k]:g}" for k in keys if isinstance(values.get(k), (int, float))]
            if shown:
                return f" (set by the file's {', '.join(shown)})"
    return ""


def drive_from_table(table: dict, source: str) -> HarmonicDrive:
    """The unit of a drive file's table (what a run file stores to rebuild it).

    Parameters
    ----------
    table : dict
        The drive file's keys (checked again here).
    source : str
        The file it came from: messages, ``provenance["drive_file"]["path"]``.

    Returns
    -------
    HarmonicDrive
        The calibrated model with the default effects.

    Raises
    ------
    InputError
        As `check_table`; also for a size outside the scaling range, a lost motion below
        the elastic span ``0.08 T_N/K1``, or a geometry the closed forms refuse.
    """
    values = check_table(dict(table), source)
    data = datasheet._data()
    fxd = data["effects"]
    ratio, rated = values["ratio"], values["rated_torque_Nm"]
    ref = reference(rated, ratio)
    size, unit = ref["size"], ref["nearest"]
    lo, hi = data["drive_file"]["size_range"]
    if not lo <= size <= hi:
        raise InputError(f"{source}: rated_torque_Nm = {rated:g} at ratio {ratio:g} means size {size:.3g}, "
                         f"outside the sizes {lo:g}-{hi:g} the built-in units are scaled to")
    figures, how = fill_datasheet(values, ref)
    entry = {"size": size, "ratio": ratio, "rated_torque": rated,
             **{CATALOG_FIELDS[k]: v for k, v in figures.items()}}
    dims = values.get("flexspline", {})
    k_given = any(k in values for k in STIFFNESS_KEYS)
    ref_ratio = datasheet.catalog_entry(unit)["ratio"]
    slip = 0.5 * values["hysteresis_loss_arcmin"] if "hysteresis_loss_arcmin" in values else fxd["slip_arcmin"]
    try:
        geometry = datasheet.nominal_geometry(size, ratio)
        if dims and k_given:  # the datasheet's stiffness is the stiffness of the datasheet's geometry
            geometry = geometry.replace(**dims)
        model = datasheet.assemble_unit(
            values["name"], size, entry, accuracy_arcmin=data["kinematic_error"]["accuracy_arcmin"][unit],
            backlash_arcmin=fxd["backlash_arcmin"] * ref_ratio / ratio, slip_arcmin=slip,
            geometry=geometry, provenance={})
        if dims and not k_given:  # scaled stiffness at the assumed proportions; the file's dimensions act
            model = model.with_updates({f"flexspline.{k}": v for k, v in dims.items()})
            k_eff = model.hardening.stiffnesses(*model.split())
            entry.update({f"K{i + 1}": float(k) for i, k in enumerate(k_eff)})
            for key in STIFFNESS_KEYS:
                how[key] += ", then the [flexspline] dimensions through the closed forms"
        if "lost_motion_arcmin" in values:
            model = model.with_updates({"backlash.gap": _gap(values, model, unit)})
    except InputError as exc:
        raise InputError(f"{source}: {exc}{_set_by(str(exc), values)}") from None
    given = [k for k in values if k != "flexspline"] + [f"flexspline.{k}" for k in dims]
    scaled = [k for k in figures if k in how]
    note = {
        "path": source, "table": values, "given": given, "scaled_from": unit, "scaled": scaled,
        "between": ref["between"], "rules": how, "size": size, "rated_torque_at_ratio_100_Nm": ref["T_100"],
        "effects": {
            "backlash.gap": "dead zone adding lost_motion_arcmin − 0.08·T_N/K1 at ±4 % T_N"
            if "lost_motion_arcmin" in values else f"{fxd['backlash_arcmin']:g} arcmin × {ref_ratio:g}/N (Oldham clearance seen at the output)",
            "friction.slip_max": "hysteresis_loss_arcmin / 2" if "hysteresis_loss_arcmin" in values
            else f"{fxd['slip_arcmin']:g} arcmin (built-in default)",
            "friction.slip_torque": f"{fxd['slip_torque_per_TN']:g} × rated_torque_Nm (built-in default)"},
        "assumed": [f"flexspline proportions, wave generator and bench inertias of size {size:.4g} "
                    "(hdsim/data/units.toml)", f"kinematic error: transmission-accuracy class of {unit}"],
    }
    status = f"drive file {source}: given " + ", ".join(given)
    if scaled:
        status += f"; scaled ({ref['rule']}): " + ", ".join(scaled)
    provenance = {"catalog": dict(entry, status=status),
                  "calibration": dict(model.provenance["calibration"]),
                  "geometry": ("drive file [flexspline] on " if dims else "") + "assumed proportions, "
                              "hdsim/data/units.toml",
                  "drive_file": note}
    return replace(model, provenance=datasheet._read_only(provenance))


def drive_table(model: HarmonicDrive) -> dict | None:
    """The drive-file table a model was built from, as plain dicts (for a run or fit file to
    store, and `drive_from_table` to rebuild it); None for a built-in unit."""
    note = model.provenance.get("drive_file")
    return None if note is None else _plain(note["table"])


def _plain(value):
    """A read-only provenance table as plain dicts and lists (what TOML writers take)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _gap(values: dict, model: HarmonicDrive, unit: str) -> float:
    """Backlash gap [rad] that makes the ±4 % T_N lost motion the file's value.

    The lost motion is the elastic span ``0.08 T_N/K1`` plus twice the angle the dead zone
    takes at ``0.04 T_N`` (`Backlash.twist_at_torque`: the full gap less what its rounded
    corners keep back); the gap that gives the file's value is found by bisection.
    """
    lost = values["lost_motion_arcmin"]
    k1 = float(model.base_stiffness)
    load = np.array([LOST_MOTION_LOAD * values["rated_torque_Nm"]])
    elastic = rad_to_arcmin(2.0 * load[0] / k1)
    if lost < elastic:
        k1_from = "given" if "K1_Nm_per_rad" in values else f"scaled from {unit}"
        raise InputError(f"lost_motion_arcmin = {lost:g} is below the elastic span 0.08·T_N/K1 = "
                         f"{elastic:.3g} arcmin of the ±4 % T_N test (K1 {k1_from}); expected at least that "
                         "(give K1_Nm_per_rad from the same datasheet, or drop lost_motion_arcmin)")
    target = arcmin_to_rad(lost - elastic)
    law = type(model.backlash)

    def span(gap):
        return 2.0 * float(law(gap=gap).twist_at_torque(load, k1)[0])

    low, high = 0.0, target
    while span(high) < target:
        high *= 2.0
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if span(mid) < target else (low, mid)
    return 0.5 * (low + high)


# --------------------------------------------------------------------------- template


def template() -> str:
    """A commented drive-file template: every key, its unit, which are required.

    The required keys hold the figures of the default unit (CSG-25-100); the optional
    ones are commented out with that unit's values, so the template loads as it is.

    Returns
    -------
    str
        TOML text.
    """
    name = datasheet.default_unit()
    entry = datasheet.catalog_entry(name)
    geometry = datasheet.nominal_geometry(entry["size"], entry["ratio"]).as_dict()
    example = {"name": "MY-DRIVE-25-100", "ratio": entry["ratio"], "rated_torque_Nm": entry["rated_torque"],
               **{k: entry[v] for k, v in CATALOG_FIELDS.items() if k not in ("ratio", "rated_torque_Nm")},
               "lost_motion_arcmin": 1.0, "hysteresis_loss_arcmin": 1.0}
    lines = ["# hdsim drive file: any harmonic drive from its datasheet.",
             "# Use it wherever a built-in unit is accepted: hdsim simulate lost_motion --unit this.toml",
             "# Required keys are set below; remove the '# ' in front of an optional key to give it.",
             f"# Whatever is not given is scaled from the nearest built-in unit (values shown: {name}).",
             "# Units are in the key names; lengths in [flexspline] are in metres, E in Pa.",
             "# T1, T2 above rated_torque_Nm are kept (low-ratio datasheets list the size's breakpoints):",
             "# the stiffness test, loaded to ±T_N, measures no K above them: raise its load amplitude",
             "# (hdsim simulate stiffness --unit this.toml --set scenario.load.amplitude=3).", ""]
    for key, (unit, required, meaning) in KEYS.items():
        value = example[key]
        text = f'"{value}"' if isinstance(value, str) else f"{value:.6g}"
        line = f"{'' if required else '# '}{key} = {text}"
        lines.append(f"{line:<34} # {'REQUIRED' if required else 'optional'}: {meaning}"
                     + (f" [{unit}]" if unit else ""))
    lines += ["", "# Optional: flexspline dimensions as in the model (flexspline.NAME), in SI units.",
              "# With any K given they are the datasheet's geometry (the calibration uses them);",
              "# without, they change the scaled stiffness through the closed forms.",
              "# [flexspline]"]
    meta = {f.name: f.metadata for f in fields(FlexsplineGeometry)}
    for key in flexspline_keys():
        line = f"# {key} = {float(geometry[key]):.6g}"
        note = {"teeth": ", 2 × ratio", "module": ", default pitch diameter / teeth"}.get(key, "")
        lines.append(f"{line:<34} # {meta[key]['doc']} [{meta[key]['unit']}{note}]")
    return "\n".join(lines) + "\n"
