"""SkyTrackerMount against the real Sky Tracker + Sky Commander emulators, over a pty and TCP.

The emulated mount runs on an accelerated clock; positions the driver reports are compared with
where the simulator says the scope points.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from scopelink.drivers.skytracker import (
    SkyTrackerMount,
    SlewInProgressError,
    axis_motion,
)
from scopelink.mount import (
    AlignmentMode,
    GuideDirection,
    InvalidValueError,
    LimitError,
    MountAxis,
    NotConnectedError,
    NotSupportedError,
    TrackingMode,
)
from scopelink.protocol.skytracker import Direction, TrackerMode

from .test_driver_skytracker_support import (
    SITE,
    TRANSPORTS,
    Rig,
    rig,
    separation_deg,
    sky_at,
)

pytestmark = pytest.mark.parametrize("transport", TRANSPORTS)

POSITION_TOLERANCE_DEG = 0.02
"""The Sky Commander rounds RA/Dec to 3 decimals (RA 0.001 h = 0.015°·cos δ) both ways (``L99``
and position), and tracks in 0.5 s ticks."""


async def eventually(condition: Callable[[], bool], timeout_s: float = 5.0) -> None:
    """Wait until ``condition()`` holds (the emulator runs on its own)."""
    async with asyncio.timeout(timeout_s):
        while not condition():  # noqa: ASYNC110 - the emulator offers no event to wait on
            await asyncio.sleep(0.01)


def box_mode(rig_: Rig) -> TrackerMode:
    """The emulated box's mode (a function, so type checkers do not narrow it between reads)."""
    return rig_.emulator.tracker.mode


def driver_position(rig_: Rig) -> tuple[float, float]:
    state = rig_.driver.state
    assert state.ra_j2000_hours is not None
    assert state.dec_j2000_deg is not None
    return state.ra_j2000_hours, state.dec_j2000_deg


async def assert_position_matches_sim(rig_: Rig) -> None:
    """A refresh reads where the simulator points, between readings of the sim around it."""
    before = rig_.sim_j2000()
    await rig_.driver.refresh()
    after = rig_.sim_j2000()
    read = driver_position(rig_)
    assert min(separation_deg(read, before), separation_deg(read, after)) < POSITION_TOLERANCE_DEG


async def goto_and_land(rig_: Rig, target: tuple[float, float]) -> None:
    await rig_.driver.goto_equatorial(*target)
    assert rig_.driver.state.slewing
    state = await rig_.driver.wait_for_goto(timeout_s=15.0)
    assert not state.slewing


async def test_connect_identifies_the_box_and_reads_the_position(
    tmp_path: Path, transport: str
) -> None:
    async with rig(tmp_path, transport) as r:
        driver = r.driver
        assert driver.identity.protocol == "skytracker"
        assert driver.identity.model == "Sky Tracker + Sky Commander"
        assert driver.identity.firmware == "v4.0"
        assert driver.identity.link == r.spec
        assert driver.commander_present is True
        assert driver.tracker_mode is TrackerMode.UTILITY  # power-on mode
        caps = driver.capabilities
        assert caps.alignment_mode is AlignmentMode.ALT_AZ
        assert caps.can_goto
        assert caps.can_sync
        assert caps.can_pulse_guide
        assert not caps.can_park
        assert not caps.can_goto_altaz
        assert not caps.can_set_time
        assert caps.max_axis_rate_deg_s == 4.0
        state = driver.state
        assert state.connected
        assert not state.slewing
        assert state.tracking is TrackingMode.OFF
        assert state.alt_deg == pytest.approx(0.0, abs=0.01)  # level, pointing north
        assert state.az_deg is not None
        assert min(state.az_deg, 360 - state.az_deg) < 0.02
        await assert_position_matches_sim(r)


