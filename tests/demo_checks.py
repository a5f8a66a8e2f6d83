"""What ``hdsim demo`` must give, checked the same way in-process (``test_cli_simulate.py``)
and through the console script (``test_console.py``, ``-m slow``)."""

import pytest

from hdsim.model.catalog import load_unit
from hdsim.model.datasheet import catalog_entry
from hdsim.scenarios.run import read_run
from hdsim.units import rad_to_arcmin


def check_demo(data: dict, folder, png_image) -> None:
    """The demo's JSON ``data`` against the closed forms, and its ``folder`` of results.

    Closed forms (tests/test_stiffness_catalog.py): the ±4 % T_N span is elastic plus the
    backlash; the hysteresis loss is twice the micro-slip range."""
    unit, cat = load_unit(), catalog_entry("CSG-25-100")
    elastic = rad_to_arcmin(0.08 * cat["rated_torque"] / cat["K1"])
    assert data["elastic_lost_motion_arcmin"] == pytest.approx(elastic, rel=1e-12)
    assert data["metrics"]["lost_motion_arcmin"] == pytest.approx(
        elastic + rad_to_arcmin(float(unit.backlash.gap)), rel=0.01)
    assert data["metrics"]["hysteresis_loss_arcmin"] == pytest.approx(
        rad_to_arcmin(2 * float(unit.friction.slip_max)), rel=0.03)
    assert {"lost_motion.h5", "stiffness.h5", "lost_motion_loop.png", "stiffness_loop.png"} <= {
        f.name for f in folder.iterdir()}
    for name in ("lost_motion_loop.png", "stiffness_loop.png"):
        png_image(folder / name)
    stored = read_run(folder / "stiffness.h5")
    assert stored.metrics["K1_Nm_per_rad"][0] == pytest.approx(data["metrics"]["K1_Nm_per_rad"])
