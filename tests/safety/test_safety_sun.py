"""Sun avoidance on the Mount API (issue #11 part 3): the simulator on a fixed clock.

At 2026-06-21 12:00 UTC from 51.5° N, 0° E the Sun stands at altitude 62.0°, azimuth 179.1°
(DE421; checked below), so every case knows where the zone is.
"""

from __future__ import annotations

import math
from datetime import UTC, datetime

import pytest

from scopelink.astro import Site, angular_separation_deg, hadec_to_altaz
from scopelink.mount import (
    InvalidValueError,
    LimitError,
    Limits,
    MountAxis,
    ParkPosition,
    TrackingMode,
)
from scopelink.mount.sun import SunZone
from scopelink.mount.types import AlignmentMode
from scopelink.sim import AZ_GTI, EQ6, MountModel, SimClock, SimulatedMount

SITE = Site(51.5, 0.0)
NOON = datetime(2026, 6, 21, 12, 0, tzinfo=UTC)
SUN_ALT, SUN_AZ = 62.0, 179.1


async def simulated(
    model: MountModel = EQ6,
    *,
    radius: float = 15.0,
    at: tuple[float, float] | None = None,
    when: datetime = NOON,
) -> SimulatedMount:
    """A connected simulator at noon, tracking off, pointing at ``at`` (alt, az) if given."""
    clock = SimClock.stepped(when)
    mount = SimulatedMount(
        model, site=SITE, clock=clock, limits=Limits(horizon_deg=0.0, sun_avoidance_deg=radius)
    )
    await mount.connect()
    if at is not None:
        with_zone_off = mount.limits
        mount.limits = Limits(horizon_deg=0.0, sun_avoidance_deg=0.0)
        await mount.goto_horizontal(*at)
        clock.advance(60.0)  # a full-sky slew at 3.34°/s
        mount.limits = with_zone_off
    return mount


def test_the_sun_is_where_the_tests_say() -> None:
    zone = SunZone(15.0, SITE, NOON, AlignmentMode.ALT_AZ)
    assert zone.alt_deg == pytest.approx(SUN_ALT, abs=0.1)
    assert zone.az_deg == pytest.approx(SUN_AZ, abs=0.1)


async def test_goto_sun_is_refused_and_nothing_moves() -> None:
    """The reproduction: on the code before this change ``goto_object("Sun")`` slewed."""
    mount = await simulated()
    before = mount.state
    with pytest.raises(LimitError, match=r"Sun avoidance zone \(limits.sun_avoidance_deg\)"):
        await mount.goto_object("Sun")
    mount.clock.advance(120.0)
    after = await mount.refresh()
    assert mount.target is None
    assert (after.alt_deg, after.az_deg) == pytest.approx((before.alt_deg, before.az_deg))


@pytest.mark.parametrize(("alt", "az"), [(60.0, 175.0), (50.0, 180.0), (70.0, 200.0)])
async def test_horizontal_target_inside_the_zone_is_refused(alt: float, az: float) -> None:
    mount = await simulated(AZ_GTI)
    with pytest.raises(LimitError, match=r"from the Sun, inside the 15° Sun avoidance zone"):
        await mount.goto_horizontal(alt, az)


async def test_equatorial_target_just_outside_the_zone_is_accepted() -> None:
    mount = await simulated(at=(30.0, 90.0))
    # 16° above the Sun, reached from the east without passing it.
    alt, az = 78.0, 179.1
    assert angular_separation_deg(az, alt, SUN_AZ, SUN_ALT) > 15.5
    await mount.goto_horizontal(alt, az)


async def test_alt_az_slew_sweeping_through_the_sun_is_refused_with_a_waypoint() -> None:
    """Both ends 30° from the Sun at its altitude: the short way round passes through it."""
    mount = await simulated(AZ_GTI, at=(SUN_ALT, 140.0))
    with pytest.raises(LimitError) as refused:
        await mount.goto_horizontal(SUN_ALT, 220.0)
    message = str(refused.value)
    assert "would pass" in message
    assert "from the Sun" in message
    assert "first, then to the target" in message
    numbers = message.split("(goto altitude ")[1].split("° azimuth ")
    waypoint = (float(numbers[0]), float(numbers[1].split("°")[0]))
    # The advice works: both legs are accepted.
    await mount.goto_horizontal(*waypoint)
    mount.clock.advance(60.0)
    await mount.refresh()
    await mount.goto_horizontal(SUN_ALT, 220.0)


