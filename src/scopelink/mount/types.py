"""Values that cross the Mount API: what a mount can do, who it is, and where it points.

``PierSide`` is the astro layer's (ASCOM values), re-exported here for front ends.
"""

from __future__ import annotations

import enum
import time
from dataclasses import dataclass, field
from datetime import datetime

from scopelink.astro import PierSide
from scopelink.mount.frozen_init import fast_frozen_init

__all__ = [
    "AlignmentMode",
    "Capabilities",
    "GuideDirection",
    "Identity",
    "MountAxis",
    "MountState",
    "ParkPosition",
    "PierSide",
    "SlewProgress",
    "SlewTarget",
    "TrackingMode",
]


class AlignmentMode(enum.Enum):
    """Mechanical geometry, named as ASCOM names them."""

    ALT_AZ = "altaz"
    POLAR = "polar"  # fork or single-arm equatorial: no meridian flip
    GERMAN_POLAR = "german-polar"


class TrackingMode(enum.Enum):
    OFF = "off"
    SIDEREAL = "sidereal"
    LUNAR = "lunar"
    SOLAR = "solar"
    KING = "king"  # sidereal less the mean refraction drift (ASCOM driveKing)
    ALT_AZ = "altaz"  # sidereal motion followed on both axes of an alt-az mount
    PEC = "pec"  # sidereal with periodic error correction played back


class MountAxis(enum.Enum):
    PRIMARY = 0  # RA / azimuth
    SECONDARY = 1  # Dec / altitude


class GuideDirection(enum.Enum):
    NORTH = "north"
    SOUTH = "south"
    EAST = "east"
    WEST = "west"


@dataclass(frozen=True, slots=True)
class Identity:
    """Who answered on the link."""

    protocol: str  # "synscan", "skytracker", "simulator"
    model: str
    firmware: str = ""
    link: str = ""


@dataclass(frozen=True, slots=True)
class Capabilities:
    """What this mount, with this firmware, can do; front ends say 'not implemented' otherwise."""

    alignment_mode: AlignmentMode
    can_goto: bool = False
    can_goto_altaz: bool = False
    can_sync: bool = False
    can_park: bool = False
    can_set_park: bool = False
    can_pulse_guide: bool = False
    can_move_axis: tuple[bool, bool] = (False, False)
    max_axis_rate_deg_s: float = 0.0
    tracking_modes: frozenset[TrackingMode] = frozenset({TrackingMode.OFF})
    can_set_site: bool = False
    can_set_time: bool = False
    can_report_pier_side: bool = False
    max_tracking_offset_arcsec_s: float = 0.0
    """Largest custom tracking rate offset (RA and Dec, arcsec per SI second) the mount takes
    in :meth:`Mount.set_tracking_rates`; 0: it cannot set custom rates (docs/tracking.md)."""


@fast_frozen_init  # one is made per poll: its fields set through their slots (frozen_init.py)
@dataclass(frozen=True, slots=True)
class MountState:
    """One consistent snapshot of the mount, stamped with when it was read.

    Coordinates are ``None`` until the mount has reported them; RA/Dec are J2000 (the frame both
    device protocols use) and of date; Alt/Az are observed (refracted) for the configured site.

    ``read_at`` is on the mount's clock (a simulator's may run fast or stand still); how old a
    reading is, is measured on the PC's monotonic clock instead: ``received_s`` is
    :func:`time.monotonic` when the reading arrived (a newly made state is a new reading;
    ``dataclasses.replace`` keeps the stamp, so a state republished with a problem ages on).
    ``position_received_s`` is when the coordinates arrived, when that is earlier than the rest
    (a Sky Tracker in a GOTO reads its status but lends no bus for the position); None: with the
    rest. Neither takes part in comparisons.
    """

    read_at: datetime
    connected: bool = False
    ra_j2000_hours: float | None = None
    dec_j2000_deg: float | None = None
    ra_of_date_hours: float | None = None
    dec_of_date_deg: float | None = None
    alt_deg: float | None = None
    az_deg: float | None = None
    pier_side: PierSide = PierSide.UNKNOWN
    slewing: bool = False
    tracking: TrackingMode = TrackingMode.OFF
    parked: bool = False
    aligned: bool = False
    pulse_guiding: bool = False
    problems: tuple[str, ...] = field(default=())
    received_s: float = field(default_factory=time.monotonic, compare=False, repr=False)
    position_received_s: float | None = field(default=None, compare=False, repr=False)

    def age_s(self, now_s: float | None = None) -> float:
        """Seconds since this reading arrived (``now_s``: a :func:`time.monotonic` value)."""
        return (time.monotonic() if now_s is None else now_s) - self.received_s

    def position_age_s(self, now_s: float | None = None) -> float:
        """Seconds since the coordinates of this reading arrived."""
        received = self.received_s if self.position_received_s is None else self.position_received_s
        return (time.monotonic() if now_s is None else now_s) - received


@dataclass(frozen=True, slots=True)
class ParkPosition:
    """Where ``park`` points the mount: an observed altitude and azimuth, and the axis positions
    there when it was given as those (a driver that can then parks on them exactly)."""

    alt_deg: float
    az_deg: float
    axes_deg: tuple[float, float] | None = None

    @classmethod
    def pole(cls, latitude_deg: float) -> ParkPosition:
        """The celestial pole of the site's hemisphere (INDI's default equatorial park)."""
        return cls(abs(latitude_deg), 0.0 if latitude_deg >= 0 else 180.0)


@dataclass(frozen=True, slots=True)
class SlewTarget:
    """Where the last goto was sent: a J2000 position, or an observed altitude and azimuth."""

    ra_j2000_hours: float | None = None
    dec_j2000_deg: float | None = None
    alt_deg: float | None = None
    az_deg: float | None = None
    name: str = ""

    @property
    def equatorial(self) -> bool:
        return self.ra_j2000_hours is not None


@dataclass(frozen=True, slots=True)
class SlewProgress:
    """How far a slew still has to go (degrees on the sky) and, once it can be estimated, when it
    will arrive (seconds, from the recent closing speed)."""

    state: MountState
    distance_deg: float | None
    eta_s: float | None
