"""The Alpaca server's HTTP front: aiohttp's low-level server, guarded, and our own dispatch.

aiohttp parses HTTP/1.1 (keep-alive, pipelining answered in order, chunked bodies); the guard
(:mod:`scopelink.servers.http_guard`) admits connections and bounds sizes and times. What this
adds per request, before the Alpaca dispatch sees it: the ``Host`` allow-list (421), the
request rate (held up to the policy's ``max_delay_s``, then 429 with ``Retry-After``),
``Expect: 100-continue`` and the body limit (413, connection closed). Handlers take an
:class:`HttpRequest` and return an :class:`HttpReply`: small values, no framework objects, so the
dispatch is tested without HTTP.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from urllib.parse import parse_qsl

from aiohttp import web

from scopelink.servers.access import AccessControl, retry_after
from scopelink.servers.hosts import WARNED_MISDIRECTED, HostAllowList
from scopelink.servers.http_guard import MAX_BODY_BYTES, GuardedRequestHandler

__all__ = ["AlpacaHttpFront", "HttpReply", "HttpRequest"]

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
    """Extra header lines (``Retry-After``, the setup page's security headers)."""

    @classmethod
    def text(cls, status: int, message: str) -> HttpReply:
        return cls(status, message.encode())

    def response(self, *, close: bool = False) -> web.Response:
        response = web.Response(status=self.status, body=self.body)
        headers = response.headers
        headers["Content-Type"] = self.content_type
        # Error texts quote what the client sent: never let a browser sniff them as HTML.
        headers["X-Content-Type-Options"] = "nosniff"
        for name, value in self.headers:
            headers[name] = value
        if close:
            response.force_close()
        return response


Handler = Callable[[HttpRequest], Awaitable[HttpReply]]


class AlpacaHttpFront:
    """The aiohttp request handler in front of an Alpaca dispatch ``handle``."""

    def __init__(
        self,
        handle: Handler,
        access: AccessControl,
        hosts: HostAllowList,
        max_body_bytes: int = MAX_BODY_BYTES,
    ) -> None:
        self._handle = handle
        self._access = access
        self.hosts = hosts
        self._max_body_bytes = max_body_bytes
        self.misdirected = 0
        """Requests answered 421 (a Host that is not ours: DNS rebinding, a wrong proxy)."""

    async def __call__(self, request: web.BaseRequest) -> web.StreamResponse:
        host = request.headers.get("Host")
        if not self.hosts.allows(host):
            self.misdirected += 1
            # A page trying DNS rebinding retries: warn on the first few, not on every one.
            level = logging.WARNING if self.misdirected <= WARNED_MISDIRECTED else logging.DEBUG
            logger.log(
                level, "Alpaca: request for Host %r from %s refused (421)", host, request.remote
            )
            message = f"this server does not answer to {host!r} (see servers.allowed_hosts)"
            return HttpReply.text(421, message).response(close=True)
        if request.headers.get("Upgrade"):
            return HttpReply.text(400, "protocol upgrades are not supported").response(close=True)
        protocol = request.protocol
        client = protocol.client if isinstance(protocol, GuardedRequestHandler) else None
        if client is not None:
            wait = client.admit_request()
            if wait is None:
                seconds = retry_after(client.retry_after_s())
                reply = HttpReply(
                    429,
                    b"too many requests from this address: retry later",
                    headers=(("Retry-After", seconds),),
                )
                return reply.response()
            if wait:
                await asyncio.sleep(wait)
        body = b""
        if request.body_exists:
            read = await self._body(request)
            if isinstance(read, web.Response):
                return read
            body = read
        item = HttpRequest(
            method=request.method,
            path=request.path,
            query=parse_qsl(request.query_string, keep_blank_values=True),
            body=body,
        )
        try:
            reply = await self._handle(item)
        except Exception:
            logger.exception("HTTP %s %s failed", item.method, item.path)
            reply = HttpReply.text(500, "internal server error")
        return reply.response()

    async def _body(self, request: web.BaseRequest) -> bytes | web.Response:
        limit = self._max_body_bytes
        too_large = HttpReply.text(413, f"request bodies are limited to {limit} bytes")
        length = request.content_length
        if length is not None and length > limit:
            # Answer now: the client may wait for this before sending a body we would drop.
            return too_large.response(close=True)
        if request.headers.get("Expect", "").strip().lower() == "100-continue":
            await request.writer.write(b"HTTP/1.1 100 Continue\r\n\r\n")
        chunks: list[bytes] = []
        size = 0
        try:
            while chunk := await request.content.readany():
                size += len(chunk)
                if size > limit:
                    return too_large.response(close=True)
                chunks.append(chunk)
        except ConnectionError:  # the client left mid-body: nobody to answer, nothing to log
            return HttpReply.text(400, "incomplete body").response(close=True)
        return b"".join(chunks)
