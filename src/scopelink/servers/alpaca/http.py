"""A small HTTP/1.1 server for the Alpaca API: httptools' C parser under an asyncio protocol.

Alpaca clients poll properties many times a second, and a general web framework spends most of
each request on machinery we do not need (a full request object, routing, middleware): aiohttp's
low-level server costs ~100 µs per request here, this one about a third of that. What it does:
keep-alive and pipelined requests answered in order, ``Expect: 100-continue``, a body size limit
(413, connection closed), malformed requests answered 400 and closed. What it leaves out: TLS,
upgrades (400), trailers. Handlers take an :class:`HttpRequest` and return an :class:`HttpReply`.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections import deque
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from http import HTTPStatus
from urllib.parse import parse_qsl, unquote

import httptools

from scopelink.servers.access import AccessControl, Client, Refusal, retry_after

__all__ = ["HttpConnection", "HttpReply", "HttpRequest"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class HttpRequest:
    """One request: the decoded path, the decoded query pairs in order, and the raw body."""

    method: str
    path: str
    query: list[tuple[str, str]]
    body: bytes = b""


@dataclass(frozen=True, slots=True)
class HttpReply:
    status: int
    body: bytes
    content_type: str = "text/plain; charset=utf-8"
    headers: tuple[tuple[str, str], ...] = ()
    """Extra header lines (``Retry-After``)."""

    @classmethod
    def text(cls, status: int, message: str) -> HttpReply:
        return cls(status, message.encode())

    def encode(self, *, keep_alive: bool) -> bytes:
        phrase = _PHRASES.get(self.status) or HTTPStatus(self.status).phrase
        connection = b"" if keep_alive else b"Connection: close\r\n"
        head = (
            f"HTTP/1.1 {self.status} {phrase}\r\nContent-Type: {self.content_type}\r\n"
            # Error texts quote what the client sent: never let a browser sniff them as HTML.
            "X-Content-Type-Options: nosniff\r\n"
            f"Content-Length: {len(self.body)}\r\n"
            + "".join(f"{name}: {value}\r\n" for name, value in self.headers)
        ).encode()
        return head + connection + b"\r\n" + self.body


_PHRASES = {200: "OK", 400: "Bad Request", 404: "Not Found", 405: "Method Not Allowed"}


def _retry_after(status: int, message: str, wait_s: float) -> HttpReply:
    return HttpReply(status, message.encode(), headers=(("Retry-After", retry_after(wait_s)),))


Handler = Callable[[HttpRequest], Awaitable[HttpReply]]


class HttpConnection(asyncio.Protocol):
    """One client connection; requests are handled one after the other, replies in order."""

    def __init__(
        self,
        handle: Handler,
        max_body_bytes: int,
        registry: set[HttpConnection],
        access: AccessControl | None = None,
    ):
        self._handle = handle
        self._access = access if access is not None else AccessControl(name="HTTP")
        self._client: Client | None = None
        self._max_body_bytes = max_body_bytes
        self._registry = registry
        self._parser = httptools.HttpRequestParser(self)
        self._transport: asyncio.Transport | None = None
        self._url = b""
        self._body = bytearray()
        self._content_length = 0
        self._too_large = False
        self._expect_continue = False
        self._queue: deque[tuple[HttpRequest | HttpReply, bool]] = deque()
        self._worker: asyncio.Task[None] | None = None
        self._broken = False

    @property
    def busy(self) -> bool:
        return self._worker is not None and not self._worker.done()

    async def finish(self, grace_s: float) -> None:
        """Let a request in progress finish (up to ``grace_s``), then close the connection."""
        worker = self._worker
        if worker is not None and not worker.done():
            with contextlib.suppress(TimeoutError, asyncio.CancelledError):
                await asyncio.wait_for(asyncio.shield(worker), grace_s)
            worker.cancel()
        if self._transport is not None:
            self._transport.close()

    # --- asyncio.Protocol -------------------------------------------------------------------------

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self._transport = transport
        self._registry.add(self)
        peer = transport.get_extra_info("peername")
        admitted = self._access.admit(str(peer[0]) if peer else None)
        if isinstance(admitted, Refusal):
            if admitted.forbidden:
                reply = HttpReply.text(403, f"forbidden: {admitted.reason}")
            else:
                reply = _retry_after(503, f"busy: {admitted.reason}", 1.0)
            self._turn_away(transport, reply)
            return
        self._client = admitted

    def _turn_away(self, transport: asyncio.Transport, reply: HttpReply) -> None:
        """Answer before reading the request, then half-close. Closing at once would reset the
        connection (the request is unread) and could destroy the answer before it is read; the
        client closes on seeing ``Connection: close``, or we do after a grace period."""
        self._broken = True
        transport.write(reply.encode(keep_alive=False))
        if transport.can_write_eof():
            transport.write_eof()
        asyncio.get_running_loop().call_later(_TURN_AWAY_GRACE_S, transport.close)

    def connection_lost(self, exc: Exception | None) -> None:
        self._registry.discard(self)
        self._transport = None
        if self._client is not None:
            self._client.release()
        if self._worker is not None:
            self._worker.cancel()

    def data_received(self, data: bytes) -> None:
        if self._broken:
            return
        try:
            self._parser.feed_data(data)
        except httptools.HttpParserUpgrade:
            self._refuse(HttpReply.text(400, "protocol upgrades are not supported"))
        except httptools.HttpParserError as error:
            self._refuse(HttpReply.text(400, f"malformed HTTP request: {error}"))

    # --- httptools callbacks ----------------------------------------------------------------------

    def on_message_begin(self) -> None:
        self._url = b""
        self._body = bytearray()
        self._content_length = 0
        self._too_large = False
        self._expect_continue = False

    def on_url(self, url: bytes) -> None:
        self._url += url

    def on_header(self, name: bytes, value: bytes) -> None:
        header = name.lower()
        if header == b"content-length":
            with contextlib.suppress(ValueError):
                self._content_length = int(value)
        elif header == b"expect" and value.strip().lower() == b"100-continue":
            self._expect_continue = True

    def on_headers_complete(self) -> None:
        if self._content_length > self._max_body_bytes:
            # Answer now: the client may wait for this before sending a body we would drop.
            self._too_large = True
            self._refuse_too_large()
        elif self._expect_continue and self._transport is not None:
            self._transport.write(b"HTTP/1.1 100 Continue\r\n\r\n")

    def on_body(self, body: bytes) -> None:
        if self._too_large:
            return
        self._body += body
        if len(self._body) > self._max_body_bytes:
            self._too_large = True
            self._body = bytearray()
            self._refuse_too_large()

    def on_message_complete(self) -> None:
        if self._broken:
            return
        try:
            url = httptools.parse_url(self._url)
        except httptools.HttpParserInvalidURLError:
            self._enqueue(HttpReply.text(400, "malformed request target"), keep_alive=False)
            self._broken = True
            return
        query = url.query.decode("utf-8", "replace") if url.query else ""
        request = HttpRequest(
            method=self._parser.get_method().decode("ascii", "replace"),
            path=unquote(url.path.decode("utf-8", "replace")),
            query=parse_qsl(query, keep_blank_values=True),
            body=bytes(self._body),
        )
        self._enqueue(request, keep_alive=self._parser.should_keep_alive())

    # --- handling ---------------------------------------------------------------------------------

    def _refuse_too_large(self) -> None:
        limit = self._max_body_bytes
        self._refuse(HttpReply.text(413, f"request bodies are limited to {limit} bytes"))

    def _refuse(self, reply: HttpReply) -> None:
        self._broken = True
        self._enqueue(reply, keep_alive=False)

    def _enqueue(self, item: HttpRequest | HttpReply, *, keep_alive: bool) -> None:
        self._queue.append((item, keep_alive))
        if len(self._queue) > _MAX_PIPELINED and self._transport is not None:
            self._transport.pause_reading()
        if not self.busy:
            self._worker = asyncio.get_running_loop().create_task(self._work())

    def _wait_for_turn(self) -> float | None:
        """Seconds to hold this request under the client's rate; None: answer 429."""
        return 0.0 if self._client is None else self._client.admit_request()

    def _too_many(self) -> HttpReply:
        assert self._client is not None
        wait = self._client.retry_after_s()
        return _retry_after(429, "too many requests from this address: retry later", wait)

    def _open_transport(self) -> asyncio.Transport | None:
        return self._transport

    async def _work(self) -> None:
        while self._queue and self._transport is not None:
            item, keep_alive = self._queue.popleft()
            if isinstance(item, HttpReply):
                reply = item
            elif (wait := self._wait_for_turn()) is None:
                reply = self._too_many()
            else:
                if wait:
                    await asyncio.sleep(wait)
                try:
                    reply = await self._handle(item)
                except Exception:
                    logger.exception("HTTP %s %s failed", item.method, item.path)
                    reply = HttpReply.text(500, "internal server error")
            transport = self._open_transport()  # the client may have gone while we worked
            if transport is None:
                return
            transport.write(reply.encode(keep_alive=keep_alive))
            if not keep_alive:
                transport.close()
                return
            if len(self._queue) <= _MAX_PIPELINED:
                transport.resume_reading()


_TURN_AWAY_GRACE_S = 2.0
"""How long a refused connection may stay open for its client to read the refusal."""

_MAX_PIPELINED = 32
"""Requests queued on one connection before it stops reading (back-pressure)."""
