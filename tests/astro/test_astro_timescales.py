"""Time scales: inputs accepted, leap seconds, TT and UT1, against ERFA's published examples."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta, timezone
from typing import Any

import numpy as np
import pytest

from scopelink.astro.timescales import (
    JulianDate,
    now,
    tai_jd,
    tai_minus_utc_s,
    tt_jd,
    ut1_jd,
    utc_jd,
)

SECOND_IN_DAYS = 1 / 86400


def seconds_between(a: tuple[Any, Any], b: tuple[Any, Any]) -> float:
    return float(((a[0] - b[0]) + (a[1] - b[1])) * 86400)


def test_naive_datetime_is_refused_with_advice() -> None:
    with pytest.raises(ValueError, match=r"naive datetime .* tzinfo"):
        utc_jd(datetime(2020, 1, 1, 12))


def test_aware_datetime_in_any_zone_is_the_same_instant() -> None:
    utc = datetime(2020, 3, 1, 12, 30, tzinfo=UTC)
    tokyo = utc.astimezone(timezone(timedelta(hours=9)))
    assert seconds_between(utc_jd(utc), utc_jd(tokyo)) == pytest.approx(0, abs=1e-6)
    jd1, jd2 = utc_jd(utc)
    assert jd1 + jd2 == pytest.approx(2458910.0208333335, abs=1e-9)


def test_erfa_example_utc_to_tai() -> None:
    # SOFA/ERFA t_utctai: 2006-01-15 21:24:37.5 UTC.
    tai1, tai2 = tai_jd((2453750.5, 0.892100694))
    assert tai1 + tai2 == pytest.approx(2453750.5 + 0.8924826384444444444, abs=1e-12)


def test_erfa_example_utc_to_ut1() -> None:
    # SOFA/ERFA t_utcut1 with DUT1 = 0.3341 s.
    ut11, ut12 = ut1_jd((2453750.5, 0.892100694), 0.3341)
    assert ut11 + ut12 == pytest.approx(2453750.5 + 0.8921045608981481481, abs=1e-12)


def test_leap_second_at_2017() -> None:
    before = datetime(2016, 12, 31, 23, 59, 59, tzinfo=UTC)
    after = datetime(2017, 1, 1, tzinfo=UTC)
    assert tai_minus_utc_s(before) == 36.0
    assert tai_minus_utc_s(after) == 37.0
    # Two UTC labels one second apart are two SI seconds apart in TT: the leap second.
    assert seconds_between(tt_jd(after), tt_jd(before)) == pytest.approx(2.0, abs=1e-5)


def test_tt_is_tai_plus_32_184() -> None:
    moment = datetime(2024, 6, 1, tzinfo=UTC)
    assert seconds_between(tt_jd(moment), utc_jd(moment)) == pytest.approx(69.184, abs=1e-5)


@pytest.mark.parametrize("dut1", [-0.9, -0.2, 0.0, 0.5, 0.9])
def test_ut1_offset_is_applied(dut1: float) -> None:
    moment = datetime(2024, 6, 1, tzinfo=UTC)
    assert seconds_between(ut1_jd(moment, dut1), utc_jd(moment)) == pytest.approx(dut1, abs=1e-5)


@pytest.mark.parametrize("dut1", [1.0, -37.0, float("nan")])
def test_impossible_ut1_offset_is_refused(dut1: float) -> None:
    with pytest.raises(ValueError, match="UT1-UTC"):
        ut1_jd(datetime(2024, 6, 1, tzinfo=UTC), dut1)


def test_julian_date_in_tt_and_tai_scales() -> None:
    moment = datetime(2021, 5, 5, 5, 5, 5, tzinfo=UTC)
    tt1, tt2 = tt_jd(moment)
    tai1, tai2 = tai_jd(moment)
    for other in (JulianDate(tt1, tt2, "tt"), JulianDate(tai1, tai2, "tai")):
        assert seconds_between(utc_jd(other), utc_jd(moment)) == pytest.approx(0, abs=1e-6)
    with pytest.raises(ValueError, match="scale"):
        JulianDate(2451545.0, 0.0, "tdb")


def test_astropy_time_is_accepted_in_any_scale() -> None:
    from astropy.time import Time

    moment = datetime(2019, 7, 1, 3, 4, 5, tzinfo=UTC)
    reference = utc_jd(moment)
    for scale in ("utc", "tai", "tt", "tdb", "tcg"):
        t = getattr(Time(moment), scale)
        assert seconds_between(utc_jd(t), reference) == pytest.approx(0, abs=1e-5), scale


def test_to_datetime_duck_is_accepted_and_naive_result_refused() -> None:
    class Stamp:
        def __init__(self, value: datetime) -> None:
            self.value = value

        def to_datetime(self) -> datetime:
            return self.value

    aware = datetime(2022, 2, 2, tzinfo=UTC)
    assert utc_jd(Stamp(aware)) == utc_jd(aware)
    with pytest.raises(ValueError, match="naive"):
        utc_jd(Stamp(aware.replace(tzinfo=None)))


@pytest.mark.parametrize("bad", ["2020-01-01", 2451545.0, (1.0, 2.0, 3.0), None])
def test_unreadable_times_raise_type_error(bad: object) -> None:
    with pytest.raises(TypeError, match=r"time|jd1"):
        utc_jd(bad)  # type: ignore[call-overload]


def test_arrays_of_instants_match_single_instants() -> None:
    jd1 = np.full(4, 2459000.5)
    jd2 = np.array([0.0, 0.25, 0.5, 0.75])
    tt1, tt2 = tt_jd((jd1, jd2))
    assert isinstance(tt1, np.ndarray)
    assert isinstance(tt2, np.ndarray)
    assert tt1.shape == (4,)
    for i in range(4):
        single = tt_jd((float(jd1[i]), float(jd2[i])))
        assert isinstance(single[0], float)
        assert seconds_between((tt1[i], tt2[i]), single) == pytest.approx(0, abs=1e-6)


def test_now_is_aware_utc() -> None:
    current = now()
    assert current.tzinfo is not None
    assert current.utcoffset() == timedelta(0)
