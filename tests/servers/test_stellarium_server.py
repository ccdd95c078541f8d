"""The Stellarium server over real TCP sockets in front of the simulated mount."""

from __future__ import annotations

import asyncio
import logging
import struct
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime

import pytest

from scopelink.astro import (
    Site,
    angular_separation_deg,
    j2000_to_apparent,
    observed_to_j2000,
)
from scopelink.protocol.stellarium import (
    NEED_DATA,
    CurrentPosition,
    GotoMessage,
    StellariumClientConnection,
)
from scopelink.servers.stellarium import Equinox, StellariumServer
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(48.2, 16.4)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)
TOLERANCE_DEG = 0.01


def simulated_mount(rate: float = 30.0) -> SimulatedMount:
    return SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=rate))


class Client:
    """What Stellarium does: gotos out, positions in, over one TCP connection."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader = reader
        self.writer = writer
        self.codec = StellariumClientConnection()

    async def goto(self, ra_hours: float, dec_deg: float) -> None:
        self.writer.write(self.codec.send(GotoMessage.from_degrees(ra_hours, dec_deg)))
        await self.writer.drain()

    async def position(self, timeout_s: float = 5.0) -> CurrentPosition:
        async with asyncio.timeout(timeout_s):
            while True:
                event = self.codec.next_event()
                if isinstance(event, CurrentPosition):
                    return event
                assert event is NEED_DATA, event
                data = await self.reader.read(4096)
                if not data:
                    raise ConnectionResetError("server closed the connection")
                self.codec.receive_data(data)

    async def latest_position(self) -> CurrentPosition:
        """A position sent after this call: those already buffered arrive at once and are
        skipped."""
        started = time.monotonic()
        while True:
            position = await self.position()
            if time.monotonic() - started > 0.05:
                return position

    async def read_until_closed(self) -> None:
        """Read positions until the server hangs up (ConnectionResetError)."""
        for _ in range(100):
            await self.position()

    async def close(self) -> None:
        self.writer.close()
        await self.writer.wait_closed()


@asynccontextmanager
async def client_of(server: StellariumServer) -> AsyncIterator[Client]:
    reader, writer = await asyncio.open_connection("127.0.0.1", server.port)
    client = Client(reader, writer)
    try:
        yield client
    finally:
        await client.close()


def separation(ra1: float, dec1: float, ra2: float, dec2: float) -> float:
    return angular_separation_deg(ra1 * 15.0, dec1, ra2 * 15.0, dec2)


def up_in_the_south(mount: SimulatedMount, alt_deg: float = 50.0) -> tuple[float, float]:
    return observed_to_j2000(alt_deg, 180.0, mount.now(), mount.site)


async def test_positions_flow_at_the_interval_and_match_the_mount() -> None:
    mount = simulated_mount(rate=1.0)
    async with StellariumServer(mount, port=0, interval_s=0.1) as server, client_of(server) as c:
        assert server.port != 0
        first = await c.position()
        started = time.monotonic()
        for _ in range(5):
            position = await c.position()
        elapsed = time.monotonic() - started
        assert 0.3 < elapsed < 2.0  # five messages 0.1 s apart, with room for a busy CPU
        state = mount.state
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        assert position.status == 0
        assert (
            separation(
                position.ra_hours, position.dec_deg, state.ra_j2000_hours, state.dec_j2000_deg
            )
            < TOLERANCE_DEG
        )
        assert abs(first.server_time_us / 1e6 - START.timestamp()) < 60


async def test_goto_in_j2000_slews_the_mount_there() -> None:
    mount = simulated_mount()
    async with StellariumServer(mount, port=0, interval_s=0.1) as server, client_of(server) as c:
        ra, dec = up_in_the_south(mount)
        await c.goto(ra, dec)
        await asyncio.sleep(0.3)
        assert mount.state.slewing
        await mount.wait_for(lambda s: not s.slewing, timeout_s=15)
        position = await c.latest_position()
        assert separation(position.ra_hours, position.dec_deg, ra, dec) < TOLERANCE_DEG
        state = mount.snapshot()
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        assert separation(state.ra_j2000_hours, state.dec_j2000_deg, ra, dec) < TOLERANCE_DEG


async def test_jnow_frame_converts_both_ways() -> None:
    mount = simulated_mount()
    async with (
        StellariumServer(mount, port=0, interval_s=0.1, frame=Equinox.JNOW) as server,
        client_of(server) as c,
    ):
        ra, dec = up_in_the_south(mount, 40.0)
        jnow = j2000_to_apparent(ra, dec, mount.now())
        # Precession since 2000 moves the place by far more than the tolerance.
        assert separation(*jnow, ra, dec) > 0.2
        await c.goto(*jnow)
        await asyncio.sleep(0.3)
        await mount.wait_for(lambda s: not s.slewing, timeout_s=15)
        state = mount.snapshot()
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        assert separation(state.ra_j2000_hours, state.dec_j2000_deg, ra, dec) < TOLERANCE_DEG
        position = await c.latest_position()
        assert separation(position.ra_hours, position.dec_deg, *jnow) < TOLERANCE_DEG


async def test_a_goto_below_the_horizon_is_refused_and_nothing_moves(
    caplog: pytest.LogCaptureFixture,
) -> None:
    mount = simulated_mount()
    async with StellariumServer(mount, port=0, interval_s=0.1) as server, client_of(server) as c:
        before = mount.snapshot()
        ra, dec = observed_to_j2000(-20.0, 0.0, mount.now(), mount.site)
        with caplog.at_level(logging.WARNING, logger="scopelink.servers.stellarium"):
            await c.goto(ra, dec)
            await c.position()
            await c.position()
        assert "below the configured horizon" in caplog.text
        assert not mount.snapshot().slewing
        assert mount.target is None
        assert before.alt_deg is not None
        after = mount.snapshot()
        assert after.alt_deg is not None
        assert after.az_deg is not None
        assert before.az_deg is not None
        assert abs(after.alt_deg - before.alt_deg) < 0.5


async def test_several_clients_at_once_and_a_bad_one_is_dropped_alone(
    caplog: pytest.LogCaptureFixture,
) -> None:
    mount = simulated_mount()
    async with (
        StellariumServer(mount, port=0, interval_s=0.1) as server,
        client_of(server) as first,
        client_of(server) as second,
        client_of(server) as bad,
    ):
        await first.position()
        await second.position()
        await bad.position()
        assert server.clients == 3
        with caplog.at_level(logging.WARNING, logger="scopelink.servers.stellarium"):
            bad.writer.write(struct.pack("<HH", 2, 0) + b"garbage")
            await bad.writer.drain()
            with pytest.raises(ConnectionResetError):
                await bad.read_until_closed()
        assert "impossible message length 2" in caplog.text
        assert server.clients == 2
        # The others carry on, and a goto from one is seen by both.
        ra, dec = up_in_the_south(mount, 60.0)
        await second.goto(ra, dec)
        await asyncio.sleep(0.3)
        await mount.wait_for(lambda s: not s.slewing, timeout_s=15)
        for client in (first, second):
            position = await client.latest_position()
            assert separation(position.ra_hours, position.dec_deg, ra, dec) < TOLERANCE_DEG


async def test_unknown_messages_are_skipped_and_partial_gotos_wait_for_the_rest() -> None:
    mount = simulated_mount()
    async with StellariumServer(mount, port=0, interval_s=0.1) as server, client_of(server) as c:
        ra, dec = up_in_the_south(mount, 45.0)
        frame = GotoMessage.from_degrees(ra, dec).encode()
        c.writer.write(struct.pack("<HH", 8, 3) + b"\x01\x02\x03\x04" + frame[:7])
        await c.writer.drain()
        await asyncio.sleep(0.3)
        assert not mount.state.slewing
        c.writer.write(frame[7:])
        await c.writer.drain()
        await mount.wait_for(lambda s: s.slewing, timeout_s=5)
        await mount.wait_for(lambda s: not s.slewing, timeout_s=15)
        position = await c.latest_position()
        assert separation(position.ra_hours, position.dec_deg, ra, dec) < TOLERANCE_DEG
        assert server.clients == 1


def test_the_interval_is_checked() -> None:
    with pytest.raises(ValueError, match="interval"):
        StellariumServer(simulated_mount(), interval_s=0.0)
