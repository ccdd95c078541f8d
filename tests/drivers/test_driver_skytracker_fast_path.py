"""The Sky Tracker line's fast path (one call writes a command and sets up its reply's reader, the
reply parsed in the transport's callback, issue #14 part 2) keeps every behaviour of the slow one:
a position reply split across segments, stray bytes after a reply, the statistics, a timeout and
its resync, a stop cutting a read short, and the byte trace. A scripted box over real TCP says
exactly which bytes come when."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

import pytest

from scopelink.drivers.skytracker.exchange import ReplyTimeoutError, SkyTrackerLine
from scopelink.links import Link, open_link, serve_tcp
from scopelink.protocol.skytracker import (
    PositionReply,
    ReadPosition,
    ReadStatus,
    ReleaseDirections,
    StatusReply,
    TrackerMode,
    TrackerStatus,
    VersionReply,
)

POSITION = PositionReply(5.5, 20.25)
STATUS = TrackerStatus.for_mode(TrackerMode.TRACK)
TIMEOUT_S = 0.3


class ScriptedBox:
    """A Sky Tracker with its Sky Commander: ``V`` and ``R`` answered at once, ``Q`` granted,
    each position request (``\\r`` inside a grant) answered as the next entry of ``plan`` says
    (the last one repeats): ``whole``, ``split`` (5 bytes, then the rest 30 ms later),
    ``trailing`` (the reply and a stray byte in one segment) or ``silent``; ``R`` stays
    unanswered while ``status_silent``. Records every byte it receives."""

    def __init__(self) -> None:
        self.plan = ["whole"]
        self.status_silent = False
        self.received = bytearray()
        self.asked = asyncio.Event()
        """Set when an ``R`` arrives."""
        self.got = asyncio.Event()
        """Set whenever a byte arrives."""

    async def serve(self, link: Link) -> None:
        held = False
        while True:
            byte = await link.read(1)
            self.received += byte
            self.got.set()
            if byte == b"Q":
                held = True
                await link.write(b"A")
            elif byte == b"q":
                held = False
            elif held and byte == b"\r":
                await self._position(link)
            elif byte == b"V":
                await link.write(VersionReply.padded("v4.0").encode())
            elif byte == b"R":
                self.asked.set()
                if not self.status_silent:
                    await link.write(StatusReply(STATUS).encode())

    async def _position(self, link: Link) -> None:
        step = self.plan.pop(0) if len(self.plan) > 1 else self.plan[0]
        reply = POSITION.encode()
        if step == "whole":
            await link.write(reply)
        elif step == "split":
            await link.write(reply[:5])
            await asyncio.sleep(0.03)
            await link.write(reply[5:])
        elif step == "trailing":
            await link.write(reply + b"Z")


@asynccontextmanager
async def scripted_line() -> AsyncIterator[tuple[SkyTrackerLine, ScriptedBox]]:
    box = ScriptedBox()
    async with await serve_tcp(box.serve) as server:
        link = await open_link(f"tcp://127.0.0.1:{server.port}")
        line = SkyTrackerLine(link, timeout_s=TIMEOUT_S)
        try:
            assert isinstance(await line.ask(ReadStatus()), StatusReply)
            yield line, box
        finally:
            await link.close()


async def read_position(line: SkyTrackerLine) -> object:
    (reply,) = await line.commander([ReadPosition()], retry_delays_s=())
    return reply


async def test_split_replies_stray_bytes_statistics_and_the_trace_on_the_fast_path(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with scripted_line() as (line, box):
        statistics = line.statistics
        sent = statistics.commands_sent
        box.plan = ["whole", "split", "trailing", "whole", "split"]
        with caplog.at_level(logging.DEBUG, logger="scopelink.links.trace"):
            replies = [await read_position(line) for _ in range(5)]
        assert replies == [POSITION] * 5
        # The 'Z' after the third reply is noted as stray when the next command goes, no resync.
        assert (statistics.stray_bytes, statistics.resyncs) == (1, 0)
        assert statistics.commands_sent == sent + 5 * 3  # Q, \r, q each time
        ours = f"{line.link.name} "  # the box's end traces too
        lines = [text for r in caplog.records if (text := r.getMessage()).startswith(ours)]
        assert sum(" --> 1 bytes: 0d" in text for text in lines) == 5
        # The grants, the five replies (the two split ones in two pieces each).
        assert sum(" <-- " in text for text in lines) == 5 + 5 + 2
        assert any(" <-- 17 bytes: " in text for text in lines)  # the reply and its stray byte


async def test_a_timeout_on_the_fast_path_is_on_time_and_recovered() -> None:
    async with scripted_line() as (line, box):
        box.plan = ["silent", "whole"]  # the first request lost, the retry in the grant answered
        started = time.monotonic()
        assert await read_position(line) == POSITION
        elapsed = time.monotonic() - started
        # One timeout, then the resync ('\r' drained, 'q', 'V' and a quiet drain): not sooner.
        assert TIMEOUT_S <= elapsed < TIMEOUT_S + 1.5
        assert line.statistics.resyncs == 1
        box.plan = ["silent"]
        with pytest.raises(ReplyTimeoutError, match=r"within 300 ms"):
            await read_position(line)


async def test_a_stop_cuts_a_fast_path_read_short_and_goes_out_at_once() -> None:
    async with scripted_line() as (line, box):
        box.status_silent = True
        box.asked.clear()
        poll = asyncio.ensure_future(line.ask(ReadStatus()))
        await box.asked.wait()  # the status request is out, its reply never comes
        started = time.monotonic()
        await line.stop_at_once([ReleaseDirections()])
        with pytest.raises(ReplyTimeoutError, match="a stop went first"):
            await poll
        assert time.monotonic() - started < TIMEOUT_S  # cut short, not timed out
        async with asyncio.timeout(2.0):
            while not box.received.endswith(b"qb"):
                box.got.clear()
                await box.got.wait()
        box.status_silent = False
        assert await line.ask(ReadStatus()) == StatusReply(STATUS)  # resynchronised first
        assert line.statistics.resyncs == 1
