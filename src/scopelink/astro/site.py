"""The observing site: where the mount stands and the air it looks through."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

__all__ = ["STANDARD_WAVELENGTH_UM", "Site"]

STANDARD_WAVELENGTH_UM = 0.55
"""Effective wavelength for refraction: visual light (ERFA treats > 100 µm as radio)."""

_SEA_LEVEL_PRESSURE_HPA = 1013.25


@dataclass(frozen=True, slots=True)
class Site:
    """An observing site.

    Longitude is east-positive (west negative), latitude north-positive, both in degrees.
    ``pressure_hpa=None`` means "standard atmosphere at this elevation"; ``pressure_hpa=0``
    switches refraction off. Relative humidity is a fraction in [0, 1].
    """

    latitude_deg: float
    longitude_deg: float
    elevation_m: float = 0.0
    pressure_hpa: float | None = None
    temperature_c: float = 10.0
    relative_humidity: float = 0.5
    wavelength_um: float = STANDARD_WAVELENGTH_UM

    def __post_init__(self) -> None:
        _check_range("latitude_deg", self.latitude_deg, -90.0, 90.0, "north positive")
        _check_range("longitude_deg", self.longitude_deg, -180.0, 180.0, "east positive")
        _check_range("elevation_m", self.elevation_m, -500.0, 10000.0, "metres above sea level")
        if self.pressure_hpa is not None:
            _check_range("pressure_hpa", self.pressure_hpa, 0.0, 1200.0, "0 turns refraction off")
        _check_range("temperature_c", self.temperature_c, -60.0, 60.0, "air temperature, °C")
        _check_range("relative_humidity", self.relative_humidity, 0.0, 1.0, "a fraction, not %")
        _check_range("wavelength_um", self.wavelength_um, 0.3, 30000.0, "micrometres")

    @property
    def effective_pressure_hpa(self) -> float:
        """The given pressure, or the standard atmosphere at this elevation when none is given.

        The default follows the SOFA astrometry cookbook: p = 1013.25 exp(-h / (29.3 T)), T in K.
        """
        if self.pressure_hpa is not None:
            return self.pressure_hpa
        kelvin = self.temperature_c + 273.15
        return _SEA_LEVEL_PRESSURE_HPA * math.exp(-self.elevation_m / (29.3 * kelvin))

    @property
    def refracts(self) -> bool:
        """Whether observed positions include atmospheric refraction (pressure above zero)."""
        return self.effective_pressure_hpa > 0.0

    def without_refraction(self) -> Site:
        """The same site with refraction switched off (pressure 0)."""
        return replace(self, pressure_hpa=0.0)


def _check_range(name: str, value: object, low: float, high: float, meaning: str) -> None:
    if not isinstance(value, int | float) or isinstance(value, bool):
        raise TypeError(f"Site.{name} must be a number, got {type(value).__name__}")
    if not low <= float(value) <= high:
        raise ValueError(f"Site.{name} must be in [{low:g}, {high:g}] ({meaning}), got {value!r}")
