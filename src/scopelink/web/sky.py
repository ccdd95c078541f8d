"""What the sky chart draws: named bright stars, the Sun, Moon and planets, at the mount's time.

Star positions (J2000 with proper motion) are taken once, at the first use: over a night they move
by far less than a pixel. Solar-system bodies are recomputed at every snapshot, because a
simulated clock may run thousands of times faster than real time. Every object is converted to
observed altitude and azimuth in one vectorised ERFA call per snapshot.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from functools import cache

import numpy as np

from scopelink.astro import Site, j2000_to_observed, observed_to_j2000
from scopelink.astro.catalog import EphemerisRangeError, ObjectKind
from scopelink.astro.catalog.entries import CatalogEntry
from scopelink.astro.catalog.solar_system import load_solar_system
from scopelink.astro.catalog.stars import load_named_stars

__all__ = ["SkyObject", "SkyPositions", "sky_frame", "sky_positions"]


@dataclass(frozen=True, slots=True)
class SkyObject:
    """One object as the chart draws it; ``magnitude`` is None where unknown (planets)."""

    name: str
    kind: ObjectKind
    magnitude: float | None
    alt_deg: float
    az_deg: float

    def as_json(self) -> dict[str, object]:
        return {
            "name": self.name,
            "kind": self.kind.value,
            "mag": self.magnitude,
            "alt": round(self.alt_deg, 3),
            "az": round(self.az_deg, 3),
        }


@dataclass(frozen=True, slots=True)
class _Stars:
    entries: tuple[CatalogEntry, ...]
    ra_hours: np.ndarray
    dec_deg: np.ndarray


@cache
def _stars(epoch: datetime) -> _Stars:
    entries = tuple(load_named_stars())
    ra = np.empty(len(entries))
    dec = np.empty(len(entries))
    for index, entry in enumerate(entries):
        star_ra, star_dec, _ = entry.position.astrometric(epoch, None)
        ra[index], dec[index] = float(star_ra), float(star_dec)
    return _Stars(entries, ra, dec)


@cache
def _bodies() -> tuple[CatalogEntry, ...]:
    return tuple(load_solar_system())


class SkyPositions:
    """Observed positions of the chart's objects; build once, call :meth:`at` per snapshot."""

    def __init__(self, epoch: datetime) -> None:
        # The year is enough for proper motion; a per-year key shares the cache between clients.
        year = epoch.replace(month=1, day=1, hour=0, minute=0, second=0, microsecond=0)
        self._stars = _stars(year)

    def at(self, t: datetime, site: Site) -> list[SkyObject]:
        """Every object at ``t`` seen from ``site``; bodies outside DE421's span are left out."""
        names: list[tuple[str, ObjectKind, float | None]] = [
            (entry.name, entry.kind, entry.magnitude) for entry in self._stars.entries
        ]
        ras = [self._stars.ra_hours]
        decs = [self._stars.dec_deg]
        for body in _bodies():
            try:
                ra, dec, _ = body.position.astrometric(t, site)
            except EphemerisRangeError:
                continue
            names.append((body.name, body.kind, None))
            ras.append(np.atleast_1d(ra))
            decs.append(np.atleast_1d(dec))
        alt, az = j2000_to_observed(np.concatenate(ras), np.concatenate(decs), t, site)
        alts, azs = np.atleast_1d(alt), np.atleast_1d(az)
        return [
            SkyObject(name, kind, magnitude, float(a), float(z))
            for (name, kind, magnitude), a, z in zip(names, alts, azs, strict=True)
        ]


def sky_frame(t: datetime, site: Site) -> dict[str, list[float]]:
    """Where the zenith and a point of the meridian above the north horizon (altitude 45°,
    azimuth 0°) are in J2000 (RA, Dec in degrees) at ``t``: the chart turns its J2000 data
    (constellations, Milky Way, deep-sky objects) into altitude and azimuth with the rotation
    these two directions define, so precession, nutation and aberration are the server's
    (ERFA's). Refraction is not in the rotation: the chart adds it (docs/dashboard.md)."""
    ra, dec = observed_to_j2000(np.array([90.0, 45.0]), np.array([0.0, 0.0]), t, site)
    ras, decs = np.atleast_1d(ra) * 15.0, np.atleast_1d(dec)
    return {
        "zenith": [round(float(ras[0]), 5), round(float(decs[0]), 5)],
        "north": [round(float(ras[1]), 5), round(float(decs[1]), 5)],
    }


def sky_positions(epoch: datetime) -> SkyPositions:
    """The chart's objects, with star positions taken at ``epoch``'s year."""
    return SkyPositions(epoch)
