"""What the Alpaca telescope says about itself and which equatorial frame it speaks."""

from __future__ import annotations

import enum
from dataclasses import dataclass

__all__ = ["EquatorialSystem", "TelescopeConfig"]


class EquatorialSystem(enum.IntEnum):
    """ASCOM ``EquatorialCoordinateType``: the frame RightAscension/Declination use."""

    TOPOCENTRIC = 1  # "JNow": apparent place of date, what most ASCOM drivers report
    J2000 = 2


@dataclass(frozen=True, slots=True)
class TelescopeConfig:
    """What the Alpaca telescope says about itself and which frame it speaks."""

    equatorial_system: EquatorialSystem = EquatorialSystem.TOPOCENTRIC
    name: str = "scopelink telescope"
    description: str = "scopelink: a Sky-Watcher SynScan / Sky Tracker mount over ASCOM Alpaca"
    slew_timeout_s: float = 600.0
    """Longest a synchronous slew (SlewToCoordinates, SlewToTarget, SlewToAltAz) may take."""
