"""Sun, Moon and planets from DE421 against two independent implementations, offline:

- astropy's built-in ephemeris (ERFA epv00 for the Earth and Sun, moon98 for the Moon, good to a
  few arcseconds) through astropy's own light time, aberration and topocentric code, compared as
  apparent places of date (our astrometric J2000 taken through ``j2000_to_apparent``);
- PyEphem (VSOP87 planetary theory, ~1") astrometric geocentric J2000 places, for the planets
  (astropy's built-in planetary theory, plan94, is off by up to a minute of arc for the giants).

The required accuracy is 10"; what is seen is written beside each check.
"""

from __future__ import annotations

import math
from datetime import UTC, datetime
from typing import Any

import erfa
import numpy as np
import pytest

from scopelink.astro import JulianDate, Site, j2000_to_apparent
from scopelink.astro.catalog import EphemerisRangeError, ObjectKind, find, lookup

TIMES = [
    datetime(1995, 1, 15, 6, 0, tzinfo=UTC),
    datetime(2012, 7, 1, 12, 30, tzinfo=UTC),
    datetime(2026, 3, 1, 0, 0, tzinfo=UTC),
]
SITES = [Site(48.8, 2.35, 60.0), Site(-33.87, 151.21, 30.0), Site(19.82, -155.47, 4205.0)]
TOLERANCE_ARCSEC = 10.0


def separation_arcsec(ra1_h: Any, dec1_deg: Any, ra2_h: Any, dec2_deg: Any) -> float:
    radians = erfa.seps(
        np.radians(ra1_h * 15.0), np.radians(dec1_deg), np.radians(ra2_h * 15.0),
        np.radians(dec2_deg),
    )  # fmt: skip
    return float(np.degrees(radians) * 3600.0)


def astropy_apparent(body: str, when: datetime, site: Site | None) -> tuple[float, float]:
    from astropy.coordinates import TETE, EarthLocation, get_body, solar_system_ephemeris
    from astropy.time import Time

    moment = Time(when)
    location = (
        None
        if site is None
        else EarthLocation.from_geodetic(site.longitude_deg, site.latitude_deg, site.elevation_m)
    )
    with solar_system_ephemeris.set("builtin"):
        coordinate = get_body(body, moment, location=location)
    frame = TETE(obstime=moment) if location is None else TETE(obstime=moment, location=location)
    apparent = coordinate.transform_to(frame)
    return float(apparent.ra.hour), float(apparent.dec.deg)


@pytest.mark.parametrize("when", TIMES)
@pytest.mark.parametrize("body", ["Sun", "Moon"])
def test_geocentric_sun_and_moon_match_astropy(body: str, when: datetime) -> None:
    ours = lookup(body, when)
    apparent = j2000_to_apparent(ours.ra_hours, ours.dec_deg, when)
    reference = astropy_apparent(body.lower(), when, None)
    assert separation_arcsec(*apparent, *reference) < TOLERANCE_ARCSEC  # seen: Sun 0.01", Moon 6"


@pytest.mark.parametrize("when", TIMES)
@pytest.mark.parametrize("site", SITES)
def test_topocentric_moon_matches_astropy(site: Site, when: datetime) -> None:
    ours = lookup("Moon", when, site)
    apparent = j2000_to_apparent(ours.ra_hours, ours.dec_deg, when)
    reference = astropy_apparent("moon", when, site)
    assert separation_arcsec(*apparent, *reference) < TOLERANCE_ARCSEC  # seen: 2-6"


def test_topocentric_moon_is_shifted_by_the_lunar_parallax() -> None:
    when, site = TIMES[1], SITES[0]
    geocentric, topocentric = lookup("Moon", when), lookup("Moon", when, site)
    assert geocentric.distance_au is not None
    shift = separation_arcsec(
        geocentric.ra_hours, geocentric.dec_deg, topocentric.ra_hours, topocentric.dec_deg
    )
    horizontal_parallax = math.degrees(
        math.asin(6378.137 / (geocentric.distance_au * 1.495978707e8))
    )
    assert 0.0 < shift <= horizontal_parallax * 3600.0
    assert 0.89 < horizontal_parallax < 1.03  # about a degree, with the Moon's distance


@pytest.mark.parametrize("when", TIMES)
@pytest.mark.parametrize(
    "body", ["Sun", "Mercury", "Venus", "Mars", "Jupiter", "Saturn", "Uranus", "Neptune"]
)
def test_planets_match_pyephem_astrometric_places(body: str, when: datetime) -> None:
    import ephem

    theirs = getattr(ephem, body)()
    theirs.compute(ephem.Date(when.replace(tzinfo=None)), epoch=ephem.J2000)
    ours = lookup(body, when)
    error = separation_arcsec(
        ours.ra_hours, ours.dec_deg, math.degrees(theirs.a_ra) / 15.0, math.degrees(theirs.a_dec)
    )
    assert error < TOLERANCE_ARCSEC  # seen: < 1.5"
    # ours is the light-time distance, PyEphem's the geometric one: they differ by < 0.03 %
    assert ours.distance_au == pytest.approx(theirs.earth_distance, rel=3e-4)


def test_pluto_is_a_dwarf_planet_with_a_position() -> None:
    pluto = lookup("Pluto", TIMES[2])
    assert pluto.kind is ObjectKind.DWARF_PLANET
    assert pluto.distance_au is not None
    assert 28.0 < pluto.distance_au < 50.0


def test_sun_distance_at_perihelion() -> None:
    sun = lookup("Sun", datetime(2026, 1, 3, 17, tzinfo=UTC))
    assert sun.distance_au == pytest.approx(0.98330, abs=2e-5)


def test_positions_work_on_arrays_of_times() -> None:
    moon = find("Moon")
    jd1 = np.full(4, 2460000.5)
    jd2 = np.array([0.0, 0.25, 0.5, 0.75])
    ra, dec, distance = moon.position.astrometric((jd1, jd2), SITES[0])
    assert ra.shape == dec.shape == distance.shape == (4,)
    for i in range(4):
        one_ra, one_dec, _ = moon.position.astrometric((jd1[i], jd2[i]), SITES[0])
        assert separation_arcsec(ra[i], dec[i], one_ra, one_dec) < 1e-6


@pytest.mark.parametrize("year", [1899, 2201])
def test_outside_de421_raises_a_clear_error(year: int) -> None:
    with pytest.raises(EphemerisRangeError, match="covers 1899-12-04 to 2200-02-01 only"):
        find("Mars").position.astrometric(JulianDate(1721058.0, year * 365.25, "tt"), None)
