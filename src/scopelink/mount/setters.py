"""What the Mount API's setters accept: values every mount kind can represent and live with.

A setter that took a value the mount cannot represent would leave it unusable: a UTC date in the
year 9999 made every later reading of the simulator fail (the astrometry cannot reach it), and a
SynScan hand control keeps its year in one byte. So each setter checks its value first and
raises :class:`InvalidValueError` (Alpaca 0x401) with the reason; nothing reaches the device.
The ranges and why are in ``docs/reliability-safety.md`` ("Setters").
"""

from __future__ import annotations

import math
from datetime import UTC, datetime

from scopelink.mount.errors import InvalidValueError
from scopelink.mount.limits import Limits
from scopelink.mount.types import ParkPosition

__all__ = ["EARLIEST_UTC", "LATEST_UTC", "check_park_position", "check_time"]

EARLIEST_UTC = datetime(2001, 1, 1, tzinfo=UTC)
"""The earliest time a mount may be set to: a SynScan hand control counts years from 2000 in a
byte and keeps local time (a day of margin for any time zone), and no observation is older."""
LATEST_UTC = datetime(2099, 12, 31, 23, 59, 59, tzinfo=UTC)
"""The latest time a mount may be set to: far beyond any clock error, well inside what the
astrometry (leap seconds, Earth orientation) and the hand control's year byte can represent."""


def check_time(utc: datetime) -> None:
    """Raise :class:`InvalidValueError` unless ``utc`` is an aware time every mount can keep."""
    if not isinstance(utc, datetime):
        raise InvalidValueError(f"the time must be a date and time, not {utc!r}")
    if utc.tzinfo is None or utc.utcoffset() is None:
        raise InvalidValueError("the time must carry a time zone (use UTC)")
    if not EARLIEST_UTC <= utc <= LATEST_UTC:
        raise InvalidValueError(
            f"the time {utc.astimezone(UTC).isoformat()} lies outside what a mount can keep "
            f"({EARLIEST_UTC:%Y-%m-%d} to {LATEST_UTC:%Y-%m-%d} UTC): nothing was sent"
        )


def check_park_position(position: ParkPosition, limits: Limits) -> None:
    """Raise unless ``position`` is a real altitude and azimuth inside ``limits`` (a park
    position below the horizon would drive the mount there at every park)."""
    if not isinstance(position, ParkPosition):
        raise InvalidValueError(f"a park position is an altitude and azimuth, not {position!r}")
    alt, az = position.alt_deg, position.az_deg
    if not (math.isfinite(alt) and -90.0 <= alt <= 90.0):
        raise InvalidValueError(f"park altitude {alt}° must lie in [-90, +90]")
    if not (math.isfinite(az) and 0.0 <= az < 360.0):
        raise InvalidValueError(f"park azimuth {az}° must lie in [0, 360)")
    limits.check_altaz(alt, az, what="the park position")
