"""The TCP link :func:`~scopelink.links.open_tcp` returns: a socket driven by an asyncio protocol.

A driver polling a device over TCP (a Wi-Fi adapter, a serial-to-TCP bridge, an emulator) does
one small write and one small read per command, thousands a second against a device that
answers at once. :class:`TcpLink` goes through ``asyncio.StreamReader`` (built for servers that
parse lines and chunks), which costs about 15 µs of CPU per reply on a 2-core machine: its
protocol, flow-control checks and waiter bookkeeping. This link's protocol hands each received
segment straight to an :class:`~scopelink.links.inbound.InboundBuffer`, whose single reader
wakes on one future (issue #14 part 2, ``docs/benchmarks.md``, "SynScan driver").

The behaviour is :class:`TcpLink`'s: Nagle off, reads cancellation-safe, ``LinkClosedError`` at
the end of the stream or on a connection error, writes that wait while the kernel's buffer is
full (the transport's high-water mark), ``peer_host`` for allow-lists.
"""

from __future__ import annotations

import asyncio
import logging
import socket
from collections.abc import Awaitable, Callable
from typing import cast

from scopelink.links.base import Link, LinkClosedError
from scopelink.links.inbound import E, InboundBuffer
from scopelink.links.trace import trace_logger, trace_transfer
from scopelink.protocol.base import NeedData


def peer_host_without_nagle(transport: asyncio.BaseTransport | asyncio.StreamWriter) -> str | None:
    """Switch Nagle off on a connected TCP socket (single-byte commands leave at once) and return
    the address at the other end (None if unknown)."""
    sock = transport.get_extra_info("socket")
    if sock is not None:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    peer = transport.get_extra_info("peername")
    return str(peer[0]) if peer else None


class _ClientProtocol(asyncio.Protocol):
    """Feeds the link's inbound buffer; tracks write back-pressure and the connection's end."""

    def __init__(self, name: str) -> None:
        self.name = name
        # The connection's loop for good; no arrival times (only paced memory links use them).
        self.inbound = InboundBuffer(asyncio.get_running_loop(), stamp=False)
        # The transport calls the buffer's feed itself: one Python call less per segment.
        self.data_received = self.inbound.feed  # type: ignore[method-assign]
        self.transport: asyncio.Transport | None = None
        self._drained: asyncio.Future[None] | None = None
        self._paused = False

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.Transport, transport)

    def data_received(self, data: bytes) -> None:  # pragma: no cover - replaced in __init__
        self.inbound.feed(data)

    def eof_received(self) -> bool:
        self.inbound.feed_end(f"{self.name}: connection closed by the peer")
        return False  # let the transport close itself

    def connection_lost(self, exc: Exception | None) -> None:
        reason = f"connection lost ({exc})" if exc else "connection closed by the peer"
        self.inbound.feed_end(f"{self.name}: {reason}")
        self._paused = False
        self._wake_writer(LinkClosedError(f"{self.name}: {reason}"))

    def pause_writing(self) -> None:
        self._paused = True

    def resume_writing(self) -> None:
        self._paused = False
        self._wake_writer(None)

    async def drained(self) -> None:
        """Return once the transport's buffer is below its low-water mark again."""
        while self._paused:
            self._drained = asyncio.get_running_loop().create_future()
            try:
                await self._drained
            finally:
                self._drained = None

    def _wake_writer(self, error: Exception | None) -> None:
        waiter = self._drained
        if waiter is not None and not waiter.done():
            if error is None:
                waiter.set_result(None)
            else:
                waiter.set_exception(error)


class TcpClientLink(Link):
    """A connected TCP stream (Nagle off, so single-byte commands leave at once)."""

    def __init__(self, transport: asyncio.Transport, protocol: _ClientProtocol, name: str):
        super().__init__(name)
        self._transport = transport
        self._protocol = protocol
        self._inbound = protocol.inbound
        self.peer_host = peer_host_without_nagle(transport)
        """The address at the other end."""

    async def _read_some(self, max_bytes: int) -> bytes:
        return await self._inbound.read(max_bytes)

    def read_event(self, parse: Callable[[bytes], E | NeedData]) -> Awaitable[E]:
        """See :meth:`Link.read_event`: the buffer's future itself, without a coroutine around
        it (issue #14: CPU per command); the buffer marks the link closed when the stream
        ends first, and the transport has closed itself by then."""
        if self._closed:
            raise LinkClosedError(f"{self.name} is closed")
        return self._inbound.read_event(parse, self)

    async def _write_all(self, data: bytes) -> None:
        transport = self._transport
        if transport.is_closing():
            raise LinkClosedError(f"{self.name}: connection closed")
        transport.write(data)  # a send error closes the transport and calls connection_lost
        if self._protocol._paused:  # above the high-water mark: wait until it drains
            await self._protocol.drained()

    def write_and_read_event(
        self, data: bytes, parse: Callable[[bytes], E | NeedData]
    ) -> asyncio.Future[E] | None:
        """See :meth:`Link.write_and_read_event`: below the transport's high-water mark, at
        once; the command and its reply traced or not as one (one look-up)."""
        transport = self._transport
        if self._closed or self._protocol._paused or transport.is_closing():
            return None
        self.bytes_written += len(data)
        trace = trace_logger.isEnabledFor(logging.DEBUG)
        if trace:
            trace_transfer("-->", self.name, data)
        transport.write(data)
        return self._inbound.read_event(parse, self, trace)

    async def _close_transport(self) -> None:
        self._inbound.feed_end(f"{self.name} is closed")
        transport = self._transport
        if not transport.is_closing():
            transport.close()
            # Let connection_lost run (the socket is released there), as StreamWriter.wait_closed.
            await asyncio.sleep(0)


async def connect_tcp_client(host: str, port: int, name: str) -> TcpClientLink:
    """Connect; OSError (refused, unknown host, ...) propagates for the caller to explain."""
    loop = asyncio.get_running_loop()
    transport, protocol = await loop.create_connection(lambda: _ClientProtocol(name), host, port)
    return TcpClientLink(transport, protocol, name)
