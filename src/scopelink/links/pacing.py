"""Wire pacing: make writes over any link leave at a serial line's rate (e.g. 9600 baud 8N2).

Links without UART timing (TCP bridges, ptys, memory pairs) deliver a burst at once; a device like
the Sky Tracker's unbuffered PC port loses characters that come faster than 11 bit-times apart.
"""

from __future__ import annotations

import asyncio
import math
import selectors
import time

from scopelink.links.base import Link

# A write starting within this long after the previous one's last byte continues its schedule:
# it absorbs the event loop's timer overshoot (about 1 ms) so back-to-back writes do not drift.
# An idle line earns no more credit than this.
CONTINUATION_SLACK_SECONDS = 0.005

# A write answering input this link has just read may start when that input arrived, up to this
# long ago: the program's own processing time and wake-up delay are not line time (a device with
# no latency). A reply that took longer to compute starts when it is written.
RESPONSE_BACKDATE_SECONDS = 0.005


class PacedLink(Link):
    """A link whose writes leave one byte every ``bits_per_byte / baudrate`` seconds.

    Byte ``k`` of a burst is handed to the inner link when its last bit would have left a real
    UART, on an absolute schedule of the monotonic clock, so timer jitter never accumulates.
    A write that answers input read since the previous write starts no earlier than that input
    arrived and no earlier than the previous write left the line, so a request/response loop
    between two paced ends never runs faster than the real line (an unpaced peer's request takes
    no line time). Reads pass straight through. Closing it closes the inner link.
    """

    def __init__(self, inner: Link, baudrate: int, bits_per_byte: int) -> None:
        if baudrate <= 0 or bits_per_byte <= 0:
            raise ValueError(
                f"baudrate and bits_per_byte must be positive: {baudrate}, {bits_per_byte}"
            )
        super().__init__(inner.name)
        self.inner = inner
        self.baudrate = baudrate
        self.bits_per_byte = bits_per_byte
        self.byte_seconds = bits_per_byte / baudrate
        self._line_free_at = -math.inf
        self._input_at = -math.inf
        self._written_at = -math.inf
        self._write_lock = asyncio.Lock()

    async def _read_some(self, max_bytes: int) -> bytes:
        # The inner link's hooks, not its public methods: the trace is logged once, by this link.
        data = await self.inner._read_some(max_bytes)
        self._input_at = time.monotonic()
        return data

    def _start_of(self, now: float) -> float:
        """When the first bit of a write requested ``now`` goes on the line."""
        if self._input_at > self._written_at:
            # A response: it cannot start before its request arrived, nor while the previous
            # write is still on the line; credit for an idle line before the request is none.
            answered_at = (
                self._input_at if now - self._input_at <= RESPONSE_BACKDATE_SECONDS else now
            )
            return max(self._line_free_at, answered_at)
        if now - self._line_free_at <= CONTINUATION_SLACK_SECONDS:
            return self._line_free_at
        return now

    async def _write_all(self, data: bytes) -> None:
        async with self._write_lock:
            start = self._start_of(time.monotonic())
            sent = 0
            while sent < len(data):
                due = min(len(data), math.floor((time.monotonic() - start) / self.byte_seconds))
                if due > sent:
                    await self.inner._write_all(data[sent:due])
                    sent = due
                else:
                    next_due_at = start + (sent + 1) * self.byte_seconds
                    await asyncio.sleep(next_due_at - time.monotonic())
            self._line_free_at = start + len(data) * self.byte_seconds
            self._written_at = time.monotonic()

    async def _close_transport(self) -> None:
        await self.inner.close()


def paced(link: Link, baudrate: int = 9600, bits_per_byte: int = 10) -> PacedLink:
    """Wrap ``link`` so writes leave at ``baudrate``; 8N1 is 10 bits per byte, 8N2 is 11."""
    return PacedLink(link, baudrate, bits_per_byte)


def precise_event_loop() -> asyncio.AbstractEventLoop:
    """An event loop whose timers keep time to about 0.1 ms, for emulated serial lines.

    The default loop on Linux waits with ``epoll``, whose timeout is rounded *up* to whole
    milliseconds, so every paced write's last byte leaves up to 1 ms late (twice per
    request/response, 3-5 % of a 19.8 ms SynScan poll). ``select`` takes microseconds. It scans
    every descriptor on each wake-up and handles at most ``FD_SETSIZE`` (1024) of them: right for
    an emulator or a benchmark with a few links, not for a server with thousands of clients.
    Use with ``asyncio.Runner(loop_factory=precise_event_loop)``.
    """
    return asyncio.SelectorEventLoop(selectors.SelectSelector())
