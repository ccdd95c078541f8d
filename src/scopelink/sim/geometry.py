"""Mount geometry: motor axis angles <-> where the tube points.

Every geometry maps the two axis counters (degrees) to the *observed* (refracted) altitude and
azimuth the tube points at, and back. The mount is perfect (level, polar-aligned, orthogonal), so
for an equatorial mount the tube's hour angle and declination are a pure rotation of the observed
altitude and azimuth (``astro.hadec_to_altaz``), and refraction lives in ``astro`` alone.

Equatorial axis conventions (``s`` = +1 north of the equator, -1 south; HA in hours):

* German equatorial (GEM). Power-on: counterweight down (primary 0), tube at the visible pole
  (secondary 90). Secondary within [-90, 90] is the *normal* state, beyond it the tube has gone
  over the pole (*flipped*)::

      normal:   HA = s (6 + primary/15),  Dec = s secondary
      flipped:  HA = s (primary/15 - 6),  Dec = s (180 - secondary)

  so with the primary within ±90° (counterweight never above the RA axis) the normal state covers
  the half of the sky west of the meridian in the north (tube east of the pier, ASCOM ``EAST``)
  and east of it in the south (tube west of the pier). The primary counts up as the hour angle
  grows in the north and down in the south, like a reversed RA motor there.
* Fork equatorial: ``HA = s primary/15``, ``Dec = s secondary``; no flip, pier side unknown.
* Alt-azimuth: primary = azimuth (north 0, east 90), secondary = altitude; power-on level and
  pointing north.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

from scopelink.astro import (
    PierSide,
    altaz_to_hadec,
    destination_side_of_pier,
    hadec_to_altaz,
    wrap_hour_angle,
    wrap_signed_degrees,
)
from scopelink.mount import AlignmentMode, GuideDirection, Limits
from scopelink.mount.meridian import limit_of, past_meridian_deg

__all__ = [
    "AltAzimuthGeometry",
    "ForkEquatorialGeometry",
    "Geometry",
    "GermanEquatorialGeometry",
    "geometry_for",
]


class Geometry(ABC):
    """How the two axis counters point the tube, at one site latitude."""

    alignment_mode: AlignmentMode
    primary_wraps: bool
    """Whether the primary axis turns freely (and so takes the short way round)."""

    def __init__(self, latitude_deg: float) -> None:
        self.latitude_deg = latitude_deg
        self.hemisphere = 1.0 if latitude_deg >= 0.0 else -1.0

    @property
    @abstractmethod
    def home(self) -> tuple[float, float]:
        """Counters at power-on."""

    @abstractmethod
    def to_observed(self, primary: float, secondary: float) -> tuple[float, float]:
        """Counters -> observed (altitude, azimuth) in degrees."""

    @abstractmethod
    def to_axes(self, alt_deg: float, az_deg: float, side: PierSide) -> tuple[float, float]:
        """Observed (altitude, azimuth) -> counters, on ``side`` of the pier where that matters.

        The primary is in [-180, 180) (or [0, 360) for azimuth); the secondary in [-90, 90], or
        (90, 270] for a flipped German mount.
        """

    def pier_side(self, primary: float, secondary: float) -> PierSide:
        """Side of the pier the tube is on (``UNKNOWN`` unless German equatorial)."""
        return PierSide.UNKNOWN

    def choose_side(self, alt_deg: float, az_deg: float, current: PierSide) -> PierSide:
        """Side of the pier a goto to (``alt_deg``, ``az_deg``) ends on."""
        return PierSide.UNKNOWN

    def meridian_margin_deg(self, primary: float, secondary: float, limits: Limits) -> float:
        """How far inside the meridian limits the tube is (only German mounts have them)."""
        return math.inf

    def axis_margin_deg(self, primary: float, secondary: float) -> float:
        """How far (degrees) the counters are inside the mechanical limits (< 0: beyond)."""
        return math.inf

    def pole_distance_deg(self, primary: float, secondary: float) -> float:
        """How far (degrees) the polar axis is from pointing the tube; ``inf`` for alt-az."""
        return math.inf

    @abstractmethod
    def guide_axis(self, direction: GuideDirection, secondary: float) -> tuple[int, float]:
        """Axis index (0 primary, 1 secondary) and sign of the rate that moves ``direction``."""


class _Equatorial(Geometry):
    """Equatorial geometries: counters <-> tube (HA, Dec) <-> observed (alt, az)."""

    @abstractmethod
    def to_hadec(self, primary: float, secondary: float) -> tuple[float, float]:
        """Counters -> tube (hour angle in [-12, 12) h, Dec degrees)."""

    @abstractmethod
    def from_hadec(self, ha_hours: float, dec_deg: float, side: PierSide) -> tuple[float, float]:
        """Tube (hour angle, Dec) -> counters."""

    def to_observed(self, primary: float, secondary: float) -> tuple[float, float]:
        ha, dec = self.to_hadec(primary, secondary)
        return hadec_to_altaz(ha, dec, self.latitude_deg)

    def to_axes(self, alt_deg: float, az_deg: float, side: PierSide) -> tuple[float, float]:
        ha, dec = altaz_to_hadec(alt_deg, az_deg, self.latitude_deg)
        return self.from_hadec(ha, dec, side)

    def pole_distance_deg(self, primary: float, secondary: float) -> float:
        _, dec = self.to_hadec(primary, secondary)
        return 90.0 - abs(dec)


class GermanEquatorialGeometry(_Equatorial):
    """German equatorial mount with a meridian flip.

    ``meridian_tolerance_deg``: how far past the meridian the counterweight may rise. A goto
    within that distance of the meridian stays on the current side of the pier (no flip), and
    motion stops when the primary reaches ±(90° + tolerance).
    """

    alignment_mode = AlignmentMode.GERMAN_POLAR
    primary_wraps = False

    def __init__(self, latitude_deg: float, *, meridian_tolerance_deg: float = 7.5) -> None:
        super().__init__(latitude_deg)
        if not 0.0 <= meridian_tolerance_deg <= 45.0:
            raise ValueError(f"meridian tolerance {meridian_tolerance_deg}° must lie in [0, 45]")
        self.meridian_tolerance_deg = meridian_tolerance_deg

    @property
    def home(self) -> tuple[float, float]:
        return 0.0, 90.0

    @property
    def normal_side(self) -> PierSide:
        """The unflipped side: tube east of the pier in the north, west in the south."""
        return PierSide.EAST if self.hemisphere > 0 else PierSide.WEST

    def to_hadec(self, primary: float, secondary: float) -> tuple[float, float]:
        s = self.hemisphere
        d = wrap_signed_degrees(secondary)
        if abs(d) <= 90.0:
            return wrap_hour_angle(s * (6.0 + primary / 15.0)), s * d
        dec = 180.0 - d if d > 0.0 else -180.0 - d
        return wrap_hour_angle(s * (primary / 15.0 - 6.0)), s * dec

    def from_hadec(self, ha_hours: float, dec_deg: float, side: PierSide) -> tuple[float, float]:
        s = self.hemisphere
        if side is PierSide.UNKNOWN:
            side = destination_side_of_pier(ha_hours)
        if side is self.normal_side:
            return wrap_signed_degrees(15.0 * (s * ha_hours - 6.0)), s * dec_deg
        # Flipped secondary in [90, 270]: with the normal [-90, 90] one continuous range through
        # the visible pole, so a flip never swings the tube through the pole below the horizon.
        return wrap_signed_degrees(15.0 * (s * ha_hours + 6.0)), 180.0 - s * dec_deg

    def pier_side(self, primary: float, secondary: float) -> PierSide:
        if abs(wrap_signed_degrees(secondary)) <= 90.0:
            return self.normal_side
        return PierSide.WEST if self.normal_side is PierSide.EAST else PierSide.EAST

    def choose_side(self, alt_deg: float, az_deg: float, current: PierSide) -> PierSide:
        """ASCOM's destination side, unless the current side reaches within the tolerance."""
        ha, dec = altaz_to_hadec(alt_deg, az_deg, self.latitude_deg)
        destination = destination_side_of_pier(ha)
        if current is PierSide.UNKNOWN or current is destination:
            return destination
        primary, _ = self.from_hadec(ha, dec, current)
        return current if abs(primary) <= 90.0 + self.meridian_tolerance_deg else destination

    def axis_margin_deg(self, primary: float, secondary: float) -> float:
        return 90.0 + self.meridian_tolerance_deg - abs(primary)

    def meridian_margin_deg(self, primary: float, secondary: float, limits: Limits) -> float:
        """How far (degrees of hour angle) the tube is inside the configured meridian limit of
        its pier side (``scopelink.mount.meridian``; the mechanical tolerance is apart)."""
        side = self.pier_side(primary, secondary)
        ha, _ = self.to_hadec(primary, secondary)
        past = past_meridian_deg(ha, side)
        return math.inf if past is None else limit_of(limits, side) - past

    def guide_axis(self, direction: GuideDirection, secondary: float) -> tuple[int, float]:
        s = self.hemisphere
        if direction in (GuideDirection.EAST, GuideDirection.WEST):
            return 0, s if direction is GuideDirection.WEST else -s
        flipped = abs(wrap_signed_degrees(secondary)) > 90.0
        sign = -s if flipped else s
        return 1, sign if direction is GuideDirection.NORTH else -sign


