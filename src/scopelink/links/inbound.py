"""A receive buffer fed by a producer (a peer link, a reader thread, a protocol) and read by one
coroutine."""

from __future__ import annotations

import asyncio
import math
import time

from scopelink.links.base import LinkClosedError


class InboundBuffer:
    """Bytes waiting to be read, plus an end-of-stream marker that wakes a waiting reader.

    Bytes fed before the end are still delivered; only then does ``read`` raise.
    All methods run on the event loop's thread (threads feed it via ``call_soon_threadsafe``).
    A waiting reader sleeps on a future of its own, which ``feed`` resolves (no
    ``asyncio.Event``: its extra look-ups cost CPU on every reply, issue #14); one reader at a
    time is the rule, but a second one is woken too.
    """

    __slots__ = ("_data", "_end_reason", "_loop", "_waiters", "arrived_at")

    def __init__(self) -> None:
        self._data = bytearray()
        self._waiters: list[asyncio.Future[None]] = []
        self._loop: asyncio.AbstractEventLoop | None = None
        self._end_reason: str | None = None
        self.arrived_at = -math.inf
        """``time.monotonic()`` when the latest bytes arrived (the producer says, or when fed)."""

    def feed(self, data: bytes, arrived_at: float | None = None) -> None:
        """Append received bytes; ignored after the end of the stream. ``arrived_at`` is when
        they arrived if the producer knows better than now (a paced peer: when due on the line)."""
        if self._end_reason is None and data:
            self._data += data
            self.arrived_at = time.monotonic() if arrived_at is None else arrived_at
            self._wake()

    def feed_end(self, reason: str) -> None:
        """Mark the end of the stream; the first reason given is the one readers see."""
        if self._end_reason is None:
            self._end_reason = reason
            self._wake()

    async def read(self, max_bytes: int) -> bytes:
        """Wait for 1..max_bytes bytes; LinkClosedError once drained and ended."""
        while not self._data:
            if self._end_reason is not None:
                raise LinkClosedError(self._end_reason)
            loop = self._loop
            if loop is None or loop.is_closed():  # looked up once: each look-up is a system call
                loop = self._loop = asyncio.get_running_loop()
            waiter = loop.create_future()
            waiters = self._waiters
            waiters.append(waiter)
            try:
                await waiter
            finally:
                waiters.remove(waiter)
        buffered = self._data
        if len(buffered) <= max_bytes:  # the common case: take everything
            data = bytes(buffered)
            buffered.clear()
            return data
        data = bytes(buffered[:max_bytes])
        del buffered[:max_bytes]
        return data

    def _wake(self) -> None:
        for waiter in self._waiters:
            if not waiter.done():
                waiter.set_result(None)