async def test_equatorial_slew_sweeping_through_the_sun_is_refused() -> None:
    """EQ6 at 09:00 UTC (the Sun 3 h east of the meridian), at the Sun's declination from 5 h
    east to 1 h east: no flip, the polar axis alone turns, through the Sun. Across the meridian
    the flip takes the tube over the pole instead, clear of the Sun."""
    morning = datetime(2026, 6, 21, 9, 0, tzinfo=UTC)
    start = hadec_to_altaz(-5.0, 23.4, SITE.latitude_deg)
    mount = await simulated(at=start, when=morning)
    with pytest.raises(LimitError, match="would pass"):
        await mount.goto_horizontal(*hadec_to_altaz(-1.0, 23.4, SITE.latitude_deg))
    await mount.goto_horizontal(*hadec_to_altaz(3.0, 23.4, SITE.latitude_deg))


async def test_the_zone_off_lets_the_sun_be_reached() -> None:
    mount = await simulated(radius=0.0)
    await mount.goto_object("Sun")
    assert mount.target is not None
    assert mount.target.name == "Sun"


async def test_sync_inside_the_zone_is_refused() -> None:
    mount = await simulated(at=(40.0, 120.0))
    zone = SunZone(15.0, SITE, NOON, AlignmentMode.GERMAN_POLAR)
    with pytest.raises(LimitError, match="sync position is"):
        await mount.sync_equatorial(zone.ra_j2000_hours, zone.dec_j2000_deg)


async def test_park_into_the_zone_is_refused() -> None:
    mount = await simulated(AZ_GTI, at=(40.0, 120.0))
    mount.park_position = ParkPosition(55.0, 185.0)
    with pytest.raises(LimitError, match="park position is"):
        await mount.park()
    assert not mount.state.parked


async def test_rate_motion_into_the_zone_is_stopped_outside_it() -> None:
    """The simulator stops itself at the zone edge, as at the horizon."""
    mount = await simulated(AZ_GTI, at=(SUN_ALT, 120.0))
    await mount.move_axis(MountAxis.PRIMARY, 2.0)  # azimuth increasing: towards the Sun
    mount.clock.advance(60.0)
    state = await mount.refresh()
    assert state.alt_deg is not None
    assert state.az_deg is not None
    # (The Sun has moved on by a few tenths since the stop, away from the tube.)
    zone = SunZone(15.0, SITE, mount.now(), AlignmentMode.ALT_AZ)
    assert 15.0 <= zone.distance_deg(state.alt_deg, state.az_deg) < 15.5
    assert "Sun avoidance zone" in state.problems[0]
    assert not state.slewing


@pytest.mark.parametrize("radius", [-1.0, 45.5, math.nan, math.inf])
def test_bad_radius_is_refused(radius: float) -> None:
    with pytest.raises(InvalidValueError, match="Sun avoidance radius"):
        Limits(sun_avoidance_deg=radius)


async def test_tracking_into_the_zone_is_turned_off_outside_it() -> None:
    """Midnight Sun at 80° N: sidereal tracking of a point 15.4° east of the Sun, which creeps
    eastwards 1° a day, is turned off when the Sun's zone reaches it (the horizon never does)."""
    arctic = Site(80.0, 0.0)
    clock = SimClock.stepped(NOON)
    mount = SimulatedMount(
        EQ6, site=arctic, clock=clock, limits=Limits(horizon_deg=0.0, sun_avoidance_deg=15.0)
    )
    await mount.connect()
    zone = SunZone(15.0, arctic, NOON, AlignmentMode.GERMAN_POLAR)
    ra = (zone.ra_j2000_hours + 15.4 / 15.0 / math.cos(math.radians(zone.dec_j2000_deg))) % 24.0
    await mount.goto_equatorial(ra, zone.dec_j2000_deg)
    clock.advance(600.0)
    assert (await mount.refresh()).tracking is TrackingMode.SIDEREAL
    clock.advance(2 * 86400.0)
    state = await mount.refresh()
    assert state.tracking is TrackingMode.OFF
    assert "Sun avoidance zone" in state.problems[0]
    assert state.alt_deg is not None
    assert state.az_deg is not None