async def test_goto_lands_on_the_target_and_tracks(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        target = sky_at(r.sim, 50.0, 120.0)
        await goto_and_land(r, target)
        assert r.driver.tracker_mode is TrackerMode.TRACK
        state = r.driver.state
        assert state.tracking is TrackingMode.ALT_AZ
        assert separation_deg(driver_position(r), target) < POSITION_TOLERANCE_DEG
        assert separation_deg(r.sim_j2000(), target) < POSITION_TOLERANCE_DEG
        assert state.alt_deg == pytest.approx(50.0, abs=0.1)  # alt/az computed on the PC
        assert r.driver.target is not None
        assert r.driver.target.ra_j2000_hours == target[0]
        await asyncio.sleep(0.5)  # 10 simulated seconds of tracking
        await assert_position_matches_sim(r)
        assert separation_deg(driver_position(r), target) < POSITION_TOLERANCE_DEG


async def test_goto_below_the_horizon_sends_nothing(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        sent = r.driver.line.commands_sent
        with pytest.raises(LimitError):
            await r.driver.goto_equatorial(*sky_at(r.sim, -10.0, 200.0))
        assert r.driver.line.commands_sent == sent
        assert box_mode(r) is TrackerMode.UTILITY


async def test_abort_during_goto_ramps_down_to_utility(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await r.driver.goto_equatorial(*sky_at(r.sim, 60.0, 200.0))
        azimuth, altitude = r.sim.axes
        await eventually(lambda: max(abs(azimuth.rate), abs(altitude.rate)) > 1.0)
        await r.driver.abort()
        assert box_mode(r) is TrackerMode.UTILITY
        assert r.driver.tracker_mode is TrackerMode.UTILITY
        await eventually(lambda: azimuth.rate == altitude.rate == 0.0)
        state = await r.driver.refresh()
        assert not state.slewing
        assert state.tracking is TrackingMode.OFF
        await assert_position_matches_sim(r)


async def test_a_goto_during_a_goto_retargets(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await r.driver.goto_equatorial(*sky_at(r.sim, 60.0, 200.0))
        await asyncio.sleep(0.1)
        second = sky_at(r.sim, 30.0, 90.0)
        await goto_and_land(r, second)
        assert separation_deg(driver_position(r), second) < POSITION_TOLERANCE_DEG
        assert separation_deg(r.sim_j2000(), second) < POSITION_TOLERANCE_DEG


async def test_sync_realigns_the_sky_commander(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await goto_and_land(r, sky_at(r.sim, 40.0, 150.0))
        here = driver_position(r)
        told = ((here[0] + 0.05) % 24.0, here[1] - 0.3)
        await r.driver.sync_equatorial(*told)
        assert r.emulator.commander.aligned
        assert separation_deg(driver_position(r), told) < POSITION_TOLERANCE_DEG
        assert separation_deg(r.sim_j2000(), here) < 0.05  # the scope did not move
        with pytest.raises(InvalidValueError):
            await r.driver.sync_equatorial(24.5, 0.0)


async def test_sync_during_goto_is_refused_clearly(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await r.driver.goto_equatorial(*sky_at(r.sim, 60.0, 200.0))
        with pytest.raises(SlewInProgressError, match="GOTO"):
            await r.driver.sync_equatorial(1.0, 10.0)
        with pytest.raises(SlewInProgressError):
            await r.driver.move_axis(MountAxis.PRIMARY, 1.0)
        with pytest.raises(SlewInProgressError):
            await r.driver.set_tracking(TrackingMode.ALT_AZ)
        assert box_mode(r) is TrackerMode.GOTO  # none of it aborted the GOTO


async def test_tracking_on_and_off(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await goto_and_land(r, sky_at(r.sim, 40.0, 100.0))
        await r.driver.set_tracking(TrackingMode.OFF)
        assert box_mode(r) is TrackerMode.UTILITY
        azimuth, altitude = r.sim.axes
        await eventually(lambda: azimuth.rate == altitude.rate == 0.0)
        assert (await r.driver.refresh()).tracking is TrackingMode.OFF
        await r.driver.set_tracking(TrackingMode.SIDEREAL)
        assert box_mode(r) is TrackerMode.TRACK
        await eventually(lambda: altitude.rate != 0.0)
        assert (await r.driver.refresh()).tracking is TrackingMode.SIDEREAL
        with pytest.raises(NotSupportedError):
            await r.driver.set_tracking(TrackingMode.LUNAR)


async def test_standby_cuts_the_drive(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await r.driver.set_tracking(TrackingMode.ALT_AZ)
        await r.driver.standby()
        assert box_mode(r) is TrackerMode.STANDBY
        await r.driver.refresh()
        assert r.driver.tracker_mode is TrackerMode.STANDBY
        assert r.driver.state.tracking is TrackingMode.OFF


async def test_move_axis_at_the_utility_rate_then_stop(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        azimuth, altitude = r.sim.axes
        await r.driver.move_axis(MountAxis.SECONDARY, 3.0)  # nearest: 4°/s UTILITY
        await r.driver.move_axis(MountAxis.PRIMARY, -3.9)
        assert r.emulator.tracker.remote_pressed == Direction.UP | Direction.LEFT
        # Left: compass azimuth decreasing.
        await eventually(lambda: (altitude.rate, azimuth.rate) == pytest.approx((4.0, -4.0)))
        assert (await r.driver.refresh()).slewing
        await r.driver.move_axis(MountAxis.SECONDARY, 0.0)
        assert r.emulator.tracker.remote_pressed == Direction.LEFT  # the other arrow is held
        await eventually(lambda: altitude.rate == 0.0)
        assert azimuth.rate == pytest.approx(-4.0)  # still going
        await r.driver.move_axis(MountAxis.PRIMARY, 0.0)
        await eventually(lambda: azimuth.rate == 0.0)
        assert not (await r.driver.refresh()).slewing
        await assert_position_matches_sim(r)


async def test_move_axis_at_a_guide_rate_adds_to_tracking(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await goto_and_land(r, sky_at(r.sim, 40.0, 100.0))
        altitude = r.sim.axes[1]
        await asyncio.sleep(0.1)
        track_rate = altitude.rate
        await r.driver.move_axis(MountAxis.SECONDARY, 0.01)  # 36 arcsec/s: GUIDE with K = 36
        assert box_mode(r) is TrackerMode.GUIDE
        assert r.emulator.tracker.guide_speeds_arcsec_s[1] == 36
        await eventually(lambda: altitude.rate == pytest.approx(track_rate + 0.01, abs=2e-4))
        with pytest.raises(InvalidValueError, match="one mode"):
            await r.driver.move_axis(MountAxis.PRIMARY, 4.0)  # UTILITY would stop tracking
        await r.driver.move_axis(MountAxis.SECONDARY, 0.0)
        assert box_mode(r) is TrackerMode.TRACK  # back to the mode before
        await eventually(lambda: altitude.rate == pytest.approx(track_rate, abs=2e-4))


def test_rates_map_to_the_nearest_supported(transport: str) -> None:
    del transport  # a pure function: the same on every link
    guide = axis_motion(MountAxis.PRIMARY, 100.4 / 3600.0)
    assert guide is not None
    assert guide.mode is TrackerMode.GUIDE
    assert guide.guide_speed_arcsec_s == 100
    assert guide.direction is Direction.RIGHT
    tiny = axis_motion(MountAxis.SECONDARY, -0.1 / 3600.0)
    assert tiny is not None
    assert tiny.guide_speed_arcsec_s == 1
    assert tiny.direction is Direction.DOWN
    track = axis_motion(MountAxis.PRIMARY, -400.0 / 3600.0)
    assert track is not None
    assert track.mode is TrackerMode.TRACK
    assert track.rate_deg_s == pytest.approx(-8.0 / 60.0)
    assert track.direction is Direction.LEFT
    near_guide = axis_motion(MountAxis.PRIMARY, 300.0 / 3600.0)
    assert near_guide is not None
    assert near_guide.guide_speed_arcsec_s == 255
    utility = axis_motion(MountAxis.SECONDARY, 2.1)
    assert utility is not None
    assert utility.mode is TrackerMode.UTILITY
    assert axis_motion(MountAxis.PRIMARY, 0.0) is None


async def test_pulse_guide_in_guide_mode_timed_on_the_pc(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport, guide_speed_arcsec_s=60) as r:
        with pytest.raises(NotSupportedError, match="tracking"):
            await r.driver.pulse_guide(GuideDirection.NORTH, 100)
        await goto_and_land(r, sky_at(r.sim, 40.0, 100.0))
        tracker = r.emulator.tracker
        assert tracker.guide_speeds_arcsec_s == (60, 60)
        started = time.monotonic()
        await r.driver.pulse_guide(GuideDirection.NORTH, 400)
        await r.driver.pulse_guide(GuideDirection.EAST, 400)
        assert box_mode(r) is TrackerMode.GUIDE
        assert tracker.remote_pressed == Direction.UP | Direction.LEFT
        assert r.driver.state.pulse_guiding
        assert not (await r.driver.refresh()).slewing  # guiding is not slewing
        await eventually(lambda: tracker.remote_pressed == Direction(0))
        elapsed = time.monotonic() - started
        assert 0.38 < elapsed < 1.5
        await eventually(lambda: not r.driver.state.pulse_guiding)
        assert box_mode(r) is TrackerMode.TRACK  # back to tracking as before


async def test_guide_speed_is_set_and_confirmed(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await r.driver.set_guide_speed(30, 45)
        assert r.emulator.tracker.guide_speeds_arcsec_s == (30, 45)
        with pytest.raises(InvalidValueError):
            await r.driver.set_guide_speed(0, 45)


async def test_what_the_box_cannot_do_is_not_supported(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        with pytest.raises(NotSupportedError):
            await r.driver.park()
        with pytest.raises(NotSupportedError):
            await r.driver.goto_horizontal(45.0, 180.0)
        with pytest.raises(NotSupportedError):
            await r.driver.set_time(r.sim.clock.now())


async def test_disconnect_releases_and_aborts(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await r.driver.goto_equatorial(*sky_at(r.sim, 60.0, 200.0))
        await r.driver.disconnect()
        assert not r.driver.state.connected
        assert box_mode(r) is TrackerMode.UTILITY
        with pytest.raises(NotConnectedError):
            await r.driver.refresh()
        await r.driver.connect()  # a new link to the same box
        assert (await r.driver.refresh()).connected
        await assert_position_matches_sim(r)


async def test_slew_down_is_released_above_the_horizon(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await goto_and_land(r, sky_at(r.sim, 20.0, 180.0))
        await r.driver.set_tracking(TrackingMode.OFF)
        async with r.driver.watching():
            await r.driver.move_axis(MountAxis.SECONDARY, -4.0)
            assert r.driver.state.slewing
            await r.driver.wait_for(lambda s: not s.slewing, 10)
        altitude = r.sim.axes[1]
        await eventually(lambda: altitude.rate == 0.0)
        assert r.sim.observed_at(r.sim.elapsed())[0] > 0.0
        assert any("horizon" in p for p in r.driver.state.problems)


async def test_blocking_facade_over_the_driver(tmp_path: Path, transport: str) -> None:
    from scopelink.mount.blocking import BlockingMount

    async with rig(tmp_path, transport, connect=False) as r:
        spec = r.spec
        clock = r.sim.clock.now
        target = sky_at(r.sim, 45.0, 135.0)

        def script() -> tuple[float, float]:
            driver = SkyTrackerMount(spec, site=SITE, clock=clock)
            with BlockingMount(driver) as mount:
                mount.connect()
                mount.goto_equatorial(*target)
                state = mount.wait_for_slew(timeout_s=15.0)
                assert state.ra_j2000_hours is not None
                assert state.dec_j2000_deg is not None
                mount.disconnect()
                return state.ra_j2000_hours, state.dec_j2000_deg

        landed = await asyncio.to_thread(script)
        assert separation_deg(landed, target) < POSITION_TOLERANCE_DEG
