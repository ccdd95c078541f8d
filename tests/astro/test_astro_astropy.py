"""Our ERFA wrappers against astropy, an independent implementation, offline with its bundled data.

Stated tolerances (docs/astronomy.md): apparent of date 0.1", observed alt/az 1" with refraction
off (astropy also applies polar motion, which we neglect), 1" with refraction above 10° altitude.
"""

from __future__ import annotations

from typing import Any

import erfa
import numpy as np
import pytest

from scopelink.astro.frames import j2000_to_apparent
from scopelink.astro.horizontal import j2000_to_observed
from scopelink.astro.sidereal import gast_hours, gmst_hours
from scopelink.astro.site import Site

SITES = [
    Site(51.4779, -0.0015, 46.0),
    Site(19.8207, -155.468, 4205.0, temperature_c=2.0),
    Site(-33.8688, 151.2093, 30.0, temperature_c=20.0, relative_humidity=0.7),
    Site(78.2232, 15.6267, 10.0, temperature_c=-15.0),
]
TIMES = ["2005-03-20T04:00:00", "2012-07-01T12:30:00", "2019-11-11T23:59:30"]


@pytest.fixture(scope="module")
def positions() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(2024)
    ra_hours = rng.uniform(0, 24, 200)
    dec_deg = np.degrees(np.arcsin(rng.uniform(-0.999, 0.999, 200)))
    return ra_hours, dec_deg


def astropy_time(iso: str) -> Any:
    from astropy.time import Time

    return Time(iso, scale="utc")


def separation_arcsec(lon1: Any, lat1: Any, lon2: Any, lat2: Any) -> np.ndarray:
    radians = erfa.seps(*(np.radians(np.asarray(x, dtype=float)) for x in (lon1, lat1, lon2, lat2)))
    return np.asarray(np.degrees(radians) * 3600)


@pytest.mark.parametrize("iso", TIMES)
def test_apparent_of_date_matches_astropy_tete(
    iso: str, positions: tuple[np.ndarray, np.ndarray]
) -> None:
    import astropy.units as u
    from astropy.coordinates import TETE, SkyCoord

    t = astropy_time(iso)
    ra, dec = positions
    theirs = SkyCoord(ra=ra * u.hourangle, dec=dec * u.deg, frame="icrs").transform_to(
        TETE(obstime=t)
    )
    our_ra, our_dec = j2000_to_apparent(ra, dec, t)
    errors = separation_arcsec(np.asarray(our_ra) * 15, our_dec, theirs.ra.deg, theirs.dec.deg)
    assert errors.max() < 0.1


@pytest.mark.parametrize("iso", TIMES)
def test_sidereal_time_matches_astropy(iso: str) -> None:
    t = astropy_time(iso)
    dut1 = float(t.delta_ut1_utc)
    mean = t.sidereal_time("mean", "greenwich", model="IAU2006").hour
    apparent = t.sidereal_time("apparent", "greenwich", model="IAU2006A").hour
    assert gmst_hours(t, ut1_minus_utc_s=dut1) == pytest.approx(mean, abs=1e-4 / 3600)
    assert gast_hours(t, ut1_minus_utc_s=dut1) == pytest.approx(apparent, abs=1e-4 / 3600)


def astropy_altaz(site: Site, t: Any, ra: np.ndarray, dec: np.ndarray, *, refraction: bool) -> Any:
    import astropy.units as u
    from astropy.coordinates import AltAz, EarthLocation, SkyCoord

    location = EarthLocation.from_geodetic(
        site.longitude_deg * u.deg, site.latitude_deg * u.deg, site.elevation_m * u.m
    )
    frame = AltAz(
        obstime=t,
        location=location,
        pressure=(site.effective_pressure_hpa if refraction else 0.0) * u.hPa,
        temperature=site.temperature_c * u.deg_C,
        relative_humidity=site.relative_humidity,
        obswl=site.wavelength_um * u.micron,
    )
    return SkyCoord(ra=ra * u.hourangle, dec=dec * u.deg, frame="icrs").transform_to(frame)


@pytest.mark.parametrize("site", SITES)
@pytest.mark.parametrize("iso", TIMES)
def test_observed_without_refraction_matches_astropy(
    site: Site, iso: str, positions: tuple[np.ndarray, np.ndarray]
) -> None:
    t = astropy_time(iso)
    ra, dec = positions
    theirs = astropy_altaz(site, t, ra, dec, refraction=False)
    alt, az = j2000_to_observed(
        ra, dec, t, site.without_refraction(), ut1_minus_utc_s=float(t.delta_ut1_utc)
    )
    errors = separation_arcsec(az, alt, theirs.az.deg, theirs.alt.deg)
    assert errors.max() < 1.0


@pytest.mark.parametrize("site", SITES)
def test_observed_with_refraction_matches_astropy_above_10_degrees(
    site: Site, positions: tuple[np.ndarray, np.ndarray]
) -> None:
    t = astropy_time(TIMES[1])
    ra, dec = positions
    theirs = astropy_altaz(site, t, ra, dec, refraction=True)
    alt, az = j2000_to_observed(ra, dec, t, site, ut1_minus_utc_s=float(t.delta_ut1_utc))
    high = np.asarray(alt) > 10.0
    assert high.sum() > 20
    errors = separation_arcsec(
        np.asarray(az)[high], np.asarray(alt)[high], theirs.az.deg[high], theirs.alt.deg[high]
    )
    assert errors.max() < 1.0
