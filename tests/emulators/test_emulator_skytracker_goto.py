"""GOTO, abort, tracking and utility slews of the emulated Sky Tracker, on a stepped clock."""

from __future__ import annotations

from pathlib import Path

import pytest

from scopelink.astro import j2000_to_observed
from scopelink.protocol.skytracker import (
    Acknowledge,
    BusAnswer,
    Direction,
    LoadObject,
    PositionReply,
    PressDirection,
    ReadPosition,
    ReadStatus,
    ReleaseBus,
    ReleaseDirections,
    RequestBus,
    SelectMode,
    StatusReply,
    TrackerMode,
)
from scopelink.servers.skytracker.tracker import UTILITY_RATE_DEG_S
from tests.support.skytracker_emulator import SITE, PcSession, pty_client, running_tracker

# 08:00 UTC on 1 Jan 2026 at 11° E: Capella (5.278 h, +45.998°) is high in the north-west.
TARGET = (5.278, 45.998)


async def status_byte(pc: PcSession) -> int:
    reply = await pc.send(ReadStatus())
    assert isinstance(reply, StatusReply)
    return reply.status.to_byte()


async def upload_and_go(pc: PcSession) -> None:
    """The spec's first operating example: Q, L99 ..., A, q, G."""
    assert (await pc.send(RequestBus())) == BusAnswer(granted=True)
    assert (await pc.send(LoadObject.current(*TARGET))) == Acknowledge()
    await pc.send(ReleaseBus())
    await pc.send(SelectMode(TrackerMode.GOTO))
    assert await status_byte(pc) == 0x10  # GOTO (and G has been read: it has no reply)


async def position(pc: PcSession) -> PositionReply:
    assert (await pc.send(RequestBus())) == BusAnswer(granted=True)
    reply = await pc.send(ReadPosition())
    await pc.send(ReleaseBus())
    assert isinstance(reply, PositionReply)
    return reply


async def test_goto_lands_on_the_object_and_tracks(tmp_path: Path) -> None:
    async with running_tracker(tmp_path) as emulator, pty_client(emulator) as link:
        pc = PcSession(link)
        await upload_and_go(pc)
        assert (await pc.send(RequestBus())) == BusAnswer(granted=False)  # NUL during GOTO
        await emulator.tracker.run_for(60.0)
        assert emulator.mount.axes[0].is_moving  # the sky moves on: tracking
        assert await status_byte(pc) == 0x00  # TRACK
        landed = await position(pc)
        assert landed.ra_hours == pytest.approx(TARGET[0], abs=0.0011)
        assert landed.dec_degrees == pytest.approx(TARGET[1], abs=0.0011)
        await emulator.tracker.run_for(120.0)  # tracking keeps it there
        tracked = await position(pc)
        assert tracked.ra_hours == pytest.approx(TARGET[0], abs=0.0011)
        assert tracked.dec_degrees == pytest.approx(TARGET[1], abs=0.0011)


@pytest.mark.parametrize("abort", ["U", "T", "D", "B"])
async def test_goto_abort_ramps_down_to_utility(tmp_path: Path, abort: str) -> None:
    async with running_tracker(tmp_path) as emulator, pty_client(emulator) as link:
        pc = PcSession(link)
        await upload_and_go(pc)
        await emulator.tracker.run_for(3.0)  # under way at full speed
        azimuth, altitude = emulator.mount.axes
        assert max(abs(azimuth.rate), abs(altitude.rate)) > 1.0
        await pc.send(SelectMode(TrackerMode(abort)))
        assert await status_byte(pc) == 0x80  # UTIL
        rates = max(abs(azimuth.rate), abs(altitude.rate))
        assert rates > 0.5  # still ramping down, not stopped dead
        await emulator.tracker.run_for(3.0)
        assert azimuth.rate == altitude.rate == 0.0
        assert (await pc.send(RequestBus())) == BusAnswer(granted=True)
        await pc.send(ReleaseBus())


async def test_utility_arrows_slew_at_four_degrees_per_second(tmp_path: Path) -> None:
    async with running_tracker(tmp_path) as emulator, pty_client(emulator) as link:
        pc = PcSession(link)
        await pc.send(PressDirection(Direction.UP))
        await pc.send(PressDirection(Direction.LEFT))
        assert await status_byte(pc) == 0x80 | 0x08 | 0x02
        await emulator.tracker.run_for(5.0)
        azimuth, altitude = emulator.mount.axes
        assert altitude.rate == pytest.approx(UTILITY_RATE_DEG_S)
        assert azimuth.rate == pytest.approx(-UTILITY_RATE_DEG_S)  # left: counter-clockwise
        await pc.send(ReleaseDirections())
        assert await status_byte(pc) == 0x80
        await emulator.tracker.run_for(5.0)
        assert altitude.rate == azimuth.rate == 0.0


async def test_track_and_guide_arrows_add_to_the_track_rate(tmp_path: Path) -> None:
    async with running_tracker(tmp_path) as emulator, pty_client(emulator) as link:
        pc = PcSession(link)
        emulator.tracker.altitude.slew_to(40.0)
        emulator.tracker.azimuth.slew_to(100.0)
        await emulator.tracker.run_for(40.0)
        await pc.send(SelectMode(TrackerMode.TRACK))
        assert await status_byte(pc) == 0x00
        await emulator.tracker.run_for(1.0)
        altitude = emulator.mount.axes[1]
        base = altitude.rate
        assert base != 0.0
        await pc.send(PressDirection(Direction.UP))
        await status_byte(pc)
        await emulator.tracker.run_for(0.5)  # the rate change ramps at the axis' acceleration
        assert altitude.rate == pytest.approx(base + 8.0 / 60.0, abs=1e-3)
        await pc.send(SelectMode(TrackerMode.GUIDE))
        await status_byte(pc)
        await emulator.tracker.run_for(0.5)  # the rate change ramps at the axis' acceleration
        assert altitude.rate == pytest.approx(base + 120.0 / 3600.0, abs=1e-4)
        await pc.send(ReleaseDirections())
        await status_byte(pc)
        await emulator.tracker.run_for(0.5)  # the rate change ramps at the axis' acceleration
        assert altitude.rate == pytest.approx(base, abs=1e-4)


async def test_tracking_follows_the_sky(tmp_path: Path) -> None:
    async with running_tracker(tmp_path) as emulator:
        tracker = emulator.tracker
        tracker.altitude.slew_to(30.0)
        tracker.azimuth.slew_to(200.0)
        await tracker.run_for(60.0)
        mount = emulator.mount
        start = mount.j2000_at(mount.clock.elapsed())
        tracker.select_mode(TrackerMode.TRACK)
        await tracker.run_for(120.0)
        ra, dec = mount.j2000_at(mount.clock.elapsed())
        assert ra == pytest.approx(start[0], abs=2e-4)
        assert dec == pytest.approx(start[1], abs=3e-3)
        alt, _ = j2000_to_observed(ra, dec, mount.clock.now(), SITE)
        assert alt == pytest.approx(mount.axes[1].position, abs=1e-6)
