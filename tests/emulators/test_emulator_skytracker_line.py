"""Line fidelity of the Sky Tracker's PC port: 9600 only, and 8N2 spacing in strict mode."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from scopelink.links import LineSettings, open_tcp, paced
from scopelink.protocol.skytracker import (
    BusAnswer,
    LoadObject,
    ReadStatus,
    ReleaseBus,
    RequestBus,
    StatusReply,
)
from scopelink.servers.skytracker import StrictReceiver, resample
from scopelink.servers.skytracker.line import DEVICE_LINE
from tests.support.skytracker_emulator import PcSession, pty_client, running_tracker

LINE = LoadObject.current(12.345, 67.890)


def test_resample_at_the_same_rate_keeps_bytes_and_a_wrong_rate_garbles_them() -> None:
    data = bytes(range(256))
    assert resample(data, LineSettings(9600, 8, "N", 2), DEVICE_LINE) == data
    garbled = resample(b"V", LineSettings(4800, 8, "N", 1), DEVICE_LINE)
    assert garbled != b"V"
    assert resample(b"V", LineSettings(19200, 8, "N", 1), DEVICE_LINE) != b"V"
    seven_bit = resample(b"V", LineSettings(9600, 7, "N", 1), DEVICE_LINE)
    assert seven_bit == bytes([ord("V") | 0x80])  # the stop bit lands in bit 7


def test_strict_receiver_model() -> None:
    eight_n_one, eight_n_two = LineSettings(9600, 8, "N", 1), LineSettings(9600, 8, "N", 2)
    assert StrictReceiver().receive(b"L99", 1.0, eight_n_one) == b"L"  # a back-to-back burst
    assert StrictReceiver().receive(b"L99", 1.0, eight_n_two) == b"L99"
    receiver = StrictReceiver()
    assert [receiver.receive(b"x", 1.0 + 0.002 * k, eight_n_one) for k in range(3)] == [b"x"] * 3
    unknown = StrictReceiver(jitter_allowance_s=0.005)
    assert unknown.receive(LINE.encode(), 1.0, None) == LINE.encode()[:5]
    spaced = StrictReceiver(jitter_allowance_s=0.005)
    kept = [spaced.receive(bytes([b]), 1.0 + k * 11 / 9600, None) for k, b in enumerate(b"abc")]
    assert b"".join(kept) == b"abc"


async def bus_exchange_loses_characters(pc: PcSession) -> bool:
    """Send the L99 line inside a bus grant; True if the Sky Commander did not acknowledge."""
    assert (await pc.send(RequestBus())) == BusAnswer(granted=True)
    await pc.link.write(LINE.encode())
    try:
        async with asyncio.timeout(0.5):
            acknowledged = await pc.link.read(1) == b"A"
    except TimeoutError:
        acknowledged = False
    # Finish any partial line the Sky Commander holds, then release the bus.
    await pc.link.write(b"\r")
    await asyncio.sleep(0.05)
    await pc.link.drain_input(quiet_seconds=0.05)
    await pc.link.write(ReleaseBus().encode())
    pc.client = type(pc.client)()
    return not acknowledged


async def test_pty_8n1_burst_loses_characters_and_8n2_does_not(tmp_path: Path) -> None:
    async with running_tracker(tmp_path, strict_line=True) as emulator:
        async with pty_client(emulator, stopbits=1) as link:
            assert await bus_exchange_loses_characters(PcSession(link))
            assert emulator.commander.current_object is None
        async with pty_client(emulator, stopbits=2) as link:
            assert not await bus_exchange_loses_characters(PcSession(link))
            assert emulator.commander.current_object is not None


async def test_tcp_fast_burst_loses_characters_and_8n2_paced_does_not(tmp_path: Path) -> None:
    async with running_tracker(tmp_path, strict_line=True) as emulator:
        host, port = await emulator.on_tcp()
        async with await open_tcp(host, port) as link:
            assert await bus_exchange_loses_characters(PcSession(link))
        assert emulator.commander.current_object is None
        async with paced(await open_tcp(host, port), 9600, 11) as link:
            assert not await bus_exchange_loses_characters(PcSession(link))
        assert emulator.commander.current_object is not None


@pytest.mark.parametrize("baudrate", [4800, 19200])
async def test_wrong_baud_rate_garbles_commands(tmp_path: Path, baudrate: int) -> None:
    async with running_tracker(tmp_path) as emulator:
        async with pty_client(emulator, baudrate=baudrate) as link:
            await link.write(ReadStatus().encode())
            await asyncio.sleep(0.2)
            garbled = await link.drain_input(quiet_seconds=0.05)
            assert garbled != b"\x80"
        async with pty_client(emulator) as link:
            reply = await PcSession(link).send(ReadStatus())
            assert isinstance(reply, StatusReply)
            assert reply.status.to_byte() == 0x80