class ForkEquatorialGeometry(_Equatorial):
    """Fork (or single-arm) equatorial mount: no meridian flip."""

    alignment_mode = AlignmentMode.POLAR
    primary_wraps = True

    @property
    def home(self) -> tuple[float, float]:
        return 0.0, 90.0

    def to_hadec(self, primary: float, secondary: float) -> tuple[float, float]:
        s = self.hemisphere
        return wrap_hour_angle(s * primary / 15.0), s * secondary

    def from_hadec(self, ha_hours: float, dec_deg: float, side: PierSide) -> tuple[float, float]:
        s = self.hemisphere
        return wrap_signed_degrees(15.0 * s * ha_hours), s * dec_deg

    def guide_axis(self, direction: GuideDirection, secondary: float) -> tuple[int, float]:
        s = self.hemisphere
        if direction in (GuideDirection.EAST, GuideDirection.WEST):
            return 0, s if direction is GuideDirection.WEST else -s
        return 1, s if direction is GuideDirection.NORTH else -s


class AltAzimuthGeometry(Geometry):
    """Alt-azimuth mount: the counters are the azimuth and the altitude.

    The altitude axis stops at the zenith (an altitude counter beyond 90° would be the tube
    tipped over the top).
    """

    alignment_mode = AlignmentMode.ALT_AZ
    primary_wraps = True

    @property
    def home(self) -> tuple[float, float]:
        return 0.0, 0.0

    def to_observed(self, primary: float, secondary: float) -> tuple[float, float]:
        return secondary, primary % 360.0

    def to_axes(self, alt_deg: float, az_deg: float, side: PierSide) -> tuple[float, float]:
        return az_deg % 360.0, alt_deg

    def axis_margin_deg(self, primary: float, secondary: float) -> float:
        return 90.0 - abs(secondary)

    def guide_axis(self, direction: GuideDirection, secondary: float) -> tuple[int, float]:
        """North/south move in altitude (up/down), west/east in azimuth (+/-)."""
        if direction in (GuideDirection.EAST, GuideDirection.WEST):
            return 0, 1.0 if direction is GuideDirection.WEST else -1.0
        return 1, 1.0 if direction is GuideDirection.NORTH else -1.0


def geometry_for(
    mode: AlignmentMode, latitude_deg: float, *, meridian_tolerance_deg: float = 7.5
) -> Geometry:
    """The geometry of an ``AlignmentMode`` at ``latitude_deg``."""
    if mode is AlignmentMode.GERMAN_POLAR:
        return GermanEquatorialGeometry(latitude_deg, meridian_tolerance_deg=meridian_tolerance_deg)
    if mode is AlignmentMode.POLAR:
        return ForkEquatorialGeometry(latitude_deg)
    return AltAzimuthGeometry(latitude_deg)
