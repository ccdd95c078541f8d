"""The simulated mount: gotos, tracking, meridian flips, limits, park, abort, guiding, sync."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest

from scopelink.astro import (
    SIDEREAL_RATE_DEG_S,
    PierSide,
    Site,
    angular_separation_deg,
    destination_side_of_pier,
    hour_angle_hours,
    j2000_to_apparent,
    j2000_to_observed,
    lst_hours,
)
from scopelink.mount import (
    GuideDirection,
    LimitError,
    Limits,
    MountAxis,
    MountState,
    ParkedError,
    TrackingMode,
)
from scopelink.sim import AZ_GTI, EQ6, MountModel, SimClock, SimulatedMount

START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
NORTH = Site(latitude_deg=45.0, longitude_deg=7.0, elevation_m=300.0)
SOUTH = Site(latitude_deg=-33.9, longitude_deg=18.4, elevation_m=50.0)
ARCSEC = 1.0 / 3600.0


async def make_mount(
    model: MountModel = EQ6, site: Site = NORTH, **options: object
) -> SimulatedMount:
    mount = SimulatedMount(model, site=site, clock=SimClock.stepped(START), **options)  # type: ignore[arg-type]
    await mount.connect()
    return mount


def error_arcsec(state: MountState, ra_hours: float, dec_deg: float) -> float:
    assert state.ra_j2000_hours is not None
    assert state.dec_j2000_deg is not None
    separation = angular_separation_deg(
        state.ra_j2000_hours * 15.0, state.dec_j2000_deg, ra_hours * 15.0, dec_deg
    )
    return separation * 3600.0


def target_at_hour_angle(site: Site, ha_hours: float, dec_deg: float) -> tuple[float, float]:
    """A J2000 position at roughly ``ha_hours`` from the meridian at START."""
    return (lst_hours(START, site.longitude_deg) - ha_hours) % 24.0, dec_deg


async def land(mount: SimulatedMount) -> MountState:
    """Step the clock to the end of the goto in progress and return the state there."""
    landing = mount.goto_ends_at
    assert landing is not None
    assert mount.goto_in_progress
    mount.step(landing - mount.elapsed() - 1e-3)
    assert mount.snapshot().slewing
    return mount.step(1e-3)


CASES = [
    pytest.param(EQ6, NORTH, 70.0, id="gem-north"),
    pytest.param(EQ6, SOUTH, -70.0, id="gem-south"),
    pytest.param(AZ_GTI, NORTH, 70.0, id="altaz-north"),
    pytest.param(AZ_GTI, SOUTH, -70.0, id="altaz-south"),
]


@pytest.mark.parametrize(("model", "site", "dec"), CASES)
async def test_goto_lands_on_target_then_tracking_holds_it_for_hours(
    model: MountModel, site: Site, dec: float
) -> None:
    mount = await make_mount(model, site)
    ra, dec = target_at_hour_angle(site, 1.0, dec)
    await mount.goto_equatorial(ra, dec)
    assert mount.state.slewing
    state = await land(mount)
    landing = mount.clock.now()
    assert not state.slewing
    assert state.tracking is not TrackingMode.OFF  # a goto turns tracking on
    assert error_arcsec(state, ra, dec) < 0.1
    # Observed position agrees with astro's at the same instant.
    alt, az = j2000_to_observed(ra, dec, landing, site)
    assert state.alt_deg == pytest.approx(alt, abs=0.1 * ARCSEC)
    assert state.az_deg == pytest.approx(az, abs=0.1 * ARCSEC / max(0.1, abs(1 - alt / 90)))
    ra_of_date, dec_of_date = j2000_to_apparent(ra, dec, landing)
    assert state.ra_of_date_hours == pytest.approx(ra_of_date, abs=0.1 * ARCSEC / 15)
    assert state.dec_of_date_deg == pytest.approx(dec_of_date, abs=0.1 * ARCSEC)
    primary_start = mount.axes[0].position
    worst = 0.0
    for _ in range(6 * 60):
        state = mount.step(60.0)
        worst = max(worst, error_arcsec(state, ra, dec))
    assert worst < 0.1
    assert state.tracking is not TrackingMode.OFF
    assert mount.axes[0].position != pytest.approx(primary_start, abs=1.0)  # it did turn


@pytest.mark.parametrize("site", [NORTH, SOUTH], ids=["north", "south"])
@pytest.mark.parametrize("ha", [-2.0, 2.0, -7.0, 7.0])
async def test_gem_goto_picks_the_ascom_side_of_pier(site: Site, ha: float) -> None:
    mount = await make_mount(EQ6, site)
    ra, dec = target_at_hour_angle(site, ha, 50.0 if site is NORTH else -50.0)
    await mount.goto_equatorial(ra, dec)
    state = await land(mount)
    ra_of_date, _ = j2000_to_apparent(ra, dec, mount.clock.now())
    expected = destination_side_of_pier(
        hour_angle_hours(lst_hours(mount.clock.now(), site.longitude_deg), ra_of_date)
    )
    assert state.pier_side is expected
    assert error_arcsec(state, ra, dec) < 0.1


async def test_gem_flips_when_crossing_to_the_other_side() -> None:
    mount = await make_mount(EQ6, NORTH)
    east = target_at_hour_angle(NORTH, -2.0, 20.0)
    west = target_at_hour_angle(NORTH, 2.0, 20.0)
    await mount.goto_equatorial(*east)
    assert (await land(mount)).pier_side is PierSide.WEST
    await mount.goto_equatorial(*west)
    state = await land(mount)
    assert state.pier_side is PierSide.EAST
    assert error_arcsec(state, *west) < 0.1


async def test_gem_stays_on_its_side_within_the_meridian_tolerance() -> None:
    mount = await make_mount(EQ6, NORTH, meridian_tolerance_deg=7.5)
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, 1.0, 20.0))
    assert (await land(mount)).pier_side is PierSide.EAST
    just_east = target_at_hour_angle(NORTH, -0.2, 20.0)  # 3° east of the meridian
    await mount.goto_equatorial(*just_east)
    state = await land(mount)
    assert state.pier_side is PierSide.EAST  # no flip for 3° past the meridian
    assert error_arcsec(state, *just_east) < 0.1


async def test_gem_tracking_stops_at_the_meridian_limit() -> None:
    mount = await make_mount(EQ6, NORTH, meridian_tolerance_deg=5.0)
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, -1.0, 20.0))  # flipped, pier west
    await land(mount)
    state = mount.step(3 * 3600.0)
    assert state.tracking is TrackingMode.OFF
    assert state.problems
    assert mount.limit_stop is not None
    # Stopped 5° (20 min) past the meridian: about 1 h 20 min after the goto.
    assert 4700.0 < mount.limit_stop.at_s < 4900.0
    assert abs(mount.axes[0].position) == pytest.approx(95.0, abs=1e-4)


@pytest.mark.parametrize("model", [EQ6, AZ_GTI], ids=["gem", "altaz"])
async def test_goto_below_the_horizon_is_refused_and_nothing_moves(model: MountModel) -> None:
    mount = await make_mount(model, NORTH)
    before = mount.counters_at(mount.elapsed())
    ra, dec = target_at_hour_angle(NORTH, 12.0, -30.0)  # under the southern horizon
    with pytest.raises(LimitError):
        await mount.goto_equatorial(ra, dec)
    with pytest.raises(LimitError):
        await mount.goto_horizontal(-5.0, 180.0)
    state = mount.step(30.0)
    assert not state.slewing
    assert mount.counters_at(mount.elapsed()) == before
    assert not mount.axes[0].is_moving
    assert not mount.axes[1].is_moving


async def test_move_axis_into_the_horizon_stops_at_the_horizon_altaz() -> None:
    mount = await make_mount(AZ_GTI, NORTH, limits=Limits(horizon_deg=10.0))
    await mount.goto_horizontal(30.0, 180.0)
    await land(mount)
    await mount.move_axis(MountAxis.SECONDARY, -2.0)
    state = mount.step(30.0)
    assert state.alt_deg == pytest.approx(10.0, abs=1e-6)
    assert not mount.axes[1].is_moving
    assert not state.slewing
    assert state.problems
    # Moving up again is allowed.
    await mount.move_axis(MountAxis.SECONDARY, 1.0)
    state = mount.step(3.0)
    assert state.alt_deg is not None
    assert state.alt_deg > 10.5


async def test_move_axis_into_the_horizon_stops_at_the_horizon_gem() -> None:
    mount = await make_mount(EQ6, NORTH)
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, 2.0, 10.0))
    await land(mount)
    await mount.set_tracking(TrackingMode.OFF)
    await mount.move_axis(MountAxis.SECONDARY, -3.0)  # towards the southern horizon
    state = mount.step(60.0)
    assert state.alt_deg == pytest.approx(0.0, abs=1e-6)
    assert not mount.axes[1].is_moving


async def test_tracking_into_the_horizon_stops_there() -> None:
    mount = await make_mount(AZ_GTI, NORTH)
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, 3.0, 0.0))  # setting in the west
    await land(mount)
    state = mount.step(6 * 3600.0)
    assert state.tracking is TrackingMode.OFF
    assert state.alt_deg == pytest.approx(0.0, abs=1e-6)


async def test_move_axis_rate_is_limited_to_the_preset() -> None:
    mount = await make_mount(EQ6, NORTH)
    with pytest.raises(ValueError, match="rate"):
        await mount.move_axis(MountAxis.PRIMARY, EQ6.max_rate_deg_s * 1.01)
    await mount.move_axis(MountAxis.PRIMARY, EQ6.max_rate_deg_s)
    state = mount.step(5.0)
    assert state.slewing
    assert mount.axes[0].rate == pytest.approx(EQ6.max_rate_deg_s)
    await mount.move_axis(MountAxis.PRIMARY, 0.0)
    state = mount.step(1.5)
    assert not state.slewing
    assert mount.axes[0].rate == 0.0


async def test_park_and_unpark() -> None:
    mount = await make_mount(EQ6, NORTH)
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, 2.0, 30.0))
    await land(mount)
    await mount.park()
    assert not mount.state.parked  # parked once it has arrived (issue #11 part 4)
    assert mount.state.slewing
    await land(mount)
    state = mount.step(0.01)  # just past the landing (land() may stop a rounding error short)
    assert state.parked
    assert not state.slewing
    assert state.tracking is TrackingMode.OFF
    assert mount.counters_at(mount.elapsed()) == pytest.approx(mount.park_counters)
    with pytest.raises(ParkedError):
        await mount.goto_equatorial(*target_at_hour_angle(NORTH, 2.0, 30.0))
    with pytest.raises(ParkedError):
        await mount.move_axis(MountAxis.PRIMARY, 1.0)
    state = mount.step(600.0)
    assert mount.counters_at(mount.elapsed()) == pytest.approx(mount.park_counters)
    await mount.unpark()
    unparked = mount.snapshot()
    assert not unparked.parked
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, 2.0, 30.0))
    assert mount.snapshot().slewing


async def test_abort_mid_slew_ramps_down_and_keeps_tracking_setting() -> None:
    mount = await make_mount(EQ6, NORTH)
    target = target_at_hour_angle(NORTH, 3.0, -10.0)
    await mount.goto_equatorial(*target)
    mount.step(3.0)
    assert mount.state.slewing
    rates = [abs(axis.rate) for axis in mount.axes]
    await mount.abort()
    state = mount.step(max(rates) / EQ6.acceleration_deg_s2 + 0.01)
    assert not state.slewing
    assert error_arcsec(state, *target) > 3600.0  # stopped well short of the target
    # Tracking goes on from where it stopped: the sky position holds.
    held = state
    state = mount.step(600.0)
    assert state.tracking is TrackingMode.SIDEREAL
    assert error_arcsec(state, held.ra_j2000_hours or 0.0, held.dec_j2000_deg or 0.0) < 0.1


@pytest.mark.parametrize(
    ("direction", "axis_index", "sign"),
    [
        (GuideDirection.WEST, 0, 1.0),
        (GuideDirection.EAST, 0, -1.0),
        (GuideDirection.NORTH, 1, 1.0),
        (GuideDirection.SOUTH, 1, -1.0),
    ],
)
async def test_pulse_guide_moves_by_rate_times_duration(
    direction: GuideDirection, axis_index: int, sign: float
) -> None:
    guided = await make_mount(EQ6, NORTH)
    reference = await make_mount(EQ6, NORTH)
    target = target_at_hour_angle(NORTH, 2.0, 30.0)
    for mount in (guided, reference):
        await mount.goto_equatorial(*target)
        await land(mount)
    await guided.pulse_guide(direction, 2000)
    assert guided.state.pulse_guiding
    guided.step(1.0)
    assert guided.snapshot().pulse_guiding
    guided.step(10.0)
    t = guided.elapsed()
    assert not guided.snapshot().pulse_guiding
    moved = guided.axes[axis_index].position_at(t) - reference.axes[axis_index].position_at(t)
    assert moved == pytest.approx(sign * 0.5 * SIDEREAL_RATE_DEG_S * 2.0, abs=1e-9)
    # The guided position is then tracked like any other.
    state = guided.snapshot()
    guided.step(1800.0)
    assert (
        error_arcsec(guided.snapshot(), state.ra_j2000_hours or 0.0, state.dec_j2000_deg or 0.0)
        < 0.1
    )
    if direction is GuideDirection.NORTH:
        assert (state.dec_j2000_deg or 0.0) - target[1] == pytest.approx(
            15.041 * ARCSEC, abs=0.05 * ARCSEC
        )


async def test_sync_shifts_the_reported_position() -> None:
    mount = await make_mount(EQ6, NORTH, aligned=False)
    assert not mount.snapshot().aligned
    target = target_at_hour_angle(NORTH, 2.0, 30.0)
    await mount.goto_equatorial(*target)
    await land(mount)
    synced = ((target[0] + 10.0 / 3600.0) % 24.0, target[1] - 0.05)
    assert mount.sync_distance_deg(*synced) == pytest.approx(
        angular_separation_deg(target[0] * 15, target[1], synced[0] * 15, synced[1]), abs=1e-6
    )
    physical = [axis.physical_position_at(mount.elapsed()) for axis in mount.axes]
    await mount.sync_equatorial(*synced)
    state = mount.step(0.0)
    assert state.aligned
    assert error_arcsec(state, *synced) < 0.1
    assert [axis.physical_position_at(mount.elapsed()) for axis in mount.axes] == pytest.approx(
        physical
    )
    state = mount.step(3600.0)
    assert error_arcsec(state, *synced) < 0.1


async def test_lunar_tracking_drifts_east_against_the_stars() -> None:
    mount = await make_mount(EQ6, NORTH)
    target = target_at_hour_angle(NORTH, 1.0, 10.0)
    await mount.goto_equatorial(*target)
    await land(mount)
    await mount.set_tracking(TrackingMode.LUNAR)
    start = mount.step(0.0)
    state = mount.step(3600.0)
    drift_arcsec = ((state.ra_j2000_hours or 0.0) - (start.ra_j2000_hours or 0.0)) * 15 * 3600
    assert drift_arcsec == pytest.approx((15.041067 - 14.685) * 3600, rel=1e-3)


async def test_pec_tracking_is_sidereal() -> None:
    mount = await make_mount(EQ6, NORTH)
    target = target_at_hour_angle(NORTH, 1.0, 10.0)
    await mount.goto_equatorial(*target)
    await land(mount)
    await mount.set_tracking(TrackingMode.PEC)
    state = mount.step(3600.0)
    assert state.tracking is TrackingMode.PEC
    assert error_arcsec(state, *target) < 0.1


async def test_set_time_moves_the_sky_not_the_axes() -> None:
    mount = await make_mount(EQ6, NORTH)
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, 1.0, 20.0))
    await land(mount)
    counters = mount.counters_at(mount.elapsed())
    await mount.set_time(mount.now() + timedelta(hours=1))
    assert mount.counters_at(mount.elapsed()) == pytest.approx(counters, abs=1e-9)
    before = mount.snapshot()
    state = mount.step(600.0)
    assert error_arcsec(state, before.ra_j2000_hours or 0.0, before.dec_j2000_deg or 0.0) < 0.1


async def test_power_on_positions() -> None:
    gem = (await make_mount(EQ6, NORTH)).snapshot()
    assert gem.alt_deg == pytest.approx(45.0)
    assert gem.dec_j2000_deg == pytest.approx(90.0, abs=0.5)  # the pole of date, not of J2000
    assert gem.tracking is TrackingMode.OFF
    south = (await make_mount(EQ6, SOUTH)).snapshot()
    assert south.alt_deg == pytest.approx(33.9)
    assert south.az_deg == pytest.approx(180.0)
    altaz = (await make_mount(AZ_GTI, NORTH)).snapshot()
    assert (altaz.alt_deg, altaz.az_deg) == (0.0, 0.0)
    assert altaz.pier_side is PierSide.UNKNOWN


@pytest.mark.parametrize("model", [EQ6, AZ_GTI], ids=["gem", "altaz"])
async def test_overlapping_guide_pulses_end_smoothly_and_are_tracked(model: MountModel) -> None:
    mount = await make_mount(model, NORTH)
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, 2.0, 30.0))
    await land(mount)
    await mount.pulse_guide(GuideDirection.WEST, 1000)
    mount.step(0.2)
    await mount.pulse_guide(GuideDirection.NORTH, 500)
    start = mount.elapsed()
    previous = mount.counters_at(start)
    for k in range(1, 500):  # both pulses end in here: no jump anywhere (3 ms steps)
        counters = mount.counters_at(start + k * 3e-3)
        assert abs(counters[0] - previous[0]) < 5e-5
        assert abs(counters[1] - previous[1]) < 5e-5
        previous = counters
    held = mount.step(2.0)
    state = mount.step(3600.0)
    assert error_arcsec(state, held.ra_j2000_hours or 0.0, held.dec_j2000_deg or 0.0) < 0.1


@pytest.mark.parametrize("site", [NORTH, SOUTH], ids=["north", "south"])
async def test_gem_flip_swings_the_tube_through_the_visible_pole(site: Site) -> None:
    mount = await make_mount(EQ6, site)
    first = target_at_hour_angle(site, 2.0, -20.0 if site is NORTH else 20.0)
    second = target_at_hour_angle(site, -2.0, first[1])  # the other side of the meridian
    for target in (first, second, first):
        start = mount.elapsed()
        await mount.goto_equatorial(*target)
        landing = mount.goto_ends_at
        assert landing is not None
        for k in range(201):
            t = start + (landing - start) * k / 200
            _, secondary = mount.counters_at(t)
            assert -90.0 - 1e-9 <= secondary <= 270.0 + 1e-9  # never through the hidden pole
            assert mount.geometry.to_observed(*mount.counters_at(t))[0] > -5.0
        state = await land(mount)
        assert error_arcsec(state, *target) < 0.1


async def test_tracking_off_stops_the_axes_on_a_running_clock() -> None:
    """On an accelerated clock time passes while a command plans; the stop it schedules at its
    own start must still apply (it was once dropped as 'past', and tracking went on)."""
    import asyncio

    mount = SimulatedMount(EQ6, site=NORTH, clock=SimClock(start=START, rate=50.0))
    await mount.connect()
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, 1.0, 30.0))
    await mount.wait_for_slew(timeout_s=20)
    assert mount.tracking is TrackingMode.SIDEREAL
    await mount.set_tracking(TrackingMode.OFF)
    before = mount.counters_at(mount.elapsed())
    await asyncio.sleep(0.4)  # 20 simulated seconds: sidereal tracking would turn 0.08°
    after = mount.counters_at(mount.elapsed())
    assert after == pytest.approx(before, abs=1e-6)


async def test_an_axis_rate_adds_to_tracking_on_a_running_clock() -> None:
    """On an accelerated clock a command acts at its start, already past when it is planned:
    the history it builds on must still be there (the move was once lost when it stopped)."""
    import asyncio

    mount = SimulatedMount(EQ6, site=NORTH, clock=SimClock(start=START, rate=20.0))
    await mount.connect()
    await mount.goto_equatorial(*target_at_hour_angle(NORTH, 1.0, 30.0))
    await mount.wait_for_slew(timeout_s=20)
    extra = 0.5 * SIDEREAL_RATE_DEG_S
    start_counter, start = mount.counters_at(mount.elapsed())[0], mount.elapsed()
    before_move = mount.elapsed()
    await mount.move_axis(MountAxis.PRIMARY, extra)
    after_move = mount.elapsed()
    await asyncio.sleep(0.5)
    before_stop = mount.elapsed()
    await mount.move_axis(MountAxis.PRIMARY, 0.0)
    after_stop = mount.elapsed()
    await asyncio.sleep(0.2)
    end_counter, end = mount.counters_at(mount.elapsed())[0], mount.elapsed()
    beyond_tracking = (end_counter - start_counter) - SIDEREAL_RATE_DEG_S * (end - start)
    # The extra rate ran from some time in the move command to some time in the stop command.
    assert extra * (before_stop - after_move) - 1e-3 <= beyond_tracking
    assert beyond_tracking <= extra * (after_stop - before_move) + 1e-3


async def test_a_chosen_park_position_is_where_park_goes() -> None:
    """Alpaca's SetPark (and a configured park) choose an alt/az; the simulator parks there
    instead of at its power-on counters."""
    from scopelink.mount import ParkPosition

    mount = await make_mount()
    chosen_before = mount.park_position_chosen
    mount.park_position = ParkPosition(30.0, 100.0)
    assert (chosen_before, mount.park_position_chosen) == (False, True)
    await mount.park()
    state = await land(mount)
    assert state.parked
    assert state.tracking is TrackingMode.OFF
    alt, az = mount.observed_at(mount.elapsed())
    assert alt == pytest.approx(30.0, abs=1e-6)
    assert az == pytest.approx(100.0, abs=1e-6)


@pytest.mark.parametrize("site", [NORTH, SOUTH], ids=["north", "south"])
async def test_tracking_at_the_pole_turns_the_polar_axis_at_the_sidereal_rate(site: Site) -> None:
    # At the pole the hour angle is undefined: following the sky point there exactly used to
    # leave the polar axis spinning at thousands of degrees a second after a stop.
    mount = await make_mount(EQ6, site)
    await mount.set_tracking(TrackingMode.SIDEREAL)
    mount.step(0.5)
    await mount.abort()
    await mount.abort()
    mount.step(3600.0)
    state = mount.snapshot()
    assert state.problems == ()
    assert not state.slewing
    polar, declination = mount.axes
    assert polar.rate_at(mount.elapsed()) == pytest.approx(
        site_sign(site) * SIDEREAL_RATE_DEG_S, rel=1e-9
    )
    assert declination.rate_at(mount.elapsed()) == 0.0
    assert state.alt_deg == pytest.approx(abs(site.latitude_deg), abs=1e-6)


def site_sign(site: Site) -> float:
    return 1.0 if site.latitude_deg >= 0.0 else -1.0
