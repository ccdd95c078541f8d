"""The limits every scopelink HTTP server (Alpaca, the dashboard) puts around aiohttp.

aiohttp parses HTTP and bounds each line and header; this module adds what a server exposed to a
LAN (and to web pages through DNS rebinding) also needs, per connection, before any handler runs:

- **admission**: the access policy's allow-list (403) and connection limits (503 with
  ``Retry-After``); when the server is full, the connection idle longest (or stuck sending a
  request head) is closed to make room, so slow or idle clients cannot lock others out;
- **sizes**: request line ≤ :data:`MAX_REQUEST_LINE_BYTES` (414), the whole head ≤
  :data:`MAX_HEADER_BYTES` beyond it (431), answered as soon as the limit is crossed;
- **time**: a request head must arrive within the policy's ``header_timeout_s`` of its first
  byte, and a connection with no request for its ``idle_timeout_s`` is closed (aiohttp's
  keep-alive timeout).

The bodies' limit (:data:`MAX_BODY_BYTES`, 413) is the handlers' (they read the body); the
``Host`` allow-list (421) too, since it needs the parsed header.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Any, cast

from aiohttp import web
from aiohttp.http_exceptions import BadHttpMessage, LineTooLong
from aiohttp.web_protocol import RequestHandler

from scopelink.servers.access import AccessControl, Client, Refusal

__all__ = [
    "MAX_BODY_BYTES",
    "MAX_HEADER_BYTES",
    "MAX_REQUEST_LINE_BYTES",
    "GuardedAppRunner",
    "GuardedServer",
    "HttpGuard",
    "plain_reply",
]

logger = logging.getLogger(__name__)

MAX_REQUEST_LINE_BYTES = 8 * 1024
"""The request line (method, target, version): longer is answered 414 URI Too Long."""
MAX_HEADER_BYTES = 16 * 1024
"""All header lines of one request together: more is answered 431."""
MAX_BODY_BYTES = 64 * 1024
"""One request body: more is answered 413 (real Alpaca requests are < 1 KiB)."""
_TURN_AWAY_GRACE_S = 2.0
"""How long a refused connection may stay open for its client to read the refusal."""
EVICTABLE_AFTER_S = 1.0
"""A connection idle (or stuck in a request head) at least this long may be closed to make
room; a newer one may not, so a crowd arriving at once is refused (503), not churned."""
_HEAD_SLACK_BYTES = 4
"""The blank line that ends a head."""


def plain_reply(status: int, message: str, headers: tuple[tuple[str, str], ...] = ()) -> bytes:
    """A complete ``Connection: close`` text reply, for answers given before aiohttp's."""
    body = message.encode()
    phrase = {403: "Forbidden", 503: "Service Unavailable", 408: "Request Timeout"}.get(
        status, {414: "URI Too Long", 431: "Request Header Fields Too Large"}.get(status, "Error")
    )
    extra = "".join(f"{name}: {value}\r\n" for name, value in headers)
    return (
        f"HTTP/1.1 {status} {phrase}\r\nContent-Type: text/plain; charset=utf-8\r\n"
        f"X-Content-Type-Options: nosniff\r\nContent-Length: {len(body)}\r\n{extra}"
        "Connection: close\r\n\r\n"
    ).encode() + body


class HttpGuard:
    """One HTTP server's admission control and limits (shared by all its connections)."""

    def __init__(self, access: AccessControl) -> None:
        self.access = access
        self.header_timeout_s = access.policy.header_timeout_s
        self.idle_timeout_s = access.policy.idle_timeout_s
        """Read when the server starts (aiohttp's keep-alive timeout)."""
        self.connections: dict[GuardedRequestHandler, None] = {}
        """Admitted connections, oldest first."""
        self.evicted = 0
        """Idle or slow connections closed to make room for a new one."""
        self.timed_out = 0
        """Connections closed because a request head came too slowly."""
        self.oversized = 0
        """Requests answered 414 or 431."""

    def handler_kwargs(self) -> dict[str, Any]:
        """aiohttp's own limits, in line with ours (it answers what it catches first)."""
        return {
            "max_line_size": MAX_REQUEST_LINE_BYTES,
            "max_field_size": MAX_HEADER_BYTES,
            "keepalive_timeout": self.idle_timeout_s,
            # After a refused body (413) the rest is read and dropped this long, then the
            # connection closes: closing at once could reset it before the client reads the 413.
            "lingering_time": _TURN_AWAY_GRACE_S,
        }

    def admit(self, host: str | None) -> Client | Refusal:
        admitted = self.access.admit(host)
        if isinstance(admitted, Refusal) and admitted.total and self._evict_one():
            self.access.refused_connections -= 1  # not refused after all: room was made
            admitted = self.access.admit(host)
        return admitted

    def _evict_one(self) -> bool:
        """Close the oldest connection that is not handling a request; False if all are."""
        for connection in self.connections:
            if connection.evictable():
                connection.evict()
                self.evicted += 1
                return True
        return False


