"""Sidereal time against ERFA's published examples and Meeus' worked examples."""

from __future__ import annotations

import math
from datetime import UTC, datetime

import numpy as np
import pytest

from scopelink.astro.sidereal import gast_hours, gmst_hours, lst_hours
from scopelink.astro.timescales import JulianDate

RADIANS_TO_HOURS = 12 / math.pi


def hms(h: int, m: int, s: float) -> float:
    return h + m / 60 + s / 3600


def test_erfa_gmst06_example() -> None:
    # t_gmst06: UT1 = TT = MJD 53736.0 -> 1.754174971870091203 rad. Our TT follows from UTC
    # (64 s later), which moves GMST by < 1e-9 rad through the TT-dependent terms.
    gmst = gmst_hours((2400000.5, 53736.0))
    assert gmst == pytest.approx(1.754174971870091203 * RADIANS_TO_HOURS, abs=1e-8)


def test_erfa_gst06a_example() -> None:
    gast = gast_hours((2400000.5, 53736.0))
    assert gast == pytest.approx(1.754166137675019159 * RADIANS_TO_HOURS, abs=1e-8)


def test_meeus_12a_gmst_at_0h() -> None:
    # Meeus, Astronomical Algorithms, ex. 12.a: 1987 April 10, 0h UT -> 13h10m46.3668s (IAU 1982).
    # IAU 2006 GMST differs from the 1982 formula by 3.3 ms at this date.
    gmst = gmst_hours(datetime(1987, 4, 10, tzinfo=UTC))
    assert gmst == pytest.approx(hms(13, 10, 46.3668), abs=0.005 / 3600)


def test_meeus_12b_mean_and_apparent() -> None:
    # Meeus ex. 12.b: 1987 April 10, 19:21:00 UT -> mean 8h34m57.0896s, apparent 8h34m56.853s.
    moment = datetime(1987, 4, 10, 19, 21, tzinfo=UTC)
    assert gmst_hours(moment) == pytest.approx(hms(8, 34, 57.0896), abs=0.005 / 3600)
    assert gast_hours(moment) == pytest.approx(hms(8, 34, 56.853), abs=0.005 / 3600)


def test_ut1_offset_advances_sidereal_time() -> None:
    moment = datetime(2024, 1, 1, tzinfo=UTC)
    shift = gmst_hours(moment, ut1_minus_utc_s=0.5) - gmst_hours(moment)
    assert shift * 3600 == pytest.approx(0.5 * 1.00273781191135448, abs=1e-6)


def test_local_sidereal_time_is_east_positive_and_wrapped() -> None:
    moment = datetime(2024, 3, 20, 22, 0, tzinfo=UTC)
    greenwich = gast_hours(moment)
    east = lst_hours(moment, 90.0)
    west = lst_hours(moment, -90.0)
    assert (east - greenwich) % 24 == pytest.approx(6.0, abs=1e-9)
    assert (greenwich - west) % 24 == pytest.approx(6.0, abs=1e-9)
    mean = lst_hours(moment, 0.0, apparent=False)
    assert mean == pytest.approx(gmst_hours(moment), abs=1e-12)
    values = lst_hours(moment, np.linspace(-180, 180, 361))
    assert isinstance(values, np.ndarray)
    assert np.all((values >= 0) & (values < 24))


def test_vectorised_times_match_scalar_path() -> None:
    jd2 = np.linspace(0.0, 1.0, 7)
    jd1 = np.full_like(jd2, 2460000.5)
    many = gast_hours(JulianDate(jd1, jd2, "utc"))
    assert isinstance(many, np.ndarray)
    singles = [gast_hours((2460000.5, float(f))) for f in jd2]
    np.testing.assert_allclose(many, singles, rtol=0, atol=1e-12)
