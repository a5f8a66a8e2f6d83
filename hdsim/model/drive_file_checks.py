"""What a drive file must not be: another kind of hdsim file, or figures that contradict each other.

Checks of `hdsim.model.drive_file.check_table` that need more than one key: a fit or
scenario file given where a drive file belongs, ``[flexspline]`` teeth other than the 2N
of the ratio, a modulus no flexspline material has.
"""

from __future__ import annotations

from hdsim.errors import InputError
from hdsim.model.geometry import E_MATERIALS

#: what the other TOML files of hdsim are, by their ``format`` key, and where they go
OTHER_FORMATS = {
    "hdsim-fit-1": "an hdsim fit file, not a drive file; load it with hdsim.identification.fit.load_fitted "
                   "('hdsim sobol --unit' takes both)",
    "hdsim-running-fit-1": "an hdsim running-torque fit file (the friction law of the wave-generator shaft), "
                           "not a drive file: paste its [input_friction] table into a driven scenario",
    "hdsim-breakaway-fit-1": "an hdsim breakaway fit file, not a drive file",
}


def refuse_other_file_kinds(table: dict, source: str) -> None:
    """InputError for another kind of hdsim file given as a drive file: a fit file (its
    ``format``) or a scenario file (its ``setup``, which every scenario has and no drive file)."""
    kind = table.get("format")
    if isinstance(kind, str) and kind in OTHER_FORMATS:
        raise InputError(f"{source}: {OTHER_FORMATS[kind]}")
    if "setup" in table and "ratio" not in table:
        setup = table["setup"]
        shown = f" (setup = {setup!r})" if isinstance(setup, str) else ""
        raise InputError(f"{source}: a scenario file{shown}, not a drive file: give it as the scenario, and "
                         "a built-in unit name or a drive file as the unit")


def check_teeth_and_material(values: dict, source: str) -> None:
    """InputError for ``[flexspline]`` teeth other than 2N, or a modulus no flexspline material has.

    A two-lobe wave generator has a circular spline with two teeth more than the flexspline,
    ``N = z_fs / (z_cs − z_fs)``, so the flexspline has ``2N`` teeth. The modulus must lie in
    `hdsim.model.geometry.E_MATERIALS`; the geometry's own check stops only at the rigid limit
    a fit may use, which no datasheet gives.
    """
    dims, ratio = values["flexspline"], values["ratio"]
    teeth = dims.get("teeth")
    if teeth is not None and abs(teeth - 2.0 * ratio) > 1e-9 * teeth:
        raise InputError(f"{source}: flexspline.teeth = {teeth:.12g} contradicts ratio = {ratio:g}: a strain-wave "
                         f"gear of ratio N has 2N = {2.0 * ratio:.12g} flexspline teeth (two-lobe wave generator); "
                         "leave teeth out or give the ratio that goes with it")
    E = dims.get("E")
    high = E_MATERIALS[1]
    if E is not None and E > high:
        raise InputError(f"{source}: flexspline.E = {E:.4g} Pa is above {high / 1e9:g} GPa, stiffer than any "
                         "flexspline material (steels 190-215 GPa): E is in Pa (steel 2.1e11)")
