"""Equatorial <-> horizontal: ERFA's published examples, round trips, vectorisation, speed."""

from __future__ import annotations

import math
import time
from datetime import UTC, datetime

import erfa
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.astro.horizontal import (
    altaz_to_hadec,
    apparent_to_observed,
    hadec_to_altaz,
    j2000_to_observed,
    observed_to_apparent,
    observed_to_j2000,
)
from scopelink.astro.site import Site

# The SOFA/ERFA t_atoc13 / t_atco13 observer: 2013-04-02 23:15:43.55 UTC, DUT1 0.1550675 s.
ERFA_SITE = Site(
    latitude_deg=math.degrees(-1.2345856),
    longitude_deg=math.degrees(-0.527800806),
    elevation_m=2738.0,
    pressure_hpa=731.0,
    temperature_c=12.8,
    relative_humidity=0.59,
    wavelength_um=0.55,
)
ERFA_UTC = (2456384.5, 0.969254051)
ERFA_DUT1 = 0.1550675
# Polar motion (0.05", 0.38" in the example) is neglected: allow 0.5".
POLAR_MOTION_ARCSEC = 0.5


def sep_arcsec(lon1: float, lat1: float, lon2: float, lat2: float) -> float:
    radians = erfa.seps(*(math.radians(x) for x in (lon1, lat1, lon2, lat2)))
    return float(math.degrees(radians) * 3600)


def test_erfa_atoc13_example_observed_to_j2000() -> None:
    azimuth, zenith_distance = 0.09233952224794989993, 1.407758704513722461
    ra, dec = observed_to_j2000(
        90 - math.degrees(zenith_distance),
        math.degrees(azimuth),
        ERFA_UTC,
        ERFA_SITE,
        ut1_minus_utc_s=ERFA_DUT1,
    )
    expected = (math.degrees(2.709956744659734086), math.degrees(0.1741696500898471366))
    assert sep_arcsec(ra * 15, dec, *expected) < POLAR_MOTION_ARCSEC


def test_erfa_atoc13_example_j2000_to_observed() -> None:
    alt, az = j2000_to_observed(
        2.709956744659734086 * 12 / math.pi,
        math.degrees(0.1741696500898471366),
        ERFA_UTC,
        ERFA_SITE,
        ut1_minus_utc_s=ERFA_DUT1,
    )
    expected = (math.degrees(0.09233952224794989993), 90 - math.degrees(1.407758704513722461))
    assert sep_arcsec(az, alt, *expected) < POLAR_MOTION_ARCSEC


def test_erfa_atoi13_example_observed_to_apparent() -> None:
    # t_atoi13 "A": the same observed direction -> CIRS
    # (2.710121574448138676, 0.1729371839116608781) rad. With EO = -0.003020548354802412839 rad
    # (t_atco13) the equinox-based RA is RA_CIRS - EO.
    azimuth, zenith_distance = 0.09233952224794989993, 1.407758704513722461
    ra, dec = observed_to_apparent(
        90 - math.degrees(zenith_distance),
        math.degrees(azimuth),
        ERFA_UTC,
        ERFA_SITE,
        ut1_minus_utc_s=ERFA_DUT1,
    )
    eo = -0.003020548354802412839
    expected = (math.degrees(2.710121574448138676 - eo), math.degrees(0.1729371839116608781))
    assert sep_arcsec(ra * 15, dec, *expected) < POLAR_MOTION_ARCSEC


def test_erfa_hd2ae_and_ae2hd_examples() -> None:
    alt, az = hadec_to_altaz(1.1 * 12 / math.pi, math.degrees(1.2), math.degrees(0.3))
    assert az == pytest.approx(math.degrees(5.916889243730066194), abs=1e-11)
    assert alt == pytest.approx(math.degrees(0.4472186304990486228), abs=1e-11)
    ha, dec = altaz_to_hadec(math.degrees(1.1), math.degrees(5.5), math.degrees(0.7))
    assert ha == pytest.approx(0.5933291115507309663 * 12 / math.pi, abs=1e-11)
    assert dec == pytest.approx(math.degrees(0.9613934761647817620), abs=1e-11)


def test_azimuth_convention_north_zero_east_ninety() -> None:
    # From latitude +40: the pole is due north at altitude 40; HA -6 h on the equator is due east.
    alt, az = hadec_to_altaz(0.0, 90.0, 40.0)
    assert (alt, az % 360) == pytest.approx((40.0, 0.0), abs=1e-9)
    alt, az = hadec_to_altaz(-6.0, 0.0, 40.0)
    assert (alt, az) == pytest.approx((0.0, 90.0), abs=1e-9)
    alt, az = hadec_to_altaz(0.0, 0.0, 40.0)
    assert (alt, az) == pytest.approx((50.0, 180.0), abs=1e-9)


