"""SkyTrackerMount motion against the real emulators, over a pty and TCP: tracking, standby,
arrows at the rates the box supports (move_axis), PC-timed guide pulses, the horizon guard."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path

import pytest

from scopelink.mount import (
    GuideDirection,
    InvalidValueError,
    Limits,
    MountAxis,
    NotSupportedError,
    TrackingMode,
)
from scopelink.protocol.skytracker import Direction, TrackerMode
from tests.support.skytracker_driver import (
    TRANSPORTS,
    Rig,
    assert_position_matches_sim,
    box_mode,
    eventually,
    rig,
)

pytestmark = pytest.mark.parametrize("transport", TRANSPORTS)


async def track_at(r: Rig, alt_deg: float, az_deg: float) -> None:
    """Point the scope there and track (TRACK mode)."""
    r.point(alt_deg, az_deg)
    await r.driver.set_tracking(TrackingMode.ALT_AZ)
    # The box reads its track rates from the Sky Commander at its next firmware tick: wait for
    # them to drive both axes (a fixed sleep missed the tick on a loaded machine).
    await eventually(lambda: all(axis.rate != 0.0 for axis in r.sim.axes))


async def test_tracking_on_and_off(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await track_at(r, 40.0, 100.0)
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
            await r.driver.set_tracking(TrackingMode.PEC)  # lunar, solar, King: the rate loop


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
        await track_at(r, 40.0, 100.0)
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


async def test_pulse_guide_in_guide_mode_timed_on_the_pc(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport, guide_speed_arcsec_s=60) as r:
        with pytest.raises(NotSupportedError, match="tracking"):
            await r.driver.pulse_guide(GuideDirection.NORTH, 100)
        await track_at(r, 40.0, 100.0)
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


async def test_slew_down_is_released_above_the_horizon(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        r.point(40.0, 180.0)
        async with r.driver.watching():
            await r.driver.move_axis(MountAxis.SECONDARY, -4.0)
            assert r.driver.state.slewing
            await r.driver.wait_for(lambda s: not s.slewing, 10)
        altitude = r.sim.axes[1]
        await eventually(lambda: altitude.rate == 0.0)
        assert r.sim.observed_at(r.sim.elapsed())[0] > 0.0
        assert any("horizon" in p for p in r.driver.state.problems)


async def test_tracking_a_setting_star_stops_above_the_horizon(
    tmp_path: Path, transport: str
) -> None:
    """The Sky Tracker driver has no horizon guard of its own any more (issue #13): the Mount's
    HorizonGuard turns tracking off before a setting star carries the tube below the horizon."""
    horizon = 5.0
    async with rig(tmp_path, transport, limits=Limits(horizon_deg=horizon), clock_rate=200.0) as r:
        await track_at(r, horizon + 0.6, 270.0)  # in the west: the tracked star sets
        assert box_mode(r) is TrackerMode.TRACK
        lowest = 90.0
        async with r.driver.watching():
            async with asyncio.timeout(20.0):
                while box_mode(r) is TrackerMode.TRACK:
                    lowest = min(lowest, r.sim.observed_at(r.sim.elapsed())[0])
                    await asyncio.sleep(0.01)
            await r.driver.wait_for(lambda s: s.tracking is TrackingMode.OFF, 5.0)
        assert box_mode(r) is TrackerMode.UTILITY
        await asyncio.sleep(0.2)  # tracking is off: the tube stays where it stopped
        lowest = min(lowest, r.sim.observed_at(r.sim.elapsed())[0])
        assert lowest >= horizon, lowest
        assert any("horizon" in p for p in r.driver.state.problems), r.driver.state.problems


async def test_move_axis_at_the_track_arrow_rate(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await track_at(r, 40.0, 100.0)
        azimuth = r.sim.axes[0]
        track_rate = azimuth.rate
        await r.driver.move_axis(MountAxis.PRIMARY, -400.0 / 3600.0)  # nearest: 8'/s, TRACK
        assert box_mode(r) is TrackerMode.TRACK
        assert r.emulator.tracker.remote_pressed == Direction.LEFT
        await eventually(lambda: azimuth.rate == pytest.approx(track_rate - 8.0 / 60.0, abs=2e-3))
        await r.driver.move_axis(MountAxis.PRIMARY, 0.0)
        assert r.emulator.tracker.remote_pressed == Direction(0)
        assert box_mode(r) is TrackerMode.TRACK
