"""Sun, Moon and planets from the JPL DE421 ephemeris (``de421`` package, read by ``jplephem``).

Positions are *astrometric*: the direction from the observer (the geocentre, or a site on the
WGS84 ellipsoid) to where the body was when the light now arriving left it, on ICRS axes. That is
a J2000 position a mount can take like a star's: aberration and light deflection are added by the
frame conversions (:func:`scopelink.astro.j2000_to_apparent` and friends). The packaged DE421
covers 1899-12-04 to 2200-02-01; TT stands in for TDB (< 2 ms). Outer planets are their system
barycentres (< 0.1").
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import de421
import erfa
import numpy as np
from jplephem.ephem import DateError, Ephemeris

from scopelink.astro._arrays import FloatArray
from scopelink.astro.catalog.entries import CatalogEntry, Prominence
from scopelink.astro.catalog.objects import ObjectKind
from scopelink.astro.site import Site
from scopelink.astro.timescales import TimeLike, tt_pair, ut1_pair

__all__ = ["EphemerisRangeError", "SolarSystemBody", "load_solar_system"]

_SPEED_OF_LIGHT_KM_PER_DAY = 299792.458 * 86400.0
_LIGHT_TIME_ITERATIONS = 3  # each shrinks the error ~10,000-fold

_BODIES = {
    "Sun": ("sun", ObjectKind.SUN),
    "Moon": ("moon", ObjectKind.MOON),
    "Mercury": ("mercury", ObjectKind.PLANET),
    "Venus": ("venus", ObjectKind.PLANET),
    "Mars": ("mars", ObjectKind.PLANET),
    "Jupiter": ("jupiter", ObjectKind.PLANET),
    "Saturn": ("saturn", ObjectKind.PLANET),
    "Uranus": ("uranus", ObjectKind.PLANET),
    "Neptune": ("neptune", ObjectKind.PLANET),
    "Pluto": ("pluto", ObjectKind.DWARF_PLANET),
}


class EphemerisRangeError(ValueError):
    """The time is outside the span the ephemeris covers."""


@cache
def _ephemeris() -> Ephemeris:
    return Ephemeris(de421)


def _coverage() -> str:
    """The ephemeris span as "YYYY-MM-DD to YYYY-MM-DD" (TDB)."""
    ephemeris = _ephemeris()
    ends = (erfa.jd2cal(jd, 0.0)[:3] for jd in (ephemeris.jalpha, ephemeris.jomega))
    return " to ".join(f"{int(y):04d}-{int(m):02d}-{int(d):02d}" for y, m, d in ends)


def _barycentric_km(segment: str, tdb1: FloatArray, tdb2: FloatArray) -> FloatArray:
    """Barycentric ICRS position (3, n) in km of ``segment`` ("earth" is derived from EMB)."""
    ephemeris = _ephemeris()
    if segment in ("earth", "moon"):
        earth_moon = ephemeris.position("earthmoon", tdb1, tdb2)
        geocentric_moon = ephemeris.position("moon", tdb1, tdb2)
        if segment == "earth":
            return np.asarray(earth_moon - geocentric_moon * ephemeris.earth_share)
        return np.asarray(earth_moon + geocentric_moon * ephemeris.moon_share)
    return np.asarray(ephemeris.position(segment, tdb1, tdb2))


def _site_gcrs_km(site: Site, t: TimeLike, tt1: FloatArray, tt2: FloatArray) -> FloatArray:
    """Geocentric ICRS-axes position (3, n) of the site: WGS84, Earth rotation, precession."""
    ut1 = ut1_pair(t)
    rotation_angle = erfa.era00(*(np.ravel(part) for part in ut1))
    position_velocity = erfa.pvtob(
        np.radians(site.longitude_deg),
        np.radians(site.latitude_deg),
        site.elevation_m,
        0.0,
        0.0,
        0.0,
        rotation_angle,
    )
    celestial_to_intermediate = erfa.c2i06a(tt1, tt2)
    gcrs_m = erfa.trxp(celestial_to_intermediate, position_velocity["p"])
    return np.asarray(gcrs_m, dtype=np.float64).T / 1000.0


@dataclass(frozen=True, slots=True)
class SolarSystemBody:
    """A body of the DE421 ephemeris, by its segment name ("sun", "moon", "mars", ...)."""

    segment: str

    def astrometric(
        self, t: TimeLike, site: Site | None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Light-time corrected astrometric RA (h), Dec (deg), distance (au), geo/topocentric."""
        tt1_in, tt2_in = tt_pair(t)
        shape = tt1_in.shape
        tt1, tt2 = np.ravel(tt1_in), np.ravel(tt2_in)
        try:
            observer = _barycentric_km("earth", tt1, tt2)
            if site is not None:
                observer = observer + _site_gcrs_km(site, t, tt1, tt2)
            light_days = np.zeros_like(tt1)
            for _ in range(_LIGHT_TIME_ITERATIONS):
                target = _barycentric_km(self.segment, tt1, tt2 - light_days)
                distance_km = np.linalg.norm(target - observer, axis=0)
                light_days = distance_km / _SPEED_OF_LIGHT_KM_PER_DAY
        except DateError:
            raise EphemerisRangeError(
                f"{self.segment} positions come from DE421, which covers {_coverage()} only"
            ) from None
        ra, dec = erfa.c2s((target - observer).T)
        hours = np.mod(np.degrees(ra) / 15.0, 24.0)
        au = _ephemeris().AU
        return (
            hours.reshape(shape),
            np.degrees(dec).reshape(shape),
            (distance_km / au).reshape(shape),
        )


def load_solar_system() -> list[CatalogEntry]:
    """The Sun, the Moon, the eight planets and Pluto."""
    return [
        CatalogEntry(
            name=name,
            aliases=(),
            kind=kind,
            type_description=kind.value.capitalize(),
            magnitude=None,
            constellation=None,
            position=SolarSystemBody(segment),
            prominence=Prominence.SOLAR_SYSTEM,
        )
        for name, (segment, kind) in _BODIES.items()
    ]
