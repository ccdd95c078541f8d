"""The byte-stream interface every link implements, and the errors links raise.

A link moves bytes and nothing else: no framing, no timeouts of its own. Callers bound waits with
``asyncio.timeout``; every ``read`` is cancellation-safe (a cancelled read loses no bytes), so a
driver can time out a reply and resynchronise with :meth:`Link.drain_input`.
"""

from __future__ import annotations

import asyncio
import logging
from abc import ABC, abstractmethod
from collections.abc import Awaitable, Callable
from types import TracebackType
from typing import Self, TypeVar

from scopelink.links.trace import trace_logger, trace_transfer
from scopelink.protocol.base import NEED_DATA, NeedData

DEFAULT_READ_SIZE = 4096

DEFAULT_BAUDRATE = 9600
"""The line speed of both mount families (SynScan, Sky Tracker and Sky Commander)."""

E = TypeVar("E")


class LinkError(Exception):
    """Base class of every error a link raises."""


class LinkClosedError(LinkError):
    """The link was closed by us, or the other end went away (EOF, hang-up, unplugged)."""


class LinkOpenError(LinkError):
    """A link could not be opened; the message names the port and says what to try."""

    def __init__(self, port: str, reason: str, hint: str = "") -> None:
        self.port = port
        self.reason = reason
        self.hint = hint
        message = f"cannot open {port}: {reason}"
        super().__init__(f"{message} — {hint}" if hint else message)


class LinkSpecError(LinkError, ValueError):
    """A link specification string (see :func:`scopelink.links.open_link`) is malformed."""


