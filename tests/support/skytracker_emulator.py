"""Helpers for the Sky Tracker / Sky Commander emulator tests: a PC session over a real link."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from scopelink.astro import Site
from scopelink.links import Link, open_serial
from scopelink.protocol.skytracker import (
    NEED_DATA,
    CommanderClient,
    CommanderCommand,
    Reply,
    TrackerClient,
    TrackerCommand,
)
from scopelink.protocol.skytracker.wire import BadReply, StrayByte
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.sim import SKY_TRACKER, SimClock, SimulatedMount

SITE = Site(latitude_deg=48.0, longitude_deg=11.0, pressure_hpa=0.0)
REPLY_TIMEOUT_S = 2.0


def sky_tracker_mount(clock: SimClock | None = None) -> SimulatedMount:
    """The Sky Tracker alt-az preset on a stepped clock, pointing level at the north."""
    return SimulatedMount(SKY_TRACKER, site=SITE, clock=clock or SimClock.stepped())


class PcSession:
    """Our own codec client on a link, one command at a time, replies read by length."""

    def __init__(self, link: Link) -> None:
        self.link = link
        self.client = TrackerClient()

    async def send(self, command: TrackerCommand | CommanderCommand) -> Reply | None:
        """Send ``command``; return its reply (None for a command without one)."""
        await self.link.write(self.client.send(command))
        if command.reply is None:
            return None
        return await self.reply()

    async def reply(self) -> Reply:
        async with asyncio.timeout(REPLY_TIMEOUT_S):
            while (event := self.client.next_event()) is NEED_DATA:
                self.client.receive_data(await self.link.read())
        assert not isinstance(event, (BadReply, StrayByte)), event
        assert isinstance(event, Reply)
        return event


class CommanderSession:
    """CommanderClient on a link (the Sky Commander alone on its port)."""

    def __init__(self, link: Link) -> None:
        self.link = link
        self.client = CommanderClient()

    async def send(self, command: CommanderCommand) -> Reply | None:
        await self.link.write(self.client.send(command))
        if command.reply is None:
            return None
        async with asyncio.timeout(REPLY_TIMEOUT_S):
            while (event := self.client.next_event()) is NEED_DATA:
                self.client.receive_data(await self.link.read())
        assert isinstance(event, Reply), event
        return event


@asynccontextmanager
async def pty_client(
    emulator: SkyTrackerEmulator, *, stopbits: float = 2, baudrate: int = 9600
) -> AsyncIterator[Link]:
    """A pty served by ``emulator`` and our serial link on its other end (8N2 by default)."""
    path = await emulator.on_pty()
    link = await open_serial(path, baudrate=baudrate, stopbits=stopbits)
    try:
        yield link
    finally:
        await link.close()


@asynccontextmanager
async def running_tracker(
    data_dir: Path, mount: SimulatedMount | None = None, *, strict_line: bool = False
) -> AsyncIterator[SkyTrackerEmulator]:
    async with SkyTrackerEmulator(
        mount or sky_tracker_mount(), data_dir, strict_line=strict_line
    ) as emulator:
        yield emulator