@pytest.mark.filterwarnings("ignore:ERFA function")  # "dubious year": 2300 is the point
async def test_a_clock_outside_the_ephemeris_refuses_gotos_but_leaves_the_mount_usable() -> None:
    """No Sun can be placed in 2300 (a clock that ran there: ``set_time`` itself refuses such a
    date): gotos are refused with the reason, the simulator keeps working, and setting a sane time
    makes gotos work again."""
    mount = await simulated(at=(30.0, 90.0), when=datetime(2300, 1, 1, tzinfo=UTC))
    with pytest.raises(LimitError, match="the Sun cannot be placed at 2300-01-01"):
        await mount.goto_horizontal(40.0, 90.0)
    await mount.move_axis(MountAxis.SECONDARY, 1.0)
    await mount.abort()
    with pytest.raises(InvalidValueError, match="outside what a mount can keep"):
        await mount.set_time(datetime(2300, 1, 1, tzinfo=UTC))
    await mount.set_time(datetime(2026, 12, 21, 0, 0, tzinfo=UTC))
    await mount.goto_horizontal(40.0, 90.0)


@pytest.mark.parametrize(
    ("model", "start", "end"),
    [
        (AZ_GTI, (62.0, 120.0), (50.0, 250.0)),  # the short way round, past the Sun
        (AZ_GTI, (20.0, 300.0), (70.0, 100.0)),  # through north
        (EQ6, (30.0, 110.0), (40.0, 150.0)),  # east of the meridian: no flip
        (EQ6, (30.0, 110.0), (35.0, 250.0)),  # east to west: a flip over the pole
        (EQ6, (50.0, 250.0), (20.0, 200.0)),  # west of the meridian
    ],
)
async def test_the_path_model_is_the_path_the_simulator_takes(
    model: MountModel, start: tuple[float, float], end: tuple[float, float]
) -> None:
    """The closest approach to the Sun the model predicts equals the simulator's true slew
    (sampled every 0.05 s) within 0.3°, and is never farther (the model may check more paths)."""
    mount = await simulated(model, radius=0.0, at=start)
    state = await mount.refresh()
    assert state.alt_deg is not None
    assert state.az_deg is not None
    zone = SunZone(15.0, SITE, mount.now(), model.alignment_mode)
    predicted = zone._closest_on_path((state.alt_deg, state.az_deg), state.pier_side, end)
    await mount.goto_horizontal(*end)
    true_closest = math.inf
    for _ in range(2400):  # 120 s: longer than any slew
        mount.clock.advance(0.05)
        alt, az = mount.observed_at(mount.elapsed())
        true_closest = min(true_closest, zone.distance_deg(alt, az))
    assert predicted <= true_closest + 0.3
    assert predicted == pytest.approx(true_closest, abs=0.3)


def test_the_zone_follows_the_sun_across_the_sky() -> None:
    """``distance_deg(later_s=...)`` (the guard's look-ahead and the simulator's physics) agrees
    with the Sun placed afresh an hour later."""
    zone = SunZone(15.0, SITE, NOON, AlignmentMode.ALT_AZ)
    later = SunZone(15.0, SITE, NOON.replace(hour=13), AlignmentMode.ALT_AZ)
    for alt, az in [(40.0, 200.0), (60.0, 230.0), (20.0, 120.0)]:
        assert zone.distance_deg(alt, az, later_s=3600.0) == pytest.approx(
            later.distance_deg(alt, az), abs=0.05
        )


async def test_a_mount_the_sun_rose_onto_may_leave_but_not_go_deeper() -> None:
    """An alt-az mount left 10° from the Sun (the zone was off): a goto away and park are
    accepted; a goto nearer the Sun, or one whose path passes nearer, is refused."""
    mount = await simulated(AZ_GTI, at=(SUN_ALT, 160.0))
    state = await mount.refresh()
    assert state.alt_deg is not None
    assert state.az_deg is not None
    zone = SunZone(15.0, SITE, mount.now(), AlignmentMode.ALT_AZ)
    assert zone.distance_deg(state.alt_deg, state.az_deg) < 12.0
    with pytest.raises(LimitError, match="would pass"):
        await mount.goto_horizontal(SUN_ALT, 230.0)  # through the Sun to the other side
    await mount.goto_horizontal(40.0, 100.0)  # away
    mount.clock.advance(60.0)
    await mount.refresh()
    mount.park_position = ParkPosition(20.0, 0.0)
    await mount.park()
