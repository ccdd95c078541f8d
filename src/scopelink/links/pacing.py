"""Wire pacing: make writes over any link leave at a serial line's rate (e.g. 9600 baud 8N2).

Links without UART timing (TCP bridges, ptys, memory pairs) deliver a burst at once; a device like
the Sky Tracker's unbuffered PC port loses characters that come faster than 11 bit-times apart.
"""

from __future__ import annotations

import asyncio
import math
import selectors
import time

from scopelink.links.base import DEFAULT_BAUDRATE, Link
from scopelink.links.memory import MemoryLink

# A write starting within this long after the previous one's last byte continues its schedule:
# it absorbs the event loop's timer overshoot (about 1 ms) so back-to-back writes do not drift.
# An idle line earns no more credit than this.
CONTINUATION_SLACK_SECONDS = 0.005

# A write answering input this link has just read may start when that input arrived, up to this
# long ago: the program's own processing time and wake-up delay are not line time (a device with
# no latency). A reply that took longer to compute starts when it is written.
RESPONSE_BACKDATE_SECONDS = 0.005


MAX_BATCH_SECONDS = 0.1
"""The most a paced link may hold bytes back to hand them over together (see ``batch_s``)."""

_DUE_EPSILON = 1e-6


class PacedLink(Link):
    """A link whose writes leave one byte every ``bits_per_byte / baudrate`` seconds.

    Byte ``k`` of a burst is handed to the inner link when its last bit would have left a real
    UART, on an absolute schedule of the monotonic clock, so timer jitter never accumulates.
    A write that answers input read since the previous write starts no earlier than that input
    arrived and no earlier than the previous write left the line, so a request/response loop
    between two paced ends never runs faster than the real line (an unpaced peer's request takes
    no line time). Input counts as arrived when it was read, or, over a memory pair, when the
    peer's pacer says the line carried it (so a busy event loop's latency is not line time either).
    Reads pass straight through. Closing it closes the inner link.

    ``batch_s`` > 0 hands bytes over at most once per ``batch_s`` within a write, all those due
    by then together, and the write's last byte exactly when due: no byte ever early, none more
    than ``batch_s`` late. It is what a PC sees behind a UART FIFO or a USB-serial adapter (an
    FTDI adapter's latency timer is 16 ms), and it spares the event loop a wake-up per byte. 0
    (the default) hands each byte over when its last bit would leave the line: for a device
    that must not see two bytes closer together than the line spaces them.
    """

    def __init__(
        self, inner: Link, baudrate: int, bits_per_byte: int, *, batch_s: float = 0.0
    ) -> None:
        if baudrate <= 0 or bits_per_byte <= 0:
            raise ValueError(
                f"baudrate and bits_per_byte must be positive: {baudrate}, {bits_per_byte}"
            )
        if not 0.0 <= batch_s <= MAX_BATCH_SECONDS:
            raise ValueError(f"batch_s must be in [0, {MAX_BATCH_SECONDS}] seconds: {batch_s}")
        super().__init__(inner.name)
        self.inner = inner
        self.baudrate = baudrate
        self.bits_per_byte = bits_per_byte
        self.byte_seconds = bits_per_byte / baudrate
        self.batch_s = batch_s
        self._line_free_at = -math.inf
        self._input_at = -math.inf
        self._input_unanswered = False
        """Input was read since the last write began: the next write answers it."""
        self._write_lock = asyncio.Lock()

    async def _read_some(self, max_bytes: int) -> bytes:
        # The inner link's hooks, not its public methods: the trace is logged once, by this link.
        data = await self.inner._read_some(max_bytes)
        # When the bytes arrived, not when this coroutine got round to reading them: over a
        # memory pair, when the peer's pacer says the line carried them (loop latency is not
        # line time, as for a reply's own processing below).
        now = time.monotonic()
        inner = self.inner
        self._input_at = min(now, inner.arrived_at) if isinstance(inner, MemoryLink) else now
        self._input_unanswered = True
        return data

    def _start_of(self, now: float) -> float:
        """When the first bit of a write requested ``now`` goes on the line."""
        if self._input_unanswered:
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
            self._input_unanswered = False
            total = len(data)
            last_at = start + total * self.byte_seconds
            handed_at = start
            sent = 0
            while sent < total:
                now = time.monotonic()
                # The epsilon (a nanosecond's worth) keeps a wake-up that lands on a byte's due
                # time by the clock from being judged a hair early by the division's rounding.
                due = min(total, math.floor((now - start) / self.byte_seconds + _DUE_EPSILON))
                if due > sent:
                    await self._hand_over(data[sent:due], start + due * self.byte_seconds)
                    sent = due
                    handed_at = now
                    continue
                wake_at = start + (sent + 1) * self.byte_seconds
                if self.batch_s:
                    wake_at = min(max(wake_at, handed_at + self.batch_s), last_at)
                await asyncio.sleep(wake_at - now)
            self._line_free_at = last_at

    async def _hand_over(self, chunk: bytes, carried_at: float) -> None:
        if isinstance(self.inner, MemoryLink):
            self.inner.hand_over(chunk, carried_at)
        else:
            await self.inner._write_all(chunk)

    async def _close_transport(self) -> None:
        await self.inner.close()


def paced(
    link: Link, baudrate: int = DEFAULT_BAUDRATE, bits_per_byte: int = 10, *, batch_s: float = 0.0
) -> PacedLink:
    """Wrap ``link`` so writes leave at ``baudrate``; 8N1 is 10 bits per byte, 8N2 is 11.
    ``batch_s`` groups bytes into hand-overs at most that often (see :class:`PacedLink`)."""
    return PacedLink(link, baudrate, bits_per_byte, batch_s=batch_s)


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
