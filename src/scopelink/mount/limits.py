"""Where the mount may point: the horizon and limits every motion command is checked against."""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass, field

from scopelink.mount.errors import InvalidValueError, LimitError

__all__ = [
    "DEFAULT_MAX_SYNC_DEG",
    "DEFAULT_MERIDIAN_DEG",
    "DEFAULT_MIN_TRACK_MINUTES",
    "MAX_MERIDIAN_DEG",
    "MAX_MIN_TRACK_MINUTES",
    "MAX_SUN_AVOIDANCE_DEG",
    "SUN_AVOIDANCE_DEG",
    "Limits",
]

SUN_AVOIDANCE_DEG = 15.0
"""Default radius of the Sun avoidance zone (degrees)."""
MAX_SUN_AVOIDANCE_DEG = 45.0
"""Largest radius accepted: a bigger zone would close a quarter of the sky."""
DEFAULT_MAX_SYNC_DEG = 10.0
"""How far a sync may correct the pointing (``limits.max_sync_deg``): the reach of a
plate-solve correction; farther is a wrong object or a typo, and would move every limit."""
DEFAULT_MERIDIAN_DEG = 5.0
"""How far past the meridian (degrees of hour angle, 20 minutes of tracking) a German mount's
counterweight may rise, on either side (``limits.meridian_east_deg``, ``meridian_west_deg``)."""
MAX_MERIDIAN_DEG = 45.0
"""Largest meridian limit accepted: three hours of tracking with the counterweight up."""
DEFAULT_MIN_TRACK_MINUTES = 10.0
"""A goto picks the pier side on which tracking lasts at least this long before the meridian
limit (``limits.min_track_minutes``)."""
MAX_MIN_TRACK_MINUTES = 180.0
"""Longest ``min_track_minutes`` accepted (what the largest meridian limit allows)."""


@dataclass(frozen=True, slots=True)
class Limits:
    """The sky the mount may point at, in observed (refracted) altitude and azimuth.

    ``horizon_deg`` is the lowest altitude allowed everywhere; ``horizon_profile`` optionally
    raises it by azimuth (pairs of azimuth and altitude, linearly interpolated, wrapping through
    north) for trees and houses. ``max_altitude_deg`` keeps alt-az mounts out of the zenith, where
    the azimuth speed diverges. ``sun_avoidance_deg`` is the radius of the zone around the Sun
    that no goto, park, sync or motion may enter (0 turns it off; :mod:`scopelink.mount.sun`).
    ``max_sync_deg`` bounds how far syncs may move the frame the limits are judged in (see
    :mod:`scopelink.mount.syncs`). ``meridian_east_deg`` / ``meridian_west_deg``,
    ``min_track_minutes`` and ``auto_flip`` are the meridian limits of German equatorial mounts
    (:mod:`scopelink.mount.meridian`; other mounts ignore them).
    """

    horizon_deg: float = 0.0
    max_altitude_deg: float = 90.0
    horizon_profile: tuple[tuple[float, float], ...] = field(default=())
    sun_avoidance_deg: float = SUN_AVOIDANCE_DEG
    max_sync_deg: float = DEFAULT_MAX_SYNC_DEG
    meridian_east_deg: float = DEFAULT_MERIDIAN_DEG
    meridian_west_deg: float = DEFAULT_MERIDIAN_DEG
    min_track_minutes: float = DEFAULT_MIN_TRACK_MINUTES
    auto_flip: bool = False

    def __post_init__(self) -> None:
        if not -10.0 <= self.horizon_deg <= 89.0:
            raise InvalidValueError(f"horizon {self.horizon_deg}° must lie between -10° and 89°")
        if not self.horizon_deg < self.max_altitude_deg <= 90.0:
            raise InvalidValueError(
                f"maximum altitude {self.max_altitude_deg}° must lie above the horizon "
                f"({self.horizon_deg}°) and at most 90°"
            )
        if not (
            math.isfinite(self.sun_avoidance_deg)
            and 0.0 <= self.sun_avoidance_deg <= MAX_SUN_AVOIDANCE_DEG
        ):
            raise InvalidValueError(
                f"Sun avoidance radius {self.sun_avoidance_deg}° must lie between 0° (off) and "
                f"{MAX_SUN_AVOIDANCE_DEG:g}°"
            )
        for az, alt in self.horizon_profile:
            if not (0.0 <= az < 360.0 and -10.0 <= alt <= 89.0):
                raise InvalidValueError(f"horizon profile point ({az}°, {alt}°) is out of range")
        if not (math.isfinite(self.max_sync_deg) and 0.0 < self.max_sync_deg <= 180.0):
            raise InvalidValueError(
                f"the sync reach (max_sync_deg) {self.max_sync_deg}° must lie in (0°, 180°]"
            )
        for name in ("meridian_east_deg", "meridian_west_deg"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= MAX_MERIDIAN_DEG):
                raise InvalidValueError(
                    f"the meridian limit ({name}) {value}° must lie between 0° and "
                    f"{MAX_MERIDIAN_DEG:g}° past the meridian"
                )
        minutes = self.min_track_minutes
        if not (math.isfinite(minutes) and 0.0 <= minutes <= MAX_MIN_TRACK_MINUTES):
            raise InvalidValueError(
                f"the tracking time a goto keeps before the meridian limit (min_track_minutes) "
                f"{minutes} must lie between 0 and {MAX_MIN_TRACK_MINUTES:g} minutes"
            )
        if not isinstance(self.auto_flip, bool):
            raise InvalidValueError(f"auto_flip must be true or false, not {self.auto_flip!r}")
        azimuths = [az for az, _ in self.horizon_profile]
        if azimuths != sorted(set(azimuths)):
            raise InvalidValueError("horizon profile azimuths must be increasing and distinct")

    def horizon_at(self, az_deg: float) -> float:
        """The lowest allowed altitude towards azimuth ``az_deg`` (degrees, north 0, east 90)."""
        if not self.horizon_profile:
            return self.horizon_deg
        az = az_deg % 360.0
        points = self.horizon_profile
        # Interpolate between neighbours, wrapping from the last point through north to the first.
        index = bisect_right([p[0] for p in points], az)
        (az0, alt0) = points[index - 1] if index > 0 else (points[-1][0] - 360.0, points[-1][1])
        (az1, alt1) = points[index] if index < len(points) else (points[0][0] + 360.0, points[0][1])
        profile = alt0 if az1 == az0 else alt0 + (alt1 - alt0) * (az - az0) / (az1 - az0)
        return max(self.horizon_deg, profile)

    def check_altaz(self, alt_deg: float, az_deg: float, *, what: str = "target") -> None:
        """Raise :class:`LimitError` unless (``alt_deg``, ``az_deg``) may be pointed at."""
        if not (math.isfinite(alt_deg) and math.isfinite(az_deg)):
            raise InvalidValueError(f"{what} position is not a number")
        floor = self.horizon_at(az_deg)
        if alt_deg < floor:
            raise LimitError(
                f"{what} is at altitude {alt_deg:.2f}° (azimuth {az_deg % 360.0:.1f}°), below the "
                f"configured horizon of {floor:.2f}°: nothing was sent to the mount"
            )
        if alt_deg > self.max_altitude_deg:
            raise LimitError(
                f"{what} is at altitude {alt_deg:.2f}°, above the configured limit of "
                f"{self.max_altitude_deg:.2f}°: nothing was sent to the mount"
            )
