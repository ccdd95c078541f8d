"""TCP links: a client connection and a server that hands each accepted connection to a handler."""

from __future__ import annotations

import asyncio
import contextlib
import errno
import logging
import socket
from collections.abc import Awaitable, Callable
from types import TracebackType
from typing import Self

from scopelink.links.base import Link, LinkClosedError, LinkOpenError
from scopelink.links.tcp_client import (
    TcpClientLink,
    connect_tcp_client,
    peer_host_without_nagle,
)

logger = logging.getLogger(__name__)

ConnectionHandler = Callable[[Link], Awaitable[None]]

# How long TcpServer.close lets handlers finish after their links closed before cancelling them.
_HANDLER_GRACE_SECONDS = 1.0


def _endpoint(host: str, port: int) -> str:
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


class TcpLink(Link):
    """A connected TCP stream (Nagle off, so single-byte commands leave at once)."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, name: str):
        super().__init__(name)
        self._reader = reader
        self._writer = writer
        self.peer_host = peer_host_without_nagle(writer)
        """The address at the other end (servers check it against their allow-list)."""

    async def _read_some(self, max_bytes: int) -> bytes:
        try:
            data = await self._reader.read(max_bytes)
        except OSError as exc:
            raise LinkClosedError(f"{self.name}: connection lost ({exc})") from exc
        if not data:
            reason = "closed" if self.closed else "closed by the peer"
            raise LinkClosedError(f"{self.name}: connection {reason}")
        return data

    async def _write_all(self, data: bytes) -> None:
        transport = self._writer.transport
        if transport.is_closing():
            raise LinkClosedError(f"{self.name}: connection closed")
        try:
            transport.write(data)
            if transport.get_write_buffer_size():
                # Not all sent at once: wait while the buffer is above its high-water mark. A
                # write that went straight to the socket (every command) skips the await.
                await self._writer.drain()
        except OSError as exc:
            raise LinkClosedError(f"{self.name}: connection lost ({exc})") from exc

    async def _close_transport(self) -> None:
        if self._writer.is_closing():
            return
        self._writer.close()
        with contextlib.suppress(OSError):
            await self._writer.wait_closed()


async def open_tcp(host: str, port: int, *, connect_timeout: float = 5.0) -> TcpClientLink:
    """Connect to ``host:port``; LinkOpenError says why if that fails within ``connect_timeout``.

    The link is a :class:`~scopelink.links.tcp_client.TcpClientLink` (protocol-driven, the
    least CPU per reply); accepted connections are :class:`TcpLink`."""
    name = f"tcp {_endpoint(host, port)}"
    try:
        async with asyncio.timeout(connect_timeout):
            return await connect_tcp_client(host, port, name)
    except TimeoutError:
        hint = "is the address right and the device on this network?"
        raise LinkOpenError(name, f"no answer within {connect_timeout:g} s", hint) from None
    except ConnectionRefusedError as exc:
        hint = "is the server running and listening on that port?"
        raise LinkOpenError(name, "connection refused", hint) from exc
    except socket.gaierror as exc:
        raise LinkOpenError(name, f"unknown host ({exc.strerror})", "check the host name") from exc
    except OSError as exc:
        raise LinkOpenError(name, exc.strerror or str(exc)) from exc


class TcpServer:
    """A listening socket that runs ``handler(link)`` for each connection; see :func:`serve_tcp`."""

    def __init__(self, handler: ConnectionHandler) -> None:
        self._handler = handler
        self._server: asyncio.Server | None = None
        self._connections: dict[asyncio.Task[None], TcpLink] = {}
        self.host = ""
        self.port = 0

    @property
    def name(self) -> str:
        """``tcp server HOST:PORT`` for logs."""
        return f"tcp server {_endpoint(self.host, self.port)}"

    async def listen(self, host: str, port: int) -> None:
        """Bind and start accepting; ``port`` 0 picks a free port, stored in ``.port``."""
        try:
            self._server = await asyncio.start_server(self._serve_connection, host, port)
        except OSError as exc:
            hint = "does another program listen there?" if exc.errno == errno.EADDRINUSE else ""
            reason = exc.strerror or str(exc)
            raise LinkOpenError(f"tcp server {_endpoint(host, port)}", reason, hint) from exc
        self.host, self.port = self._server.sockets[0].getsockname()[:2]

    async def close(self) -> None:
        """Stop listening, close every connection, and wait for the handlers to return."""
        if self._server is not None:
            self._server.close()
        connections = dict(self._connections)
        for link in connections.values():
            await link.close()
        if connections:
            _, stragglers = await asyncio.wait(connections, timeout=_HANDLER_GRACE_SECONDS)
            for task in stragglers:
                task.cancel()
            await asyncio.gather(*stragglers, return_exceptions=True)
        if self._server is not None:
            await self._server.wait_closed()

    async def __aenter__(self) -> Self:
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        await self.close()

    async def _serve_connection(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        peer_host, peer_port = writer.get_extra_info("peername")[:2]
        local_port = writer.get_extra_info("sockname")[1]
        name = f"tcp {_endpoint(peer_host, peer_port)} on :{local_port}"
        link = TcpLink(reader, writer, name)
        task = asyncio.current_task()
        assert task is not None
        self._connections[task] = link
        logger.info("%s: connected", name)
        try:
            await self._handler(link)
        except LinkClosedError as exc:
            logger.info("%s", exc)
        except Exception:
            logger.exception("%s: connection handler failed", name)
        finally:
            del self._connections[task]
            await link.close()
            logger.info("%s: disconnected", name)


async def serve_tcp(
    handler: ConnectionHandler, *, host: str = "127.0.0.1", port: int = 0
) -> TcpServer:
    """Listen on ``host:port`` (port 0 picks a free one: read ``.port``) and serve each connection.

    The handler gets a :class:`Link` per connection, closed for it when the handler returns.
    A handler ending in LinkClosedError is a normal disconnect; other exceptions are logged.
    """
    server = TcpServer(handler)
    await server.listen(host, port)
    return server
