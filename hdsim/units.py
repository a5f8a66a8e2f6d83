"""Unit conversions used only at the edges (CLI, files, figures). SI inside."""

from __future__ import annotations

import math

ARCMIN_PER_RAD = 10800.0 / math.pi
ARCSEC_PER_RAD = 648000.0 / math.pi
DEG_PER_RAD = 180.0 / math.pi
RAD_PER_S_PER_RPM = 2.0 * math.pi / 60.0

#: Angle units a file column name may end in (``angle_deg``, ``wg_angle_arcsec``), and
#: the size of one such unit [rad].
ANGLE_UNITS: dict[str, float] = {
    "rad": 1.0,
    "deg": math.pi / 180.0,
    "arcmin": math.pi / (180.0 * 60.0),
    "arcsec": math.pi / (180.0 * 3600.0),
    "rev": 2.0 * math.pi,  # encoders and drive software often log revolutions
}


def rad_to_arcmin(x):
    """[rad] → [arcmin]"""
    return x * ARCMIN_PER_RAD


def arcmin_to_rad(x):
    """[arcmin] → [rad]"""
    return x / ARCMIN_PER_RAD


def rad_to_arcsec(x):
    """[rad] → [arcsec]"""
    return x * ARCSEC_PER_RAD


def arcsec_to_rad(x):
    """[arcsec] → [rad]"""
    return x / ARCSEC_PER_RAD


def rpm_to_rad_per_s(x):
    """[rpm] → [rad/s]"""
    return x * RAD_PER_S_PER_RPM


def rad_per_s_to_rpm(x):
    """[rad/s] → [rpm]"""
    return x / RAD_PER_S_PER_RPM
