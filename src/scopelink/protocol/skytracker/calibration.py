"""Sky Tracker motor calibration factors (``S``/``s``) and the telescope sizes they stand for."""

from __future__ import annotations

import math

AZIMUTH_FACTOR_NUMERATOR = 332500.0
"""Azimuth factor = this / ground-board diameter in inches (spec, ``S`` command)."""

ELEVATION_FACTOR_NUMERATOR = 320300.0
"""Elevation factor = this / elevation-bearing (trunnion) diameter in inches (spec, ``S``)."""


def _checked_positive(value: float, what: str) -> float:
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{what} must be a positive finite number, got {value!r}")
    return value


def azimuth_factor(ground_board_diameter_in: float) -> float:
    """Azimuth calibration factor for a ground board of the given diameter (inches)."""
    return AZIMUTH_FACTOR_NUMERATOR / _checked_positive(
        ground_board_diameter_in, "ground-board diameter (in)"
    )


def ground_board_diameter_in(azimuth_factor_value: float) -> float:
    """Ground-board diameter (inches) that an azimuth calibration factor stands for."""
    return AZIMUTH_FACTOR_NUMERATOR / _checked_positive(azimuth_factor_value, "azimuth factor")


def elevation_factor(bearing_diameter_in: float) -> float:
    """Elevation calibration factor for an elevation bearing of the given diameter (inches)."""
    return ELEVATION_FACTOR_NUMERATOR / _checked_positive(
        bearing_diameter_in, "elevation-bearing diameter (in)"
    )


def bearing_diameter_in(elevation_factor_value: float) -> float:
    """Elevation-bearing diameter (inches) that an elevation calibration factor stands for."""
    return ELEVATION_FACTOR_NUMERATOR / _checked_positive(
        elevation_factor_value, "elevation factor"
    )