class GuardedRequestHandler(RequestHandler):
    """aiohttp's connection handler with :class:`HttpGuard`'s admission, sizes and timeouts."""

    def __init__(self, manager: web.Server, *, guard: HttpGuard, **kwargs: Any) -> None:
        super().__init__(manager, **kwargs)
        self._guard = guard
        self._client: Client | None = None
        self._refused = False
        self._handled = 0
        self._busy = False
        self._head_bytes = 0
        self._line_bytes: int | None = None
        self._head_timer: asyncio.TimerHandle | None = None
        self._idle_since = self._loop.time()

    # --- admission --------------------------------------------------------------------------

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        # A TCP transport: uvloop's implements asyncio.Transport's methods without deriving
        # from it, so this is a cast, not an isinstance check (docs/serve.md, "Event loop").
        transport = cast(asyncio.Transport, transport)
        peer = transport.get_extra_info("peername")
        admitted = self._guard.admit(str(peer[0]) if peer else None)
        if isinstance(admitted, Refusal):
            if admitted.forbidden:
                reply = plain_reply(403, f"forbidden: {admitted.reason}")
            else:
                reply = plain_reply(503, f"busy: {admitted.reason}", (("Retry-After", "1"),))
            self._turn_away(transport, reply)
            return
        self._client = admitted
        self._guard.connections[self] = None
        super().connection_made(transport)

    def _turn_away(self, transport: asyncio.Transport, reply: bytes) -> None:
        """Answer, then half-close: closing at once with the request unread would reset the
        connection and could destroy the answer before the client reads it."""
        self._refused = True
        transport.write(reply)
        if transport.can_write_eof():
            transport.write_eof()
        asyncio.get_running_loop().call_later(_TURN_AWAY_GRACE_S, transport.close)

    def connection_lost(self, exc: BaseException | None) -> None:
        self._cancel_head_timer()
        if self._refused and self._client is None:
            return  # turned away before aiohttp saw the connection
        self._guard.connections.pop(self, None)
        if self._client is not None:
            self._client.release()
        super().connection_lost(exc)

    @property
    def client(self) -> Client | None:
        """The access policy's client for this connection (its request rate)."""
        return self._client

    @property
    def busy(self) -> bool:
        """Whether a request is being handled (or is parsed and waiting its turn)."""
        return self._busy or self._request_count != self._handled

    def evictable(self) -> bool:
        if self._busy or self._refused or self._request_count != self._handled:
            return False
        return self._loop.time() - self._idle_since >= EVICTABLE_AFTER_S

    def evict(self) -> None:
        logger.info("%s: closing an idle connection to make room", self._guard.access.name)
        self._guard.connections.pop(self, None)
        if self._client is not None:
            self._client.release()  # frees its slot now; connection_lost releases only once
        self.force_close()

    # --- sizes and head timeout -------------------------------------------------------------

    def data_received(self, data: bytes) -> None:
        if self._refused:
            return
        parsed_before = self._request_count
        counting = parsed_before == self._handled and not self._busy
        if counting:
            if self._head_timer is None:
                self._head_timer = self._loop.call_later(
                    self._guard.header_timeout_s, self._head_too_slow
                )
            self._head_bytes += len(data)
            if self._line_bytes is None and b"\n" in data:
                self._line_bytes = self._head_bytes - len(data) + data.index(b"\n") + 1
            line = self._line_bytes if self._line_bytes is not None else self._head_bytes
            if line > MAX_REQUEST_LINE_BYTES + 2:  # the line and its CRLF
                self._oversized(414, f"request lines are limited to {MAX_REQUEST_LINE_BYTES} bytes")
                return
        super().data_received(data)
        if self._request_count != parsed_before:
            self._head_bytes = 0
            self._line_bytes = None
            self._cancel_head_timer()
        elif (
            counting
            and self._line_bytes is not None
            and self._head_bytes - self._line_bytes > MAX_HEADER_BYTES + _HEAD_SLACK_BYTES
        ):
            self._oversized(431, f"request headers are limited to {MAX_HEADER_BYTES} bytes")

    def _oversized(self, status: int, message: str) -> None:
        self._guard.oversized += 1
        self._cancel_head_timer()
        if self.transport is not None:
            self._turn_away(self.transport, plain_reply(status, message))

    def _head_too_slow(self) -> None:
        self._head_timer = None
        if self._refused or self._busy or self._request_count != self._handled:
            return
        self._guard.timed_out += 1
        timeout = self._guard.header_timeout_s
        logger.info("%s: closing a connection: no complete request within %g s", "HTTP", timeout)
        if self.transport is not None:
            self._turn_away(
                self.transport, plain_reply(408, f"request heads must arrive within {timeout:g} s")
            )

    def _cancel_head_timer(self) -> None:
        if self._head_timer is not None:
            self._head_timer.cancel()
            self._head_timer = None

    async def _handle_request(self, *args: Any, **kwargs: Any) -> Any:
        self._busy = True
        self._cancel_head_timer()
        try:
            return await super()._handle_request(*args, **kwargs)
        finally:
            self._busy = False
            self._handled += 1
            self._idle_since = self._loop.time()

    def handle_error(
        self,
        request: web.BaseRequest,
        status: int = 500,
        exc: BaseException | None = None,
        message: str | None = None,
    ) -> web.StreamResponse:
        """aiohttp's parser errors, with the size statuses a client can act on; a client that
        went away (a closed or reloaded page) is not an error, and gets no traceback."""
        if isinstance(exc, ConnectionError):
            logger.debug("HTTP client %s went away: %s", request.remote, exc)
            gone = web.Response(status=400, text="connection lost")
            gone.force_close()
            return gone
        if isinstance(exc, LineTooLong):
            limit = exc.args[1] if len(exc.args) > 1 else None
            status = 414 if limit == MAX_REQUEST_LINE_BYTES else 431
        elif isinstance(exc, BadHttpMessage) and "Too many headers" in str(exc):
            status = 431
        if status == 500:
            return super().handle_error(request, status, exc, message)
        # A client's malformed request is not our error: no traceback in the log.
        logger.info("HTTP %d to %s: %s", status, request.remote, message or exc)
        text = f"{status}: {message or exc}" if status != 500 else "internal server error"
        response = web.Response(status=status, text=text)
        response.headers["X-Content-Type-Options"] = "nosniff"
        response.force_close()
        return response