def test_refraction_lifts_observed_altitude() -> None:
    moment = datetime(2024, 8, 1, 22, tzinfo=UTC)
    site = Site(48.0, 11.0, 500.0)
    refracted = j2000_to_observed(18.6, 38.8, moment, site)
    geometric = j2000_to_observed(18.6, 38.8, moment, site.without_refraction())
    assert refracted[1] == pytest.approx(geometric[1], abs=1e-9)
    assert 0 < (refracted[0] - geometric[0]) * 3600 < 120


sites = st.builds(
    Site,
    latitude_deg=st.floats(min_value=-89, max_value=89),
    longitude_deg=st.floats(min_value=-180, max_value=180),
    elevation_m=st.floats(min_value=0, max_value=4000),
    pressure_hpa=st.one_of(st.none(), st.just(0.0)),
)
times = st.floats(min_value=0, max_value=20 * 365.25).map(lambda days: (2451545.0, days))


@given(
    st.floats(min_value=0, max_value=24, exclude_max=True),
    st.floats(min_value=-89, max_value=89),
    times,
    sites,
)
@settings(max_examples=150, deadline=None)
def test_j2000_observed_round_trip(
    ra: float, dec: float, t: tuple[float, float], site: Site
) -> None:
    alt, az = j2000_to_observed(ra, dec, t, site)
    back = observed_to_j2000(alt, az, t, site)
    assert sep_arcsec(ra * 15, dec, back[0] * 15, back[1]) < 0.01


@given(
    st.floats(min_value=0, max_value=360, exclude_max=True),
    st.floats(min_value=-1, max_value=89),
    times,
    sites,
)
@settings(max_examples=150, deadline=None)
def test_observed_apparent_round_trip(
    az: float, alt: float, t: tuple[float, float], site: Site
) -> None:
    ra, dec = observed_to_apparent(alt, az, t, site)
    back_alt, back_az = apparent_to_observed(ra, dec, t, site)
    assert sep_arcsec(az, alt, back_az, back_alt) < 0.01


@given(
    st.floats(min_value=-12, max_value=12, exclude_max=True),
    st.floats(min_value=-89, max_value=89),
    st.floats(min_value=-89, max_value=89),
)
@settings(max_examples=300, deadline=None)
def test_hadec_altaz_round_trip(ha: float, dec: float, latitude: float) -> None:
    alt, az = hadec_to_altaz(ha, dec, latitude)
    back_ha, back_dec = altaz_to_hadec(alt, az, latitude)
    assert -12 <= back_ha < 12
    assert sep_arcsec(ha * 15, dec, back_ha * 15, back_dec) < 0.01


def test_vectorised_matches_scalar() -> None:
    rng = np.random.default_rng(3)
    ras, decs = rng.uniform(0, 24, 15), rng.uniform(-60, 89, 15)
    moment = datetime(2025, 1, 10, 3, tzinfo=UTC)
    site = Site(-33.9, 18.4, 50.0)
    many_alt, many_az = j2000_to_observed(ras, decs, moment, site)
    assert isinstance(many_alt, np.ndarray)
    assert isinstance(many_az, np.ndarray)
    for i in range(15):
        alt, az = j2000_to_observed(float(ras[i]), float(decs[i]), moment, site)
        assert isinstance(alt, float)
        # One float position takes ERFA's CIRS route (astro.one_position: 0.2 mas from the
        # array path's, whose 0-d inputs match it to 1e-10 degrees).
        assert (alt, az) == pytest.approx((many_alt[i], many_az[i]), abs=1e-3 / 3600)
        zero_d = j2000_to_observed(np.asarray(ras[i]), np.asarray(decs[i]), moment, site)
        assert zero_d == pytest.approx((many_alt[i], many_az[i]), abs=1e-10)


def test_ten_thousand_positions_in_one_fast_call() -> None:
    rng = np.random.default_rng(11)
    ras = rng.uniform(0, 24, 10_000)
    decs = np.degrees(np.arcsin(rng.uniform(-1, 1, 10_000)))
    site = Site(52.0, 5.0, 10.0)
    moment = datetime(2026, 2, 1, 20, tzinfo=UTC)
    started = time.perf_counter()
    alt, az = j2000_to_observed(ras, decs, moment, site)
    ra, dec = observed_to_j2000(alt, az, moment, site)
    elapsed = time.perf_counter() - started
    assert np.asarray(alt).shape == (10_000,)
    # ~40 ms on the 2-core CI machine; a Python loop per position would take seconds.
    assert elapsed < 1.0
    errors = np.degrees(
        erfa.seps(
            np.radians(ras * 15), np.radians(decs), np.radians(np.asarray(ra) * 15), np.radians(dec)
        )
    )
    assert np.max(errors) * 3600 < 0.01
