"""The Sky Tracker's motor calibration factors as the driver hands them out and takes them in."""

from __future__ import annotations

from dataclasses import dataclass

from scopelink.mount import MountError
from scopelink.protocol.skytracker import (
    azimuth_factor,
    bearing_diameter_in,
    elevation_factor,
    ground_board_diameter_in,
)

__all__ = ["CalibrationFactors", "CalibrationRuleError"]


class CalibrationRuleError(MountError):
    """``S`` is refused: the Sky Tracker takes it only as the first command after power-on, once."""


@dataclass(frozen=True, slots=True)
class CalibrationFactors:
    """Azimuth factor = 332500 / ground-board diameter (in); elevation = 320300 / bearing (in)."""

    azimuth_factor: float
    elevation_factor: float

    @classmethod
    def for_telescope(
        cls, ground_board_diameter_in: float, bearing_diameter_in: float
    ) -> CalibrationFactors:
        """The factors for a ground board and an elevation bearing of these diameters (inches)."""
        return cls(azimuth_factor(ground_board_diameter_in), elevation_factor(bearing_diameter_in))

    @property
    def ground_board_diameter_in(self) -> float:
        return ground_board_diameter_in(self.azimuth_factor)

    @property
    def bearing_diameter_in(self) -> float:
        return bearing_diameter_in(self.elevation_factor)
