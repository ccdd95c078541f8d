"""The planetarium and dashboard clients, on the package's codecs: LX200 (SkySafari-like),
Stellarium, SynScan, dashboard pages; each reconnects all night."""

from __future__ import annotations

import asyncio
import contextlib
import random
from collections.abc import Awaitable, Callable
from datetime import datetime

import aiohttp

from bench.soak.config import COMMAND_BOUND_S, READ_BOUND_S, STREAM_GAP_BOUND_S
from bench.soak.night import Night
from bench.soak.targets import random_target
from scopelink.links import LinkError, open_tcp
from scopelink.protocol import lx200, stellarium
from scopelink.protocol.synscan import (
    NEED_DATA,
    AnyReply,
    GetRaDec,
    Position,
    SynScanClientConnection,
)


class LX200Session:
    """SkySafari's end of one LX200 connection, on the codec's client connection: each command
    encoded by it, and its reply cut by the shape the codec gives the command."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self._reader = reader
        self._writer = writer
        self._connection = lx200.LX200ClientConnection()

    def send(self, command: lx200.AnyCommand) -> str:
        """Send ``command``; its text (``:GR#``), which names the request in the records."""
        frame = self._connection.send(command)
        self._writer.write(frame)
        return frame.decode("ascii")

    async def read(self, command: lx200.AnyCommand) -> bytes:
        """The reply to ``command`` (sent before the reply of any later command is read)."""
        while (event := self._connection.next_event()) is lx200.NEED_DATA:
            data = await self._reader.read(_LX200_READ_SIZE)
            if not data:
                raise EOFError("the LX200 server closed the connection")
            self._connection.receive_data(data)
        if not isinstance(event, lx200.LX200Reply) or event.command != command:
            raise ValueError(event.describe())
        return event.data

    async def close(self) -> None:
        self._writer.close()
        with contextlib.suppress(OSError):
            await self._writer.wait_closed()


_LX200_READ_SIZE = 256
_POLLS = (lx200.Get(lx200.Query.RA), lx200.Get(lx200.Query.DEC))
_HALT = lx200.Halt()


async def lx200_client(port: int, night: Night, chance: random.Random, period_s: float) -> None:
    """SkySafari-like: :GR#/:GD# polling, now and then a goto (:Sr :Sd :MS#) or :Q#; one
    connection of 20-40 s."""
    session = LX200Session(*await asyncio.open_connection("127.0.0.1", port))
    night.reconnects["lx200"] += 1
    try:
        connected_until = night.now() + chance.uniform(20.0, 40.0)
        behind_a_command = False
        while night.now() < connected_until:
            for command in _POLLS:
                what = session.send(command)
                work = session.read(command)
                if behind_a_command:
                    # LX200 answers in order: this read waits for the :Q# before it to reach
                    # the device (through any fault)
                    await night.timed("lx200", f"{what} after :Q#", COMMAND_BOUND_S, work)
                else:
                    await night.timed("lx200", what, READ_BOUND_S, work)
            behind_a_command = False
            roll = chance.random()
            if roll < 0.03:
                await _lx200_goto(session, night, chance)
            elif roll < 0.04:
                night.moved("LX200 :Q#")
                session.send(_HALT)  # no reply
                night.of("lx200").count += 1
                behind_a_command = True
            await asyncio.sleep(period_s)
    finally:
        await session.close()


async def _lx200_goto(session: LX200Session, night: Night, chance: random.Random) -> None:
    target = random_target(chance)
    for command in (
        lx200.SetTargetRA(target.ra_of_date_hours),
        lx200.SetTargetDec(target.dec_of_date_deg),
    ):
        code = session.send(command)[:3]
        accepted = await night.timed("lx200", code, READ_BOUND_S, session.read(command))
        if accepted != lx200.boolean_reply(True):
            night.answered_error("lx200", f"{code} refused")
    night.moved("LX200 :MS#")
    goto = lx200.GotoTarget()
    what = session.send(goto)
    reply = await night.timed("lx200", what, COMMAND_BOUND_S, session.read(goto))
    if reply != lx200.slew_reply(None):
        night.answered_error("lx200", f"{what} {reply.decode(errors='replace')}")
    else:
        night.slews += 1


async def stellarium_client(port: int, night: Night, chance: random.Random, *, gotos: bool) -> None:
    """Reads the position stream (a message every 0.5 s), framed by the codec's client
    connection; with ``gotos`` sends a goto now and then; one connection of 20-40 s. A message
    that is no position is an answered error; a stream that cannot be framed ends the
    connection."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    night.reconnects["stellarium"] += 1
    connection = stellarium.StellariumClientConnection()

    async def next_message() -> (
        stellarium.CurrentPosition | stellarium.SkippedMessage | stellarium.BadLength
    ):
        while (event := connection.next_event()) is stellarium.NEED_DATA:
            data = await reader.read(_STELLARIUM_READ_SIZE)
            if not data:
                raise EOFError("the Stellarium server closed the connection")
            connection.receive_data(data)
        return event

    try:
        connected_until = night.now() + chance.uniform(20.0, 40.0)
        last = night.now()
        while night.now() < connected_until:
            message = await night.timed(
                "stellarium", "position", STREAM_GAP_BOUND_S, next_message()
            )
            if not isinstance(message, stellarium.CurrentPosition):
                night.answered_error("stellarium", message.describe())
                if connection.broken:
                    break
            night.stream_gaps.append(night.now() - last)
            last = night.now()
            if gotos and chance.random() < 0.04:
                target = random_target(chance)
                goto = stellarium.GotoMessage.from_degrees(
                    target.ra_j2000_hours, target.dec_j2000_deg
                )
                night.moved("Stellarium goto")
                writer.write(connection.send(goto))
                night.of("stellarium").count += 1
    finally:
        writer.close()
        with contextlib.suppress(OSError):
            await writer.wait_closed()


_STELLARIUM_READ_SIZE = 4096


async def synscan_client(port: int, night: Night, period_s: float) -> None:
    """A planetarium on our SynScan server: ``e`` polls; one connection of 30 s."""
    async with await open_tcp("127.0.0.1", port) as link:
        night.reconnects["synscan"] += 1
        client = SynScanClientConnection()
        connected_until = night.now() + 30.0
        while night.now() < connected_until:
            await link.write(client.send(GetRaDec(precise=True)))

            async def reply(client: SynScanClientConnection = client) -> object:
                while (event := client.next_event()) is NEED_DATA:
                    client.receive_data(await link.read())
                return event

            event = await night.timed("synscan", "e", READ_BOUND_S, reply())
            if not isinstance(event, Position):
                night.answered_error("synscan", type(event).__name__)
                if not isinstance(event, AnyReply):
                    break
            await asyncio.sleep(period_s)


async def dashboard_observer(session: aiohttp.ClientSession, port: int, night: Night) -> None:
    """A dashboard page: every update's read_at (the poller's pulse) and slewing flag."""
    async with session.ws_connect(f"http://127.0.0.1:{port}/ws") as ws:
        night.reconnects["dashboard"] += 1
        last_read_at = ""
        async for message in ws:
            if message.type is not aiohttp.WSMsgType.TEXT:
                break
            night.of("dashboard").count += 1
            state = message.json().get("state")
            if state is None:
                continue
            if state["read_at"] != last_read_at:
                last_read_at = state["read_at"]
                night.reading_advances.append(night.at(datetime.fromisoformat(last_read_at)))
            night.slewing_samples.append((night.now(), bool(state["slewing"])))
            problems = [str(problem) for problem in state["problems"]]
            failed = any("poll failed" in problem for problem in problems)
            night.poll_failed_samples.append((night.now(), failed))
            night.last_problems = problems
    night.broken.append(f"dashboard page closed by the server at {night.now():.1f} s")


async def first_page(session: aiohttp.ClientSession, port: int) -> float:
    """Seconds from opening a dashboard page to its hello (serve's first page is cold)."""
    start = asyncio.get_running_loop().time()
    async with session.ws_connect(f"http://127.0.0.1:{port}/ws") as ws:
        await ws.receive()
        return asyncio.get_running_loop().time() - start


async def dashboard_churn(session: aiohttp.ClientSession, port: int, night: Night) -> None:
    """A page opened and closed again: a hello and a few updates, then 3 s away."""
    async with session.ws_connect(f"http://127.0.0.1:{port}/ws") as ws:
        night.reconnects["dashboard"] += 1
        for _ in range(3):
            await night.timed("dashboard", "update", READ_BOUND_S, ws.receive())
            night.of("dashboard").count += 1
    await asyncio.sleep(3.0)


async def reconnecting(
    protocol: str, night: Night, connection: Callable[[], Awaitable[None]]
) -> None:
    """One client connection after another, as long as the night lasts. A connection that
    breaks (or whose replies go out of step: ValueError) is recorded (a late reply already is, by
    :meth:`Night.timed`) and replaced."""
    while True:
        try:
            await connection()
        except TimeoutError:
            pass  # a reply came too late: recorded; a new connection starts from a clean stream
        except (OSError, EOFError, ValueError, LinkError, aiohttp.ClientError) as error:
            night.broken.append(f"{protocol} at {night.now():.1f} s: {error!r}")
        await asyncio.sleep(0.2)
