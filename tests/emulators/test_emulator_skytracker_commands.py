"""The Sky Tracker emulator answers every command of the spec, over a real pty and TCP."""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

import pytest

from scopelink.links import Link, open_tcp
from scopelink.protocol.skytracker import (
    Acknowledge,
    BusAnswer,
    CalibrationReply,
    Direction,
    GuideSpeedReply,
    LoadObject,
    OffsetsReply,
    PositionReply,
    PressDirection,
    RatesReply,
    ReadCalibration,
    ReadGuideSpeed,
    ReadOffsets,
    ReadPosition,
    ReadRates,
    ReadStatus,
    ReadVersion,
    Realign,
    ReleaseBus,
    ReleaseDirections,
    RequestBus,
    SelectMode,
    SetCalibration,
    SetGuideSpeed,
    StatusReply,
    TrackerMode,
    VersionReply,
)
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.servers.skytracker.tracker import DEFAULT_CALIBRATION
from tests.support.skytracker_emulator import PcSession, pty_client, running_tracker

TRANSPORTS = ("pty", "tcp")


@asynccontextmanager
async def connected(emulator: SkyTrackerEmulator, transport: str) -> AsyncIterator[PcSession]:
    if transport == "pty":
        async with pty_client(emulator) as link:
            yield PcSession(link)
        return
    host, port = await emulator.on_tcp()
    tcp_link: Link = await open_tcp(host, port)
    try:
        yield PcSession(tcp_link)
    finally:
        await tcp_link.close()


async def status(pc: PcSession) -> StatusReply:
    reply = await pc.send(ReadStatus())
    assert isinstance(reply, StatusReply)
    return reply


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_version_calibration_and_guide_speed(tmp_path: Path, transport: str) -> None:
    async with running_tracker(tmp_path) as emulator, connected(emulator, transport) as pc:
        version = await pc.send(ReadVersion())
        assert version == VersionReply("v4.0    ")
        assert (await pc.send(ReadGuideSpeed())) == GuideSpeedReply(120, 120)
        assert await pc.send(SetGuideSpeed(10, 255)) is None
        assert (await pc.send(ReadGuideSpeed())) == GuideSpeedReply(10, 255)
        calibration = await pc.send(ReadCalibration())
        assert calibration == CalibrationReply(
            DEFAULT_CALIBRATION.azimuth_factor, DEFAULT_CALIBRATION.elevation_factor
        )


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_modes_and_buttons_set_the_status_bits(tmp_path: Path, transport: str) -> None:
    expected = {
        TrackerMode.UTILITY: 0x80,
        TrackerMode.TRACK: 0x00,
        TrackerMode.GUIDE: 0x20,
        TrackerMode.STANDBY: 0x40,
    }
    async with running_tracker(tmp_path) as emulator, connected(emulator, transport) as pc:
        assert (await status(pc)).status.to_byte() == 0x80  # power-on: UTIL
        for mode, byte in expected.items():
            await pc.send(SelectMode(mode))
            assert (await status(pc)).status.to_byte() == byte
        await pc.send(SelectMode(TrackerMode.UTILITY))
        await pc.send(PressDirection(Direction.UP))
        await pc.send(PressDirection(Direction.LEFT))
        assert (await status(pc)).status.to_byte() == 0x80 | 0x08 | 0x02
        await pc.send(PressDirection(Direction.DOWN))  # cancels up
        await pc.send(PressDirection(Direction.RIGHT))  # cancels left
        assert (await status(pc)).status.to_byte() == 0x80 | 0x04 | 0x01
        await pc.send(ReleaseDirections())
        emulator.tracker.handbox.press(Direction.UP)
        assert (await status(pc)).status.to_byte() == 0x80 | 0x08
        emulator.tracker.handbox.release()
        assert (await status(pc)).status.to_byte() == 0x80


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_bus_relays_sky_commander_commands_and_q_is_not_relayed(
    tmp_path: Path, transport: str
) -> None:
    async with running_tracker(tmp_path) as emulator, connected(emulator, transport) as pc:
        started = time.monotonic()
        assert (await pc.send(RequestBus())) == BusAnswer(granted=True)
        # At once (a few ms), not after the box's exchange timeout or its next tick (0.5 s);
        # 0.4, not the spec's 0.1: a loaded machine's stall is not the emulator's.
        assert time.monotonic() - started < 0.4
        position = await pc.send(ReadPosition())
        assert isinstance(position, PositionReply)
        expected_ra, expected_dec = emulator.mount.j2000_at(emulator.mount.clock.elapsed())
        assert position.ra_hours == pytest.approx(expected_ra, abs=0.0006)
        assert position.dec_degrees == pytest.approx(expected_dec, abs=0.0006)
        assert (await pc.send(LoadObject.current(5.5, 20.0))) == Acknowledge()
        assert isinstance(await pc.send(ReadOffsets()), OffsetsReply)
        assert isinstance(await pc.send(ReadRates()), RatesReply)
        await pc.send(ReleaseBus())
        # 'q' was not relayed: the next 'R' is the Sky Tracker's status, not the drive rates.
        assert (await status(pc)).status.to_byte() == 0x80
        assert emulator.commander.current_object is not None
        assert emulator.commander.current_object.ra_hours == 5.5


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_calibration_only_as_first_command_and_persisted(
    tmp_path: Path, transport: str
) -> None:
    async with running_tracker(tmp_path) as emulator, connected(emulator, transport) as pc:
        assert (await pc.send(SetCalibration(16000.0, 40000.0))) == Acknowledge()
        assert (await pc.send(ReadCalibration())) == CalibrationReply(16000.0, 40000.0)
        # Second S: refused without a reply (the codec client would wait for 'A').
        await pc.link.write(SetCalibration(1.0, 2.0).encode())
        with pytest.raises(TimeoutError):
            async with asyncio.timeout(0.3):
                await pc.link.read()
        assert (await pc.send(ReadCalibration())) == CalibrationReply(16000.0, 40000.0)
    async with running_tracker(tmp_path) as emulator, connected(emulator, transport) as pc:
        assert (await pc.send(ReadCalibration())) == CalibrationReply(16000.0, 40000.0)
        await pc.link.write(SetCalibration(1.0, 2.0).encode())  # not the first command any more
        assert (await pc.send(ReadCalibration())) == CalibrationReply(16000.0, 40000.0)


async def test_realign_example_moves_the_reported_position(tmp_path: Path) -> None:
    async with running_tracker(tmp_path) as emulator, connected(emulator, "pty") as pc:
        assert (await pc.send(RequestBus())) == BusAnswer(granted=True)
        assert (await pc.send(LoadObject.current(12.345, 67.890))) == Acknowledge()
        await pc.send(Realign())
        await pc.send(ReleaseBus())
        assert (await pc.send(RequestBus())) == BusAnswer(granted=True)
        position = await pc.send(ReadPosition())
        await pc.send(ReleaseBus())
        assert position == PositionReply(12.345, 67.890)
        assert emulator.commander.aligned
