"""Earth satellites from a TLE, propagated by SGP4 (PyPI ``sgp4``, the Vallado et al. code).

SGP4 gives the satellite in the TEME frame; Greenwich mean sidereal time (IAU 1982, SGP4's own
convention) turns it to the Earth-fixed frame, where the WGS84 site is subtracted: the
*geometric* topocentric altitude and azimuth. The J2000-equivalent place is the J2000 RA/Dec that
the mount's own conversion (``j2000_to_observed``, without refraction) maps onto that direction,
so a mount pointing there with refraction on sees the satellite where the atmosphere puts it.
Not modelled: polar motion (< 0.5″), the satellite's light time (< 7 ms: ~50 m along its path,
< 30″ at 400 km), UT1 - UTC (0, as everywhere in the package: up to 0.9 s × the satellite's
angular speed near the site's meridian is taken up by the follower's loop). A TLE is good for a
few days around its epoch; the error grows by ~1-3 km a day for the ISS.
"""

from __future__ import annotations

import math
from pathlib import Path

import erfa
import numpy as np
from sgp4.api import SGP4_ERRORS, Satrec

from scopelink.astro._arrays import FloatArray
from scopelink.astro.catalog.names import name_key
from scopelink.astro.horizontal import observed_to_j2000
from scopelink.astro.site import Site
from scopelink.astro.targets.base import (
    MovingTarget,
    TargetError,
    TargetKind,
    read_target_file,
)

__all__ = ["SatelliteTarget", "Tle", "read_tles", "satellite_target"]

_WGS84 = 1


class Tle:
    """One two-line element set and its name (the line before it, or the catalogue number)."""

    def __init__(self, name: str, line1: str, line2: str) -> None:
        self.name = name
        self.line1 = line1
        self.line2 = line2
        self.satrec = Satrec.twoline2rv(line1, line2)
        self.number = line1[2:7].strip()


class SatelliteTarget(MovingTarget):
    """A satellite on its TLE (SGP4), topocentric for the site (module docstring)."""

    def __init__(self, tle: Tle, site: Site) -> None:
        super().__init__(tle.name, TargetKind.SATELLITE, site)
        self.site: Site = site
        self.tle = tle
        self._airless = site.without_refraction()
        lon, lat = math.radians(site.longitude_deg), math.radians(site.latitude_deg)
        self._site_m = np.asarray(erfa.gd2gc(_WGS84, lon, lat, site.elevation_m))
        sin_lat, cos_lat = math.sin(lat), math.cos(lat)
        sin_lon, cos_lon = math.sin(lon), math.cos(lon)
        # Earth-fixed to east, north, up at the site.
        self._enu = np.array(
            [
                [-sin_lon, cos_lon, 0.0],
                [-sin_lat * cos_lon, -sin_lat * sin_lon, cos_lat],
                [cos_lat * cos_lon, cos_lat * sin_lon, sin_lat],
            ]
        )

    def altaz(self, jd: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
        """Geometric (airless) topocentric altitude and azimuth in degrees (N = 0, E = 90)."""
        jd1, jd2 = (np.ravel(np.asarray(part, dtype=np.float64)) for part in jd)
        errors, teme_km, _ = self.tle.satrec.sgp4_array(jd1, jd2)
        bad = np.flatnonzero(errors)
        if bad.size:
            raise TargetError(
                f"{self.name}: SGP4 cannot propagate this TLE to that time "
                f"({SGP4_ERRORS.get(int(errors[bad[0]]), 'error')}); get a recent TLE"
            )
        theta = erfa.gmst82(jd1, jd2)  # UT1 taken as UTC
        cos_t, sin_t = np.cos(theta), np.sin(theta)
        x, y, z = teme_km[:, 0], teme_km[:, 1], teme_km[:, 2]
        fixed_m = np.stack([cos_t * x + sin_t * y, -sin_t * x + cos_t * y, z]) * 1000.0
        east, north, up = self._enu @ (fixed_m - self._site_m[:, None])
        alt = np.degrees(np.arctan2(up, np.hypot(east, north)))
        az = np.mod(np.degrees(np.arctan2(east, north)), 360.0)
        shape = np.shape(jd[0])
        return alt.reshape(shape), az.reshape(shape)

    def positions(self, jd: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
        alt, az = self.altaz(jd)
        ra, dec = observed_to_j2000(alt, az, jd, self._airless)
        return np.asarray(ra, dtype=np.float64), np.asarray(dec, dtype=np.float64)


def _checksum_ok(line: str) -> bool:
    total = sum(int(c) if c.isdigit() else (1 if c == "-" else 0) for c in line[:68])
    return line[68:69].isdigit() and total % 10 == int(line[68])


def read_tles(path: Path) -> list[Tle]:
    """Every element set in a TLE file (two-line or three-line with names), or a one-line
    :class:`TargetError` naming the line."""
    lines = read_target_file(path, "TLE file").splitlines()
    tles: list[Tle] = []
    name: str | None = None
    index = 0
    while index < len(lines):
        line = lines[index].rstrip()
        number = index + 1
        index += 1
        if not line.strip():
            continue
        if not line.startswith("1 "):
            name = line.strip().removeprefix("0 ")
            continue
        line2 = lines[index].rstrip() if index < len(lines) else ""
        index += 1
        for at, text, first in ((number, line, "1 "), (number + 1, line2, "2 ")):
            if not text.startswith(first) or len(text) < 69:
                raise TargetError(f"{path} line {at}: not line {first[0]} of a TLE (69 columns)")
            if not _checksum_ok(text):
                raise TargetError(f"{path} line {at}: TLE checksum does not match (a typo?)")
        try:
            tle = Tle(name or line[2:7].strip(), line, line2)
        except (ValueError, RuntimeError) as error:
            raise TargetError(f"{path} line {number}: bad TLE ({error})") from None
        if tle.satrec.error:
            raise TargetError(f"{path} line {number}: bad TLE (SGP4 error {tle.satrec.error})")
        tles.append(tle)
        name = None
    if not tles:
        raise TargetError(f"{path} holds no TLE (lines starting '1 ' and '2 ')")
    return tles


def satellite_target(name: str, path: Path, site: Site) -> SatelliteTarget:
    """The satellite called ``name`` (or with that catalogue number) in the TLE file ``path``;
    "ISS" finds "ISS (ZARYA)"."""
    tles = read_tles(path)
    wanted = name_key(name)
    for tle in tles:
        before, _, inside = tle.name.partition("(")
        keys = {name_key(tle.name), name_key(before), name_key(inside.rstrip(") ")), tle.number}
        if wanted in keys or name.strip() == tle.number:
            return SatelliteTarget(tle, site)
    names = ", ".join(tle.name for tle in tles[:5])
    more = f" and {len(tles) - 5} more" if len(tles) > 5 else ""
    raise TargetError(f"no satellite called {name!r} in {path} (it has {names}{more})")
