"""How fast the sky turns: the sidereal, solar and lunar rates, in degrees per second.

The one definition of each in the package. The sidereal rate is also the unit of the "8x", "16x"
speeds of hand controls, the command line (``scopelink move dec 16x``) and the dashboard, whose
page gets it from the server (``sidereal_rate_deg_s`` in its mount JSON) rather than writing it.
"""

from __future__ import annotations

from typing import Final

__all__ = [
    "KING_RATE_DEG_S",
    "LUNAR_RATE_DEG_S",
    "SIDEREAL_DAY_S",
    "SIDEREAL_RATE_DEG_S",
    "SOLAR_RATE_DEG_S",
]

SIDEREAL_DAY_S: Final = 86164.0905
"""The mean sidereal day in SI seconds: one turn of the Earth relative to the equinox."""

SIDEREAL_RATE_DEG_S: Final = 360.0 / SIDEREAL_DAY_S
"""One turn per sidereal day (15.0411 arcsec/s): how fast the stars turn about the celestial
pole, and what equatorial tracking runs at."""

SOLAR_RATE_DEG_S: Final = 15.0 / 3600.0
"""One turn per solar day (15.0 arcsec/s, ASCOM's ``DriveRates`` solar rate): how fast the
Sun's hour angle grows; 0.3 % slower than the stars, which is the Sun's 1° a day eastwards."""

LUNAR_RATE_DEG_S: Final = 14.685 / 3600.0
"""ASCOM's ``DriveRates`` lunar rate (14.685 arcsec/s): the Moon's mean motion taken off the
sidereal rate."""

KING_RATE_DEG_S: Final = 15.0369 / 3600.0
"""ASCOM's ``DriveRates`` King rate (15.0369 arcsec/s): the sidereal rate slowed by the mean
effect of refraction on a star's hour-angle motion (King, 1931), for long unguided exposures."""
