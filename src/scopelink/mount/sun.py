"""The Sun avoidance zone: no goto, park, sync or motion into the sky around the Sun.

``Limits.sun_avoidance_deg`` (default 15°, 0 turns it off) is the radius of the zone around the
Sun's observed position. Whatever the Sun's altitude, the zone applies (the Earth hides a Sun below
the horizon, but a target within 15° of it is itself deep in the twilight glow, and one rule has
no edge to get wrong at sunrise).

A goto is refused when its target lies inside the zone, or when the path the mount takes sweeps
through it. The path is modelled as the axes actually move: both motors start together at the same
top rate, so in the mount's own axis coordinates the tube moves diagonally until the shorter axis
arrives, then along the longer one alone (a "dog-leg"):

- alt-az: the axes are azimuth (the short way round) and altitude;
- fork equatorial: hour angle (the short way round) and declination;
- German equatorial: the mechanical axes, with a meridian flip taking the declination axis over
  the visible pole and the polar axis never through counterweight-up. The pier side the goto
  ends on is ASCOM's destination side; within 1 h of the meridian the firmware may keep the
  current side, so both are checked (and both starting sides when the mount does not report one).

A refused slew names a waypoint from which both legs are clear, when one of a few candidates is.
Decisions and figures: ``docs/reliability-safety.md`` ("Sun avoidance").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import UTC, datetime
from functools import lru_cache

import numpy as np

from scopelink.astro import (
    SOLAR_RATE_DEG_S,
    PierSide,
    Site,
    altaz_to_hadec,
    angular_separation_deg,
    destination_side_of_pier,
    j2000_to_observed,
)
from scopelink.astro.catalog.solar_system import EphemerisRangeError, SolarSystemBody
from scopelink.mount.errors import SunAvoidanceError
from scopelink.mount.types import AlignmentMode, MountState

__all__ = [
    "SETTING",
    "SunZone",
    "sun_j2000",
    "sun_zone",
]

SETTING = "limits.sun_avoidance_deg"
"""The settings-file key messages name."""

_PATH_STEP_DEG = 0.5
"""Largest axis motion between two checked points of a slew path."""
_LEAVING_TOLERANCE_DEG = 0.01
"""How much closer than its start a slew from inside the zone may sample (rounding)."""
_NEAR_MERIDIAN_HOURS = 1.0
"""Within this of the meridian a German mount may end a goto on either side of the pier."""
_SUN = SolarSystemBody("sun")


@lru_cache(maxsize=256)
def _sun_j2000_cached(site: Site, minute: int) -> tuple[float, float]:
    t = datetime.fromtimestamp(minute * 60.0, tz=UTC)
    ra, dec, _ = _SUN.astrometric(t, site)
    return float(ra), float(dec)


def sun_j2000(t: datetime, site: Site) -> tuple[float, float]:
    """The Sun's astrometric J2000 RA (hours) and Dec (degrees) seen from ``site`` at ``t``.

    Computed once per minute of ``t`` (the Sun moves 0.0007° a minute against the stars), so
    every reading of a guard can afford it.
    """
    return _sun_j2000_cached(site, math.floor(t.timestamp() / 60.0))


def sun_zone(radius_deg: float, site: Site, t: datetime, mode: AlignmentMode) -> SunZone | None:
    """The zone at ``t`` (None when ``radius_deg`` is 0); :class:`SunAvoidanceError` when the
    Sun cannot be placed (a clock outside the ephemeris): then nothing can be judged safe."""
    if radius_deg <= 0.0:
        return None
    try:
        return SunZone(radius_deg, site, t, mode)
    except EphemerisRangeError as error:
        raise SunAvoidanceError(
            f"the Sun cannot be placed at {t:%Y-%m-%d %H:%M} UTC ({error}), so no motion can be "
            "checked against it: nothing was sent to the mount (set the mount's time)"
        ) from None


@dataclass(frozen=True, slots=True)
class _Point:
    alt_deg: float
    az_deg: float


class SunZone:
    """The zone around the Sun at one time and site, for one mount geometry."""

    def __init__(self, radius_deg: float, site: Site, t: datetime, mode: AlignmentMode) -> None:
        self.radius_deg = radius_deg
        self.site = site
        self.at = t
        self.mode = mode
        ra, dec = sun_j2000(t, site)
        self.ra_j2000_hours, self.dec_j2000_deg = ra, dec
        self.alt_deg, self.az_deg = j2000_to_observed(ra, dec, t, site)
        self._ha_hours, self._dec_deg = altaz_to_hadec(self.alt_deg, self.az_deg, site.latitude_deg)

    @property
    def active(self) -> bool:
        return self.radius_deg > 0.0

    def distance_deg(self, alt_deg: float, az_deg: float, *, later_s: float = 0.0) -> float:
        """Degrees between an observed position and the Sun (``later_s`` seconds from now)."""
        if later_s == 0.0:
            return float(angular_separation_deg(az_deg, alt_deg, self.az_deg, self.alt_deg))
        ha, dec = altaz_to_hadec(alt_deg, az_deg, self.site.latitude_deg)
        sun_ha = self._ha_hours * 15.0 + SOLAR_RATE_DEG_S * later_s
        return float(angular_separation_deg(ha * 15.0, dec, sun_ha, self._dec_deg))

    def minutes_until_reached(self, alt_deg: float, az_deg: float, within_min: int) -> int | None:
        """The first whole minute (1..``within_min``) at which the zone covers a fixed observed
        position (a mount standing still), or None."""
        ha, dec = altaz_to_hadec(alt_deg, az_deg, self.site.latitude_deg)
        minutes = np.arange(1, within_min + 1)
        sun_ha = self._ha_hours * 15.0 + SOLAR_RATE_DEG_S * 60.0 * minutes
        distances = angular_separation_deg(ha * 15.0, dec, sun_ha, self._dec_deg)
        inside = np.flatnonzero(np.asarray(distances) < self.radius_deg)
        return int(minutes[inside[0]]) if inside.size else None

    def distance_j2000_deg(self, ra_hours: float, dec_deg: float) -> float:
        """Degrees between a J2000 position and the Sun (what tracking keeps constant)."""
        return float(
            angular_separation_deg(
                ra_hours * 15.0, dec_deg, self.ra_j2000_hours * 15.0, self.dec_j2000_deg
            )
        )

    # --- checks that raise --------------------------------------------------------------------

    def check_position(self, alt_deg: float, az_deg: float, *, what: str = "target") -> None:
        """Raise :class:`SunAvoidanceError` when (``alt_deg``, ``az_deg``) lies inside the zone."""
        if not self.active:
            return
        distance = self.distance_deg(alt_deg, az_deg)
        if distance < self.radius_deg:
            raise SunAvoidanceError(
                f"{what} is {distance:.1f}° from the Sun, inside the {self.radius_deg:g}° Sun "
                f"avoidance zone ({SETTING}): nothing was sent to the mount"
            )

    def check_slew(
        self,
        start: tuple[float, float] | None,
        start_side: PierSide,
        end: tuple[float, float],
        *,
        what: str = "the slew",
    ) -> None:
        """Raise :class:`SunAvoidanceError` when the slew from ``start`` to ``end`` (observed
        altitude, azimuth) would pass through the zone (from a start inside it: nearer the Sun
        than the start). An unknown start checks the end only."""
        if not self.active or start is None:
            return
        closest = self._closest_on_path(start, start_side, end)
        # A mount already inside (the Sun rose onto it) may leave: only deeper is refused.
        if closest >= min(self.radius_deg, self.distance_deg(*start) - _LEAVING_TOLERANCE_DEG):
            return
        advice = "goto a position away from the Sun first"
        waypoint = self._waypoint(start, start_side, end)
        if waypoint is not None:
            advice = (
                f"goto altitude {waypoint.alt_deg:.0f}° azimuth {waypoint.az_deg:.0f}° first, "
                "then to the target"
            )
        raise SunAvoidanceError(
            f"{what} from altitude {start[0]:.1f}° azimuth {start[1] % 360.0:.1f}° to altitude "
            f"{end[0]:.1f}° azimuth {end[1] % 360.0:.1f}° would pass {closest:.1f}° from the Sun, "
            f"inside the {self.radius_deg:g}° Sun avoidance zone ({SETTING}): nothing was sent "
            f"to the mount ({advice})"
        )

    def check_slew_from(
        self, state: MountState, end: tuple[float, float], *, what: str = "the slew"
    ) -> None:
        """:meth:`check_slew` from where ``state`` says the mount points."""
        start = None
        if state.alt_deg is not None and state.az_deg is not None:
            start = (state.alt_deg, state.az_deg)
        self.check_slew(start, state.pier_side, end, what=what)

    # --- the path model -----------------------------------------------------------------------

    def _closest_on_path(
        self, start: tuple[float, float], start_side: PierSide, end: tuple[float, float]
    ) -> float:
        """The least distance to the Sun along every path the mount may take."""
        return min(
            self._closest_along(a, b, wraps)
            for a, b, wraps in self._axis_paths(start, start_side, end)
        )

    def _axis_paths(
        self, start: tuple[float, float], start_side: PierSide, end: tuple[float, float]
    ) -> list[tuple[tuple[float, float], tuple[float, float], bool]]:
        """(start axes, end axes, primary wraps) for each path the mount may take."""
        lat = self.site.latitude_deg
        if self.mode is AlignmentMode.ALT_AZ:
            return [((start[1], start[0]), (end[1], end[0]), True)]
        ha0, dec0 = altaz_to_hadec(start[0], start[1], lat)
        ha1, dec1 = altaz_to_hadec(end[0], end[1], lat)
        if self.mode is AlignmentMode.POLAR:
            return [((ha0 * 15.0, dec0), (ha1 * 15.0, dec1), True)]
        starts = _sides(ha0, start_side)
        ends = _sides(ha1, PierSide.UNKNOWN)
        return [
            (_gem_axes(ha0, dec0, s0, lat), _gem_axes(ha1, dec1, s1, lat), False)
            for s0 in starts
            for s1 in ends
        ]

    def _closest_along(
        self, a: tuple[float, float], b: tuple[float, float], primary_wraps: bool
    ) -> float:
        d_primary = b[0] - a[0]
        if primary_wraps:
            d_primary = (d_primary + 180.0) % 360.0 - 180.0
        d_secondary = b[1] - a[1]
        longest = max(abs(d_primary), abs(d_secondary))
        u = np.linspace(0.0, longest, max(2, math.ceil(longest / _PATH_STEP_DEG) + 1))
        primary = a[0] + np.sign(d_primary) * np.minimum(u, abs(d_primary))
        secondary = a[1] + np.sign(d_secondary) * np.minimum(u, abs(d_secondary))
        lat = self.site.latitude_deg
        if self.mode is AlignmentMode.ALT_AZ:
            distances = angular_separation_deg(primary, secondary, self.az_deg, self.alt_deg)
        else:
            if self.mode is AlignmentMode.GERMAN_POLAR:
                ha_deg, dec = _gem_sky(primary, secondary, lat)
            else:
                ha_deg, dec = primary, secondary
            distances = angular_separation_deg(ha_deg, dec, self._ha_hours * 15.0, self._dec_deg)
        return float(np.min(distances))

    def _waypoint(
        self, start: tuple[float, float], start_side: PierSide, end: tuple[float, float]
    ) -> _Point | None:
        """A position both legs to and from which keep out of the zone, if one is found."""
        lat = self.site.latitude_deg
        pole = _Point(abs(lat), 0.0 if lat >= 0.0 else 180.0)
        away = (self.az_deg + 180.0) % 360.0
        candidates = [
            _Point(start[0], end[1]),
            _Point(end[0], start[1]),
            _Point(max(start[0], end[0], 30.0), away),
            pole,
            _Point(75.0, away),
        ]
        for candidate in candidates:
            # Whole degrees, as the message names it (and checked as named).
            point = _Point(float(round(candidate.alt_deg)), float(round(candidate.az_deg) % 360))
            where = (point.alt_deg, point.az_deg)
            if self.distance_deg(*where) < self.radius_deg:
                continue
            if self._closest_on_path(start, start_side, where) < self.radius_deg:
                continue
            if self._closest_on_path(where, PierSide.UNKNOWN, end) < self.radius_deg:
                continue
            return point
        return None


def _sides(ha_hours: float, known: PierSide) -> list[PierSide]:
    """The pier sides a German mount may be on at hour angle ``ha_hours``."""
    if known is not PierSide.UNKNOWN:
        return [known]
    destination = destination_side_of_pier(ha_hours)
    if abs(ha_hours) < _NEAR_MERIDIAN_HOURS or abs(ha_hours) > 12.0 - _NEAR_MERIDIAN_HOURS:
        other = PierSide.WEST if destination is PierSide.EAST else PierSide.EAST
        return [destination, other]
    return [destination]


def _gem_axes(ha_hours: float, dec_deg: float, side: PierSide, lat: float) -> tuple[float, float]:
    """A German mount's (polar, declination) axis angles on ``side`` (the simulator's
    convention, docs/simulator.md): the declination axis is continuous over the visible pole."""
    s = 1.0 if lat >= 0.0 else -1.0
    normal = PierSide.EAST if s > 0.0 else PierSide.WEST
    if side is normal:
        return (15.0 * (s * ha_hours - 6.0) + 180.0) % 360.0 - 180.0, s * dec_deg
    return (15.0 * (s * ha_hours + 6.0) + 180.0) % 360.0 - 180.0, 180.0 - s * dec_deg


def _gem_sky(
    primary: np.ndarray, secondary: np.ndarray, lat: float
) -> tuple[np.ndarray, np.ndarray]:
    """A German mount's axis angles -> (hour angle in degrees, Dec)."""
    s = 1.0 if lat >= 0.0 else -1.0
    flipped = np.abs(secondary) > 90.0
    ha_deg = np.where(flipped, s * (primary - 90.0), s * (primary + 90.0))
    dec = np.where(flipped, s * (180.0 - secondary), s * secondary)
    return ha_deg, dec