class Link(ABC):
    """An open, bidirectional byte stream: serial port, TCP connection, pty or in-memory pipe.

    Subclasses implement ``_read_some``, ``_write_all`` and ``_close_transport``; this class adds
    the closed state, the hex trace of every transfer and the input-draining helper once for all.
    """

    def __init__(self, name: str) -> None:
        self._name = name
        self._closed = False
        self._closing: asyncio.Future[None] | None = None
        self.bytes_read = 0
        """Bytes read and written since the link opened (the poller's line cap counts them)."""
        self.bytes_written = 0

    @property
    def name(self) -> str:
        """Human-readable identity used in logs and errors, e.g. ``/dev/ttyUSB0``."""
        return self._name

    @property
    def closed(self) -> bool:
        """True once :meth:`close` was called or the other end was seen to go away.

        Either way the link's resources are released; calling :meth:`close` again is harmless.
        """
        return self._closed

    async def read(self, max_bytes: int = DEFAULT_READ_SIZE) -> bytes:
        """Wait for at least one byte and return up to ``max_bytes`` bytes.

        Raises :class:`LinkClosedError` when the link is closed or the other end has gone.
        """
        if max_bytes < 1:
            raise ValueError(f"max_bytes must be at least 1, not {max_bytes}")
        if self._closed:
            raise LinkClosedError(f"{self._name} is closed")
        try:
            data = await self._read_some(max_bytes)
        except LinkClosedError:
            await self._release_after_end()
            raise
        self.bytes_read += len(data)
        if trace_logger.isEnabledFor(logging.DEBUG):  # inline: every reply passes here
            trace_transfer("<--", self._name, data)
        return data

    def read_event(self, parse: Callable[[bytes], E | NeedData]) -> Awaitable[E]:
        """Wait until ``parse``, given the bytes received from now on (each byte once, in order,
        in chunks as they come), returns something other than ``NEED_DATA``; return that.

        A reply reader: a link fed by a callback (TCP, memory, a reader thread) runs ``parse``
        right there, so the reader wakes once per reply, with the reply, rather than once per
        chunk (issue #14: CPU per command). ``parse`` must not raise. Cancellation-safe: the
        bytes ``parse`` took are the caller's (in its parser); later ones wait for the next
        read. Raises :class:`LinkClosedError` as :meth:`read` does. Not a coroutine function,
        so that a link can hand its future over directly (:class:`~scopelink.links.TcpClientLink`);
        await what it returns.
        """
        return self._read_event_checked(parse)

    async def _read_event_checked(self, parse: Callable[[bytes], E | NeedData]) -> E:
        if self._closed:
            raise LinkClosedError(f"{self._name} is closed")
        try:
            return await self._read_event(parse)
        except LinkClosedError:
            await self._release_after_end()
            raise

    def _read_event(self, parse: Callable[[bytes], E | NeedData]) -> Awaitable[E]:
        """:meth:`read_event` by :meth:`_read_some`; a link whose bytes come through a callback
        overrides it (see :meth:`InboundBuffer.read_event`)."""
        return self._read_event_by_chunks(parse)

    async def _read_event_by_chunks(self, parse: Callable[[bytes], E | NeedData]) -> E:
        while True:
            data = await self._read_some(DEFAULT_READ_SIZE)
            self.bytes_read += len(data)
            if trace_logger.isEnabledFor(logging.DEBUG):
                trace_transfer("<--", self._name, data)
            event = parse(data)
            if event is not NEED_DATA:
                return event  # anything but NEED_DATA is an E

    async def read_exactly(self, count: int) -> bytes:
        """Wait for exactly ``count`` bytes, e.g. a fixed-length reply.

        Unlike :meth:`read`, a cancelled call loses the bytes it had already received:
        after a timeout, resynchronise with :meth:`drain_input`.
        """
        received = bytearray()
        while len(received) < count:
            received += await self.read(count - len(received))
        return bytes(received)

    async def write(self, data: bytes | bytearray | memoryview) -> None:
        """Send ``data``; return once it is handed to the OS (or the wire pacing allows)."""
        if self._closed:
            raise LinkClosedError(f"{self._name} is closed")
        payload = data if type(data) is bytes else bytes(data)
        if not payload:
            return
        self.bytes_written += len(payload)
        if trace_logger.isEnabledFor(logging.DEBUG):  # inline: every command passes here
            trace_transfer("-->", self._name, payload)
        try:
            await self._write_all(payload)
        except LinkClosedError:
            await self._release_after_end()
            raise

    def write_and_read_event(
        self, data: bytes, parse: Callable[[bytes], E | NeedData]
    ) -> asyncio.Future[E] | None:
        """Hand non-empty ``data`` over at once and start :meth:`read_event`, whose future it
        returns, if this link can without waiting; None when it cannot, having sent nothing:
        then :meth:`write` and :meth:`read_event`. A driver's command and its reply in one call
        (issue #14: CPU per command); the bytes are counted and traced as :meth:`write` does.
        Cancel the future to give the read up before awaiting it. A link that can
        (:class:`~scopelink.links.TcpClientLink`) overrides this; this one never can."""
        return None

    async def close(self) -> None:
        """Release the link (idempotent); pending and later reads and writes then raise."""
        self._closed = True
        await self._close_transport_once()

    async def _close_transport_once(self) -> None:
        """Close the transport once, whoever asks and however many at a time: a reader meeting
        the end of the stream and a disconnect close together, and a descriptor closed twice
        fails (EBADF) or closes whatever file reused its number meanwhile. The first caller
        closes at once, in its own turn (a separate task would let others see the link closed
        and not yet released); later callers wait for it."""
        if self._closing is not None:
            await asyncio.shield(self._closing)
            return
        self._closing = asyncio.get_running_loop().create_future()
        try:
            await self._close_transport()
        finally:
            self._closing.set_result(None)

    async def drain_input(self, quiet_seconds: float = 0.05, max_seconds: float = 2.0) -> bytes:
        """Read and discard input until the line has been quiet for ``quiet_seconds``.

        Returns the discarded bytes (for logging). Gives up after ``max_seconds`` on a line that
        never falls silent. Used by drivers to resynchronise after a timeout.
        """
        loop = asyncio.get_running_loop()
        give_up_at = loop.time() + max_seconds
        discarded = bytearray()
        while (remaining := give_up_at - loop.time()) > 0:
            try:
                async with asyncio.timeout(min(quiet_seconds, remaining)):
                    discarded += await self.read()
            except TimeoutError:
                break
        return bytes(discarded)

    async def __aenter__(self) -> Self:
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        await self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"<{type(self).__name__} {self._name!r} {state}>"

    def _end_seen(self) -> None:
        """A reader fed by a callback met the end of the stream: the link reads as closed from
        now on, as after :meth:`read` raised (its transport releases itself at the end, or
        :meth:`close` does)."""
        self._closed = True

    async def _release_after_end(self) -> None:
        """The stream ended under us: nothing more can pass, so free the resources now."""
        self._closed = True
        await self._close_transport_once()

    @abstractmethod
    async def _read_some(self, max_bytes: int) -> bytes:
        """Wait for 1..max_bytes bytes; cancellation-safe; LinkClosedError at end of stream."""

    @abstractmethod
    async def _write_all(self, data: bytes) -> None:
        """Hand every byte of non-empty ``data`` over; LinkClosedError if the other end is gone."""

    @abstractmethod
    async def _close_transport(self) -> None:
        """Release resources and wake pending reads with LinkClosedError. Called once or more."""
