"""What every moving target offers: its J2000 place and rates at any instant, and its path.

A target is bound to a site (the Moon's parallax is up to ~1°, a satellite's is everything) and
answers with *J2000-equivalent* RA (hours) and Dec (degrees): the astrometric place a J2000 mount
points at, to which the frame conversions add aberration and refraction as for a star. Rates are
how fast those coordinates change, in the units of ``Mount.set_tracking_rates``: arcseconds of RA
(15″ = 1 s of RA) and arcseconds of Dec per SI second.
"""

from __future__ import annotations

import enum
import stat
from abc import ABC, abstractmethod
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np

from scopelink.astro._arrays import FloatArray
from scopelink.astro.site import Site
from scopelink.astro.timescales import utc_pair

__all__ = [
    "MAX_FILE_BYTES",
    "RATE_STEP_S",
    "MovingTarget",
    "TargetError",
    "TargetKind",
    "TargetRates",
    "read_target_file",
    "times_after",
    "utc_datetime",
]

RATE_STEP_S = 1.0
"""Half the interval of the central difference that gives a rate (the Moon's rate changes by
~1e-4 of itself over it; a low satellite's by < 1 %)."""


MAX_FILE_BYTES = 512 * 1024 * 1024
"""The largest elements or TLE file read (512 MiB): MPCORB.DAT, every numbered asteroid, is
about 300 MB; CelesTrak's whole catalogue of satellites is a few MB."""


class TargetError(ValueError):
    """A target that cannot be made: an unknown name, a bad elements or TLE file (one line)."""


def read_target_file(path: Path, what: str) -> str:
    """The text of an elements or TLE file (``what`` names it in errors), or a one-line
    :class:`TargetError`: only a regular file of at most ``MAX_FILE_BYTES`` is read (a device
    such as /dev/zero or a pipe would never end), undecodable bytes replaced."""
    try:
        info = path.stat()
        if stat.S_ISDIR(info.st_mode):
            raise TargetError(f"cannot read {what} {path}: it is a directory")
        if not stat.S_ISREG(info.st_mode):
            raise TargetError(f"cannot read {what} {path}: not a regular file")
        if info.st_size > MAX_FILE_BYTES:
            raise TargetError(
                f"cannot read {what} {path}: {info.st_size / 2**20:.0f} MiB is more than the "
                f"{MAX_FILE_BYTES / 2**20:.0f} MiB any {what} needs"
            )
        return path.read_text(encoding="utf-8", errors="replace")
    except OSError as error:
        raise TargetError(f"cannot read {what} {path}: {error.strerror or error}") from None


class TargetKind(enum.StrEnum):
    """What a target is (the web API's ``kind``)."""

    SUN = "sun"
    MOON = "moon"
    PLANET = "planet"
    COMET = "comet"
    ASTEROID = "asteroid"
    SATELLITE = "satellite"


@dataclass(frozen=True, slots=True)
class TargetRates:
    """Rates of the J2000-equivalent coordinates: arcsec of RA and of Dec per SI second."""

    ra_arcsec_per_s: float
    dec_arcsec_per_s: float


def times_after(start: datetime, offsets_s: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The UTC (jd1, jd2) pair of ``start`` plus each offset in seconds (vectorised)."""
    jd1, jd2 = utc_pair(start)
    offsets = np.asarray(offsets_s, dtype=np.float64)
    return np.broadcast_to(jd1, offsets.shape).copy(), jd2 + offsets / 86400.0


class MovingTarget(ABC):
    """A target whose place changes: ``positions`` is the one thing a kind of target writes."""

    name: str
    kind: TargetKind
    site: Site | None
    """Where the target is seen from; None: the geocentre (not for satellites)."""

    def __init__(self, name: str, kind: TargetKind, site: Site | None) -> None:
        self.name = name
        self.kind = kind
        self.site = site

    @abstractmethod
    def positions(self, jd: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
        """J2000-equivalent RA (h) and Dec (deg) at the UTC (jd1, jd2) arrays ``jd``."""

    def position(self, t: datetime) -> tuple[float, float]:
        """J2000-equivalent RA (h) and Dec (deg) at ``t``."""
        ra, dec = self.positions(times_after(t, np.zeros(1)))
        return float(ra[0]), float(dec[0])

    def rate(self, t: datetime, *, step_s: float = RATE_STEP_S) -> TargetRates:
        """How fast the coordinates change at ``t`` (central difference over ±``step_s``)."""
        ra, dec = self.positions(times_after(t, np.array([-step_s, step_s])))
        return _rates(ra, dec, 2.0 * step_s)

    def mean_rate(self, start: datetime, seconds: float) -> TargetRates:
        """The mean rates from ``start`` to ``seconds`` later: what carries a mount from the
        place at ``start`` to the place at the end (the follower's feed-forward)."""
        ra, dec = self.positions(times_after(start, np.array([0.0, seconds])))
        return _rates(ra, dec, seconds)

    def path(
        self, start: datetime, minutes: float = 60.0, points: int = 60
    ) -> list[tuple[float, float]]:
        """``points`` places (RA degrees, Dec degrees) evenly over the next ``minutes``."""
        offsets = np.linspace(0.0, minutes * 60.0, points)
        ra, dec = self.positions(times_after(start, offsets))
        return [(float(r) * 15.0, float(d)) for r, d in zip(ra, dec, strict=True)]

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r}, {self.kind.value})"


def _rates(ra_hours: FloatArray, dec_deg: FloatArray, seconds: float) -> TargetRates:
    # RA wraps at 24 h: the change is taken the short way round.
    d_ra_hours = (float(ra_hours[-1] - ra_hours[0]) + 12.0) % 24.0 - 12.0
    d_dec = float(dec_deg[-1] - dec_deg[0])
    return TargetRates(d_ra_hours * 15.0 * 3600.0 / seconds, d_dec * 3600.0 / seconds)


def utc_datetime(jd1: float, jd2: float) -> datetime:
    """An aware UTC datetime from a UTC quasi Julian date (to the microsecond)."""
    unix_days = (jd1 - 2440587.5) + jd2
    return datetime(1970, 1, 1, tzinfo=UTC) + timedelta(days=unix_days)
