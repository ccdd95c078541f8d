"""Rise, transit and set: published almanac values, and astropy (offline) at the found instants."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta
from typing import Any

import pytest

from scopelink.astro import Site, j2000_to_observed
from scopelink.astro.catalog import (
    STANDARD_HORIZON_DEG,
    SUN_MOON_HORIZON_DEG,
    is_up,
    lookup,
    rise_transit_set,
)

WASHINGTON = Site(38.8894, -77.0352, 10.0)
BOSTON = Site(42.3333, -71.0833)
SOLSTICE_2024 = datetime(2024, 6, 21, 4, 0, tzinfo=UTC)  # local midnight, EDT = UTC - 4 h
MINUTE = timedelta(minutes=1)


def astropy_airless_altitude(body: str, site: Site, when: datetime) -> float:
    from astropy.coordinates import AltAz, EarthLocation, get_body, solar_system_ephemeris
    from astropy.time import Time

    location = EarthLocation.from_geodetic(site.longitude_deg, site.latitude_deg, site.elevation_m)
    moment = Time(when)
    with solar_system_ephemeris.set("builtin"):
        coordinate = get_body(body, moment, location=location)
    horizontal: Any = coordinate.transform_to(AltAz(obstime=moment, location=location, pressure=0))
    return float(horizontal.alt.deg)


def astropy_hour_angle_hours(body: str, site: Site, when: datetime) -> float:
    from astropy.coordinates import TETE, EarthLocation, get_body, solar_system_ephemeris
    from astropy.time import Time

    location = EarthLocation.from_geodetic(site.longitude_deg, site.latitude_deg, site.elevation_m)
    moment = Time(when)
    with solar_system_ephemeris.set("builtin"):
        coordinate = get_body(body, moment, location=location)
    apparent: Any = coordinate.transform_to(TETE(obstime=moment, location=location))
    sidereal = moment.sidereal_time("apparent", longitude=site.longitude_deg)
    return (float(sidereal.hour) - float(apparent.ra.hour) + 12.0) % 24.0 - 12.0


def test_sun_at_washington_on_the_2024_solstice_matches_usno() -> None:
    # USNO "Sun and Moon data for one day", Washington DC, 2024-06-21 (EDT):
    # rise 05:43, transit 13:10, set 20:37.
    events = rise_transit_set("Sun", WASHINGTON, SOLSTICE_2024)
    edt = timedelta(hours=-4)
    assert events.rise is not None
    assert events.transit is not None
    assert events.set is not None
    expected = [(5, 43), (13, 10), (20, 37)]
    for found, (hour, minute) in zip(
        [events.rise, events.transit, events.set], expected, strict=True
    ):
        local = found + edt
        published = local.replace(hour=hour, minute=minute, second=30, microsecond=0)
        assert abs(local - published) <= 1.5 * MINUTE  # USNO rounds to the minute
    assert not events.always_up
    assert not events.never_up


def test_venus_at_boston_matches_meeus_example_15a() -> None:
    # Meeus, Astronomical Algorithms, example 15.a: 1988 March 20, h0 = -0°34'.
    events = rise_transit_set("Venus", BOSTON, datetime(1988, 3, 20, tzinfo=UTC))
    day = datetime(1988, 3, 20, tzinfo=UTC)
    for found, expected in [
        (events.rise, day + timedelta(hours=12, minutes=25)),
        (events.transit, day + timedelta(hours=19, minutes=41)),
        (events.set, day + timedelta(hours=2, minutes=55)),
    ]:
        assert found is not None
        assert abs(found - expected) <= 1.5 * MINUTE  # Meeus quotes minutes


@pytest.mark.parametrize("body", ["Sun", "Moon"])
def test_astropy_puts_the_upper_limb_on_the_horizon_at_our_rise_and_set(body: str) -> None:
    events = rise_transit_set(body, WASHINGTON, SOLSTICE_2024, window_hours=30)
    for event in (events.rise, events.set):
        assert event is not None
        altitude = astropy_airless_altitude(body.lower(), WASHINGTON, event)
        assert altitude == pytest.approx(SUN_MOON_HORIZON_DEG, abs=0.02)  # 0.02° ≈ 5 s of time


@pytest.mark.parametrize("body", ["Sun", "Moon"])
def test_astropy_puts_the_meridian_at_our_transit(body: str) -> None:
    events = rise_transit_set(body, WASHINGTON, SOLSTICE_2024)
    assert events.transit is not None
    hour_angle = astropy_hour_angle_hours(body.lower(), WASHINGTON, events.transit)
    assert hour_angle == pytest.approx(0.0, abs=2.0 / 3600.0)


def test_a_star_rises_when_its_airless_altitude_is_minus_34_arcmin() -> None:
    events = rise_transit_set("Sirius", WASHINGTON, SOLSTICE_2024)
    assert events.rise is not None
    assert events.set is not None
    airless = WASHINGTON.without_refraction()
    for event in (events.rise, events.set):
        sirius = lookup("Sirius", event)
        altitude, _ = j2000_to_observed(sirius.ra_hours, sirius.dec_deg, event, airless)
        assert altitude == pytest.approx(STANDARD_HORIZON_DEG, abs=0.005)


def test_a_configured_horizon_is_an_observed_altitude() -> None:
    default = rise_transit_set("Vega", WASHINGTON, SOLSTICE_2024)
    above_trees = rise_transit_set("Vega", WASHINGTON, SOLSTICE_2024, horizon_deg=15.0)
    assert default.rise is not None
    assert default.set is not None
    assert above_trees.rise is not None
    assert above_trees.set is not None
    assert above_trees.rise > default.rise
    assert above_trees.set < default.set
    assert above_trees.transit == default.transit
    vega = lookup("Vega", above_trees.rise)
    altitude, _ = j2000_to_observed(vega.ra_hours, vega.dec_deg, above_trees.rise, WASHINGTON)
    assert altitude == pytest.approx(15.0, abs=0.005)


def test_circumpolar_and_never_rising_stars() -> None:
    oslo = Site(59.91, 10.75)
    polaris = rise_transit_set("Polaris", oslo, SOLSTICE_2024)
    assert (polaris.rise, polaris.set, polaris.always_up, polaris.never_up) == (
        None, None, True, False,
    )  # fmt: skip
    assert polaris.transit is not None
    canopus = rise_transit_set("Canopus", oslo, SOLSTICE_2024)
    assert (canopus.rise, canopus.set, canopus.always_up, canopus.never_up) == (
        None, None, False, True,
    )  # fmt: skip
    assert canopus.transit is not None  # it still crosses the meridian, below the horizon


def test_fixed_coordinates_and_window() -> None:
    # On the equator a point on the celestial equator is up for half a sidereal day plus the
    # 2 x 34' of refraction: rise to transit is 6 h 02 m of sidereal time, 6 h 01 m of clock time.
    equator = Site(0.0, 0.0)
    day = datetime(2024, 3, 20, tzinfo=UTC)
    events = rise_transit_set((6.0, 0.0), equator, day)
    assert events.set is not None
    assert events.rise is not None
    assert events.transit is not None
    assert events.set < events.rise < events.transit  # first of each after the start
    rise_to_transit = events.transit - events.rise
    assert rise_to_transit == pytest.approx(timedelta(hours=6, minutes=1), abs=MINUTE)
    between = rise_transit_set((6.0, 0.0), equator, events.set + MINUTE, window_hours=6)
    assert (between.rise, between.transit, between.set) == (None, None, None)
    assert between.never_up


def test_is_up_agrees_with_rise_and_set() -> None:
    events = rise_transit_set("Sun", WASHINGTON, SOLSTICE_2024)
    assert events.rise is not None
    assert events.set is not None
    assert not is_up("Sun", WASHINGTON, events.rise - MINUTE)
    assert is_up("Sun", WASHINGTON, events.rise + MINUTE)
    assert is_up("Sun", WASHINGTON, events.set - MINUTE)
    assert not is_up("Sun", WASHINGTON, events.set + MINUTE)
    assert not is_up("Sun", WASHINGTON, events.rise + MINUTE, horizon_deg=10.0)
