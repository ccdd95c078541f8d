"""Put a device server on a link: a pseudo-terminal, a TCP port or an in-memory pair.

:class:`HostedDevice` is an async context manager shared by every emulated device. It wraps each
server-side link in 9600-baud pacing (unless told not to), runs the server's connection handler,
and on exit closes the links and waits for the handler to return.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from dataclasses import dataclass
from types import TracebackType
from typing import Self

from scopelink.links import (
    ConnectionHandler,
    Link,
    LinkClosedError,
    TcpServer,
    memory_pair,
    open_pty,
    paced,
    serve_tcp,
)
from scopelink.servers.access import AccessControl, Refusal

__all__ = ["SERIAL_9600_8N1", "USB_SERIAL_BATCH_S", "HostedDevice", "WireSpeed"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class WireSpeed:
    """The line a device's replies leave at: ``baudrate`` and bits per byte (8N1 is 10);
    ``batch_s`` hands the bytes of a reply over in groups at most that often (the last one on
    time, none early; see :class:`~scopelink.links.PacedLink`), 0 one by one."""

    baudrate: int = 9600
    bits_per_byte: int = 10
    batch_s: float = 0.0

    def __post_init__(self) -> None:
        if self.baudrate <= 0 or self.bits_per_byte <= 0:
            raise ValueError(f"baud rate and bits per byte must be positive: {self}")


USB_SERIAL_BATCH_S = 0.016
"""How often an emulator hands a reply's bytes over: an FTDI USB-serial adapter's default
latency timer, what most PCs see of a hand control's bytes (a reply's last byte on time)."""

SERIAL_9600_8N1 = WireSpeed(batch_s=USB_SERIAL_BATCH_S)
"""The SynScan and Sky Tracker line: 9600 baud, 8 data bits, no parity, 1 stop bit; replies
handed over every 16 ms (:data:`USB_SERIAL_BATCH_S`), never early."""


class HostedDevice:
    """Serves ``handler`` on one pty, TCP port or memory pair; ``wire=None`` disables pacing.

    Start it with one of :meth:`on_pty`, :meth:`on_tcp` or :meth:`on_memory`; :attr:`address` then
    says where clients connect. :meth:`close` (or leaving ``async with``) stops it.
    """

    def __init__(
        self,
        handler: ConnectionHandler,
        *,
        wire: WireSpeed | None = None,
        access: AccessControl | None = None,
    ) -> None:
        self._handler = handler
        self._wire = wire
        self._tasks: list[asyncio.Task[None]] = []
        self._links: list[Link] = []
        self._tcp_server: TcpServer | None = None
        self.access = access if access is not None else AccessControl(name=type(self).__name__)
        """Who may connect over TCP, how many, how fast (no limits unless given)."""
        self.address = ""
        """The pty path, ``HOST:PORT``, or ``memory``, once started."""

    def _paced(self, link: Link) -> Link:
        if self._wire is None:
            return link
        return paced(
            link, self._wire.baudrate, self._wire.bits_per_byte, batch_s=self._wire.batch_s
        )

    async def on_pty(self, symlink: str | None = None) -> str:
        """Serve a new pseudo-terminal; returns the path a client opens."""
        pty = await open_pty(symlink)
        self.address = pty.path
        self._start(self._paced(pty))
        return pty.path

    async def on_tcp(self, host: str = "127.0.0.1", port: int = 0) -> tuple[str, int]:
        """Listen on ``host:port`` (0 picks a free port); returns the bound address."""
        self._tcp_server = await serve_tcp(self._serve_tcp_link, host=host, port=port)
        server = self._tcp_server
        self.address = (
            f"[{server.host}]:{server.port}"
            if ":" in server.host
            else f"{server.host}:{server.port}"
        )
        return server.host, server.port

    async def on_memory(self) -> Link:
        """Serve one end of an in-memory pair; returns the client's end."""
        device_end, client_end = memory_pair(("emulated device", "client"))
        self.address = "memory"
        self._start(self._paced(device_end))
        return client_end

    async def wait_closed(self) -> None:
        """Wait until every served pty or memory link has ended (TCP servers run until closed)."""
        if self._tasks:
            await asyncio.gather(*self._tasks, return_exceptions=True)

    async def close(self) -> None:
        """Stop serving: close the links and the TCP server, wait for the handlers."""
        if self._tcp_server is not None:
            await self._tcp_server.close()
        for link in self._links:
            await link.close()
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)

    async def __aenter__(self) -> Self:
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        await self.close()

    def _start(self, link: Link) -> None:
        self._links.append(link)
        self._tasks.append(asyncio.create_task(self._run(link), name=f"serve {link.name}"))

    async def _run(self, link: Link) -> None:
        try:
            await self._handler(link)
        except LinkClosedError as exc:
            logger.info("%s", exc)
        finally:
            with contextlib.suppress(LinkClosedError):
                await link.close()

    async def _serve_tcp_link(self, link: Link) -> None:
        async with self.access.session(getattr(link, "peer_host", None)) as client:
            if isinstance(client, Refusal):
                return  # no protocol here has a refusal message: the connection just closes
            idle_s = self.access.policy.idle_timeout_s
            await self._handler(self._paced(IdleClosingLink(link, idle_s)))


class IdleClosingLink(Link):
    """A network client's link that ends when the client sends nothing for ``idle_s``: a
    vanished phone or a forgotten connection must not hold a slot (and its dead-man) forever.
    Reads pass straight through; the trace is logged once, by this link."""

    def __init__(self, inner: Link, idle_s: float) -> None:
        super().__init__(inner.name)
        self.inner = inner
        self.idle_s = idle_s
        self.peer_host = getattr(inner, "peer_host", None)

    async def _read_some(self, max_bytes: int) -> bytes:
        try:
            async with asyncio.timeout(self.idle_s):
                return await self.inner._read_some(max_bytes)
        except TimeoutError:
            logger.info("%s: nothing received for %g s: closing", self.name, self.idle_s)
            await self.inner.close()
            raise LinkClosedError(f"{self.name}: idle for {self.idle_s:g} s, closed") from None

    async def _write_all(self, data: bytes) -> None:
        await self.inner._write_all(data)

    async def _close_transport(self) -> None:
        await self.inner.close()
