"""SkyTrackerMount against the real Sky Tracker + Sky Commander emulators, over a pty and TCP.

The emulated mount runs on an accelerated clock; positions the driver reports are compared with
where the simulator says the scope points.
"""

from __future__ import annotations

import asyncio
import time
from pathlib import Path

import pytest

from scopelink.astro import Site, j2000_to_observed
from scopelink.drivers.skytracker import (
    SkyTrackerMount,
    SlewInProgressError,
)
from scopelink.mount import (
    AlignmentMode,
    InvalidValueError,
    LimitError,
    MountAxis,
    NotConnectedError,
    NotSupportedError,
    TrackingMode,
)
from scopelink.protocol.skytracker import TrackerMode
from tests.support.skytracker_driver import (
    POSITION_TOLERANCE_DEG,
    SITE,
    TRANSPORTS,
    Rig,
    assert_position_matches_sim,
    box_mode,
    driver_position,
    eventually,
    rig,
    separation_deg,
    sky_at,
)

pytestmark = pytest.mark.parametrize("transport", TRANSPORTS)


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
        # Alt/az are computed on the PC from the J2000 position and the time of the reading.
        expected_alt, expected_az = j2000_to_observed(*target, state.read_at, SITE)
        assert state.alt_deg == pytest.approx(expected_alt, abs=0.03)
        assert state.az_deg == pytest.approx(expected_az, abs=0.05)
        assert r.driver.target is not None
        assert r.driver.target.ra_j2000_hours == target[0]
        await asyncio.sleep(0.5)  # 10 simulated seconds of tracking
        await assert_position_matches_sim(r)
        assert separation_deg(driver_position(r), target) < POSITION_TOLERANCE_DEG


async def test_goto_below_the_horizon_sends_nothing(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        sent = r.driver.line.statistics.commands_sent
        with pytest.raises(LimitError):
            await r.driver.goto_equatorial(*sky_at(r.sim, -10.0, 200.0))
        assert r.driver.line.statistics.commands_sent == sent
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
        r.point(40.0, 150.0)
        await r.driver.set_tracking(TrackingMode.ALT_AZ)
        await r.driver.refresh()
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
        here = r.driver.state  # a sync within limits.max_sync_deg: the GOTO refuses it
        assert here.ra_j2000_hours is not None
        assert here.dec_j2000_deg is not None
        with pytest.raises(SlewInProgressError, match="GOTO"):
            await r.driver.sync_equatorial(here.ra_j2000_hours, here.dec_j2000_deg)
        with pytest.raises(SlewInProgressError):
            await r.driver.move_axis(MountAxis.PRIMARY, 1.0)
        with pytest.raises(SlewInProgressError):
            await r.driver.set_tracking(TrackingMode.ALT_AZ)
        assert box_mode(r) is TrackerMode.GOTO  # none of it aborted the GOTO


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


async def test_open_constructs_and_connects(tmp_path: Path, transport: str) -> None:
    """The constructor touches nothing; ``await SkyTrackerMount.open`` connects (the same meaning
    as ``SynScanMount.open``); ``timeout_s`` is the one reply timeout, as on SynScan."""
    async with rig(tmp_path, transport, connect=False) as r:
        assert not r.driver.state.connected
        assert r.emulator.tracker.mode is not None  # the box is there, untouched
        with pytest.raises(NotConnectedError):
            _ = r.driver.line
        opened = await SkyTrackerMount.open(
            r.spec, site=SITE, clock=r.sim.clock.now, timeout_s=0.5, name=r.spec
        )
        try:
            assert opened.state.connected
            assert opened.identity.link == r.spec
            assert opened.timeout_s == opened.line.timeout_s == 0.5
            assert opened.line.statistics.commands_sent > 0
        finally:
            await opened.disconnect()
    with pytest.raises(ValueError, match="timeout"):
        SkyTrackerMount("tcp://127.0.0.1:1", site=SITE, timeout_s=0.0)


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


async def test_abort_goes_before_waiting_polls(tmp_path: Path, transport: str) -> None:
    """While the poller keeps the wire busy, a command takes the next turn (Priority.COMMAND)."""
    async with rig(tmp_path, transport) as r:
        await r.driver.goto_equatorial(*sky_at(r.sim, 60.0, 200.0))
        async with r.driver.watching():
            await r.driver.wait_for(lambda s: s.slewing, 5.0)
            polls = r.driver.poller.polls
            started = time.monotonic()
            await r.driver.abort()
            assert time.monotonic() - started < 1.0  # generous: an abort is ~3 bytes of wire
            assert box_mode(r) is TrackerMode.UTILITY
            state = await r.driver.wait_for(lambda s: not s.slewing, 5.0)
            # The poller goes on after the abort (its poll may be the one that waited for it).
            await eventually(lambda: r.driver.poller.polls > polls)
        assert state.tracking is TrackingMode.OFF


async def test_set_site_moves_only_the_pc_side_altaz(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        r.point(45.0, 90.0)
        before = await r.driver.refresh()
        sent = r.driver.line.statistics.commands_sent
        elsewhere = Site(latitude_deg=-30.0, longitude_deg=11.0, pressure_hpa=0.0)
        await r.driver.set_site(elsewhere)
        assert r.driver.line.statistics.commands_sent == sent  # the box keeps no site
        assert r.driver.site == elsewhere
        after = r.driver.state
        assert after.ra_j2000_hours == before.ra_j2000_hours
        assert after.alt_deg is not None
        assert before.alt_deg is not None
        assert abs(after.alt_deg - before.alt_deg) > 10.0


async def test_polls_during_a_goto_do_not_flood_the_line(tmp_path: Path, transport: str) -> None:
    async with rig(tmp_path, transport) as r:
        await r.driver.goto_equatorial(*sky_at(r.sim, 60.0, 200.0))
        async with r.driver.watching():
            await asyncio.sleep(0.5)
            polls = r.driver.poller.polls
        # One status byte every 50 ms (~10), not hundreds; at least one however loaded the machine.
        assert 1 <= polls <= 0.5 / 0.05 + 2
        assert r.driver.state.slewing
