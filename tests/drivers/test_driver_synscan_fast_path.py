"""The wire's fast path (a free wire, in step: one call writes the command and sets up its reader,
the reply parsed in the transport's callback, issue #14 part 2) keeps every behaviour of the
slow one: replies split across segments, stale bytes before a reply, the timeout, a stop cutting
a read short, the statistics and the byte trace. A scripted hand control over real TCP says
exactly which bytes come when."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

import pytest

from scopelink.drivers.synscan.exchange import STOP_GRACE_S, SynScanWire
from scopelink.links import Link, open_link, serve_tcp
from scopelink.mount import DeviceError, Priority
from scopelink.protocol.synscan import CancelGoto, GetRaDec, Position
from scopelink.protocol.synscan.message import Complete

REPLY = b"12AB0500,40000500#"
"""The device's answer to ``e`` (RA 12AB05, Dec 400005 in precise units)."""

TIMEOUT_S = 0.3


class ScriptedDevice:
    """Answers echoes at once, and each ``e`` as the next entry of ``plan`` says (the last one
    repeats): ``whole``, ``split`` (5 bytes, then the rest 30 ms later), ``trailing`` (the reply
    and two stray bytes in one segment) or ``silent``. Records every byte it receives."""

    def __init__(self) -> None:
        self.plan = ["whole"]
        self.received = bytearray()
        self.asked = asyncio.Event()
        self.got = asyncio.Event()
        """Set whenever a byte arrives."""

    async def serve(self, link: Link) -> None:
        while True:
            byte = await link.read(1)
            self.received += byte
            self.got.set()
            if byte == b"K":  # a resynchronising echo: its byte back, and '#'
                value = await link.read(1)
                self.received += value
                await link.write(value + b"#")
            elif byte == b"e":
                step = self.plan.pop(0) if len(self.plan) > 1 else self.plan[0]
                self.asked.set()
                if step == "whole":
                    await link.write(REPLY)
                elif step == "split":
                    await link.write(REPLY[:5])
                    await asyncio.sleep(0.03)
                    await link.write(REPLY[5:])
                elif step == "trailing":
                    await link.write(REPLY + b"XY")


@asynccontextmanager
async def scripted_wire() -> AsyncIterator[tuple[SynScanWire, ScriptedDevice]]:
    device = ScriptedDevice()
    async with await serve_tcp(device.serve) as server:
        url = f"tcp://127.0.0.1:{server.port}"

        async def factory() -> Link:
            return await open_link(url)

        wire = SynScanWire(factory, name=url, timeout_s=TIMEOUT_S)
        await wire.open()
        try:
            yield wire, device
        finally:
            await wire.close()


def expected() -> Position:
    """REPLY as the codec reads it."""
    scanned = GetRaDec().scan_reply(REPLY)
    assert isinstance(scanned, Complete)
    assert isinstance(scanned.reply, Position)
    return scanned.reply


async def test_split_replies_stale_bytes_statistics_and_the_trace_on_the_fast_path(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with scripted_wire() as (wire, device):
        statistics = wire.statistics
        resyncs, exchanges = statistics.resyncs, statistics.exchanges
        device.plan = ["whole", "split", "split", "trailing", "whole", "whole"]
        with caplog.at_level(logging.DEBUG, logger="scopelink.links.trace"):
            replies = [await wire.ask(GetRaDec(), Priority.POLL) for _ in range(6)]
        assert replies == [expected()] * 6  # parsed once, then the remembered reply each time
        # "XY" came after the fourth reply: the fifth exchange dropped it as stale, no resync.
        assert statistics.discarded_bytes == 2
        assert (statistics.resyncs, statistics.failures) == (resyncs, 0)
        assert statistics.exchanges == exchanges + 6
        assert statistics.bytes_received >= 6 * len(REPLY) + 2
        # The trace: every command out and every reply in, the split ones in two pieces.
        assert wire.link is not None
        ours = f"{wire.link.name} "  # the device's end traces too
        lines = [line for r in caplog.records if (line := r.getMessage()).startswith(ours)]
        assert sum(" --> 1 bytes: 65 " in line for line in lines) == 6
        assert sum(" <-- " in line for line in lines) == 6 + 2
        assert any(" <-- 20 bytes: " in line for line in lines)  # the reply and "XY"


async def test_a_timeout_on_the_fast_path_is_on_time_and_recovered() -> None:
    async with scripted_wire() as (wire, device):
        device.plan = ["silent", "whole"]  # the first 'e' lost, the retry answered
        started = time.monotonic()
        reply = await wire.ask(GetRaDec(), Priority.POLL)
        elapsed = time.monotonic() - started
        assert reply == expected()
        # One timeout, the quiet drain (0.05 s) and the echo: not sooner than the timeout.
        assert TIMEOUT_S <= elapsed < TIMEOUT_S + 1.0
        assert (wire.statistics.failures, wire.statistics.resyncs) == (1, 2)  # open's echo too
        device.plan = ["silent"]
        with pytest.raises(DeviceError, match=r"no reply to 'get precise RA/Dec' within 0\.3 s"):
            await wire.ask(GetRaDec(), Priority.POLL)


async def test_a_stop_cuts_a_fast_path_read_short_and_goes_out_at_once() -> None:
    async with scripted_wire() as (wire, device):
        device.plan = ["silent"]
        device.asked.clear()
        poll = asyncio.ensure_future(wire.ask(GetRaDec(), Priority.POLL))
        await device.asked.wait()  # the poll is out, on the fast path, its reply never comes
        started = time.monotonic()
        assert await wire.stop_at_once([CancelGoto()])  # interrupted: written at once
        waited = time.monotonic() - started
        with pytest.raises(DeviceError, match="a stop went first"):
            await poll
        assert STOP_GRACE_S * 0.5 <= waited < TIMEOUT_S  # the grace, not the timeout
        assert wire.statistics.interrupted == 1
        async with asyncio.timeout(2.0):
            while not device.received.endswith(CancelGoto().encode()):
                device.got.clear()
                await device.got.wait()
        device.plan = ["whole"]
        assert await wire.ask(GetRaDec(), Priority.POLL) == expected()  # resynchronised first
