"""J2000 <-> of-date: ERFA's published example, Meeus' worked example, round trips."""

from __future__ import annotations

import math
from datetime import UTC, datetime
from typing import Any

import erfa
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.astro import one_position
from scopelink.astro.frames import (
    apparent_to_j2000,
    j2000_to_apparent,
    j2000_to_mean_of_date,
    mean_of_date_to_j2000,
)
from scopelink.astro.timescales import JulianDate

ARCSEC = 1 / 3600


def separation_arcsec(ra1: Any, dec1: Any, ra2: Any, dec2: Any) -> float:
    return float(
        np.degrees(
            erfa.seps(
                math.radians(ra1 * 15),
                math.radians(dec1),
                math.radians(ra2 * 15),
                math.radians(dec2),
            )
        )
        * 3600
    )


def test_erfa_atic13_example() -> None:
    # SOFA/ERFA t_atic13: CIRS (2.710121572969038991, 0.1729371367218230438) rad at
    # TDB 2456165.5 + 0.401182685 -> ICRS (2.710126504531716819, 0.1740632537627034482).
    # Our input is equinox-based, RA = RA_CIRS - EO; TT stands in for TDB (< 2 ms apart).
    tt = JulianDate(2456165.5, 0.401182685, "tt")
    eo = -0.002900618712657375647
    ra_hours = (2.710121572969038991 - eo) * 12 / math.pi
    ra, dec = apparent_to_j2000(ra_hours, math.degrees(0.1729371367218230438), tt)
    assert ra * math.pi / 12 == pytest.approx(2.710126504531716819, abs=1e-11)
    assert math.radians(dec) == pytest.approx(0.1740632537627034482, abs=1e-11)


def test_meeus_23a_theta_persei() -> None:
    # Meeus, Astronomical Algorithms, ex. 23.a (and 21.b): θ Persei on 2028 Nov 13.19 TD.
    # The proper motion over the 28.87 years is applied here, since we take positions at date.
    years = (2462088.69 - 2451545.0) / 365.25
    ra0 = 2 + 44 / 60 + (11.986 + 0.03425 * years) / 3600
    dec0 = 49 + 13 / 60 + (42.48 - 0.0895 * years) / 3600
    date = JulianDate(2462088.69, 0.0, "tt")
    mean_ra, mean_dec = j2000_to_mean_of_date(ra0, dec0, date)
    meeus_mean = (2 + 46 / 60 + 11.331 / 3600, 49 + 20 / 60 + 54.54 / 3600)
    assert separation_arcsec(mean_ra, mean_dec, *meeus_mean) < 0.1
    apparent_ra, apparent_dec = j2000_to_apparent(ra0, dec0, date)
    meeus_apparent = (2 + 46 / 60 + 14.390 / 3600, 49 + 21 / 60 + 7.45 / 3600)
    assert separation_arcsec(apparent_ra, apparent_dec, *meeus_apparent) < 0.1


def test_of_date_differs_from_j2000_by_precession() -> None:
    # Precession in RA on the equator at 6 h is m = 3.075 s/yr = 46.1"/yr (Meeus eq. 21.1).
    moment = datetime(2024, 1, 1, tzinfo=UTC)
    ra, _ = j2000_to_apparent(6.0, 0.0, moment)
    assert (ra - 6.0) * 15 * 3600 == pytest.approx(46.1 * 24, rel=0.05)
    assert 0 <= ra < 24


ra_hours = st.floats(min_value=0, max_value=24, exclude_max=True)
dec_deg = st.floats(min_value=-89.9, max_value=89.9)
years = st.floats(min_value=1950, max_value=2060)


def at_year(year: float) -> JulianDate:
    return JulianDate(2451545.0, (year - 2000.0) * 365.25, "tt")


@given(ra_hours, dec_deg, years)
@settings(max_examples=200, deadline=None)
def test_apparent_round_trip(ra: float, dec: float, year: float) -> None:
    t = at_year(year)
    back = apparent_to_j2000(*j2000_to_apparent(ra, dec, t), t)
    assert separation_arcsec(ra, dec, *back) < 0.01
    forth = j2000_to_apparent(*apparent_to_j2000(ra, dec, t), t)
    assert separation_arcsec(ra, dec, *forth) < 0.01


@given(ra_hours, st.floats(min_value=-90, max_value=90), years)
@settings(max_examples=200, deadline=None)
def test_mean_of_date_round_trip(ra: float, dec: float, year: float) -> None:
    t = at_year(year)
    back = mean_of_date_to_j2000(*j2000_to_mean_of_date(ra, dec, t), t)
    assert separation_arcsec(ra, dec, *back) < 1e-6


def test_vectorised_matches_scalar() -> None:
    rng = np.random.default_rng(7)
    ras = rng.uniform(0, 24, 20)
    decs = rng.uniform(-89, 89, 20)
    moment = datetime(2025, 9, 1, 21, tzinfo=UTC)
    # One float position reuses its context for 10 s (< 0.1 mas): a fresh one here, so the two
    # paths share the instant of their context and agree to the last bits.
    vars(one_position)["_last_geocentric"] = None
    many_ra, many_dec = j2000_to_apparent(ras, decs, moment)
    assert isinstance(many_ra, np.ndarray)
    assert isinstance(many_dec, np.ndarray)
    for i in range(20):
        one_ra, one_dec = j2000_to_apparent(float(ras[i]), float(decs[i]), moment)
        assert isinstance(one_ra, float)
        assert one_ra == pytest.approx(many_ra[i], abs=1e-12)
        assert one_dec == pytest.approx(many_dec[i], abs=1e-12)


def test_vectorised_over_times() -> None:
    jd2 = np.linspace(0, 1825, 5)
    ra, _ = j2000_to_apparent(5.0, 20.0, JulianDate(np.full(5, 2460000.5), jd2, "utc"))
    assert isinstance(ra, np.ndarray)
    assert ra.shape == (5,)
    for i in range(5):
        single = j2000_to_apparent(5.0, 20.0, (2460000.5, float(jd2[i])))
        assert single[0] == pytest.approx(ra[i], abs=1e-12)
