"""A receive buffer fed by a producer (a peer link, a reader thread) and read by one coroutine."""

from __future__ import annotations

import asyncio
import math
import time

from scopelink.links.base import LinkClosedError


class InboundBuffer:
    """Bytes waiting to be read, plus an end-of-stream marker that wakes a waiting reader.

    Bytes fed before the end are still delivered; only then does ``read`` raise.
    All methods run on the event loop's thread (threads feed it via ``call_soon_threadsafe``).
    """

    def __init__(self) -> None:
        self._data = bytearray()
        self._changed = asyncio.Event()
        self._end_reason: str | None = None
        self.arrived_at = -math.inf
        """``time.monotonic()`` when the latest bytes arrived (the producer says, or when fed)."""

    def feed(self, data: bytes, arrived_at: float | None = None) -> None:
        """Append received bytes; ignored after the end of the stream. ``arrived_at`` is when
        they arrived if the producer knows better than now (a paced peer: when due on the line)."""
        if self._end_reason is None and data:
            self._data += data
            self.arrived_at = time.monotonic() if arrived_at is None else arrived_at
            self._changed.set()

    def feed_end(self, reason: str) -> None:
        """Mark the end of the stream; the first reason given is the one readers see."""
        if self._end_reason is None:
            self._end_reason = reason
            self._changed.set()

    async def read(self, max_bytes: int) -> bytes:
        """Wait for 1..max_bytes bytes; LinkClosedError once drained and ended."""
        while not self._data:
            if self._end_reason is not None:
                raise LinkClosedError(self._end_reason)
            self._changed.clear()
            await self._changed.wait()
        data = bytes(self._data[:max_bytes])
        del self._data[:max_bytes]
        return data