class GuardedServer(web.Server):
    """aiohttp's low-level server whose connections go through ``guard``."""

    def __init__(self, handler: Any, *, guard: HttpGuard, **kwargs: Any) -> None:
        super().__init__(handler, **guard.handler_kwargs(), **kwargs)
        self.guard = guard

    def __call__(self) -> GuardedRequestHandler:
        try:
            return GuardedRequestHandler(self, guard=self.guard, loop=self._loop, **self._kwargs)
        except TypeError:  # pragma: no cover - aiohttp changed its keyword arguments
            logger.exception("aiohttp's RequestHandler rejected our limits")
            raise


class GuardedAppRunner(web.AppRunner):
    """An :class:`aiohttp.web.AppRunner` whose server is a :class:`GuardedServer`."""

    def __init__(self, app: web.Application, guard: HttpGuard, **kwargs: Any) -> None:
        super().__init__(app, **kwargs)
        self.guard = guard

    async def _make_server(self) -> web.Server:
        plain = await super()._make_server()
        server_kwargs = {k: v for k, v in plain._kwargs.items() if k not in _GUARD_KEYS}
        return GuardedServer(
            plain.request_handler,
            guard=self.guard,
            request_factory=plain.request_factory,
            handler_cancellation=plain.handler_cancellation,
            loop=plain._loop,
            **server_kwargs,
        )


_GUARD_KEYS = frozenset({"max_line_size", "max_field_size", "keepalive_timeout", "lingering_time"})
