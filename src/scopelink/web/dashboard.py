"""The live web dashboard: an aiohttp server for one mount (``docs/dashboard.md``).

``/`` is the page, ``/static/`` its script and style (package data, served by aiohttp's static
route, which refuses paths outside the folder), ``/api/`` the JSON commands and ``/ws`` the live
updates. Requests from another site's page are refused (``Origin`` must match ``Host``), and
every response forbids framing and foreign scripts.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from importlib import resources
from pathlib import Path
from types import TracebackType
from typing import Self
from urllib.parse import urlsplit

from aiohttp import web
from aiohttp.typedefs import Middleware

from scopelink.decode import Protocol
from scopelink.mount import Mount
from scopelink.servers.access import AccessControl, AccessPolicy, Refusal, retry_after
from scopelink.web.api import Handler, add_api_routes, error_middleware
from scopelink.web.live import LiveHub
from scopelink.web.traffic import DEFAULT_CAPACITY, ProtocolChooser, TrafficMonitor

__all__ = ["Dashboard", "static_dir"]

logger = logging.getLogger(__name__)

_SECURITY_HEADERS = {
    "Content-Security-Policy": (
        "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
        "connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; form-action 'self'"
    ),
    "X-Content-Type-Options": "nosniff",
    "X-Frame-Options": "DENY",
    "Referrer-Policy": "no-referrer",
}


def static_dir() -> Path:
    """Where the page's files are installed."""
    return Path(str(resources.files("scopelink.web") / "static"))


def _trace_protocol(
    mount: Mount, trace: bool | Protocol | ProtocolChooser
) -> Protocol | ProtocolChooser | None:
    if trace is False:
        return None
    if trace is not True:
        return trace
    try:
        return Protocol(mount.identity.protocol)
    except ValueError:  # the simulator: traffic comes only from servers in front of it
        return Protocol.SYNSCAN


@web.middleware
async def _same_origin(request: web.Request, handler: Handler) -> web.StreamResponse:
    """Refuse requests a page of another site makes (cross-site WebSocket or form posts)."""
    origin = request.headers.get("Origin")
    if origin is not None and origin != "null" and urlsplit(origin).netloc != request.host:
        return web.json_response(
            {"error": f"requests from {origin} are not allowed", "kind": "Forbidden"}, status=403
        )
    if origin == "null":
        return web.json_response(
            {"error": "requests from opaque origins are not allowed", "kind": "Forbidden"},
            status=403,
        )
    response = await handler(request)
    response.headers.update(_SECURITY_HEADERS)
    return response


def _access_middleware(control: AccessControl) -> Middleware:
    """The allow-list (403), read-only (403 on every POST), the request rate (held up to the
    policy's ``max_delay_s``, then 429 with Retry-After) and the connection limits for the
    live pages' WebSockets (503)."""

    @web.middleware
    async def access(request: web.Request, handler: Handler) -> web.StreamResponse:
        host = request.remote
        if not control.allows(host):
            return web.json_response(
                {"error": f"{host} may not use this dashboard", "kind": "Forbidden"}, status=403
            )
        if control.read_only and request.method not in ("GET", "HEAD"):
            return web.json_response(
                {"error": "this dashboard is read-only", "kind": "ReadOnly"}, status=403
            )
        wait = control.request_wait(host)
        if wait is None:
            return web.json_response(
                {"error": "too many requests: retry later", "kind": "TooManyRequests"},
                status=429,
                headers={"Retry-After": retry_after(control.retry_after_s(host or ""))},
            )
        if wait:
            await asyncio.sleep(wait)
        if request.path != "/ws":
            return await handler(request)
        # A live page holds its WebSocket open: those count against the connection limits.
        admitted = control.admit(host)
        if isinstance(admitted, Refusal):
            return web.json_response(
                {"error": admitted.reason, "kind": "Busy"}, status=503, headers={"Retry-After": "1"}
            )
        try:
            return await handler(request)
        finally:
            admitted.release()

    return access


class Dashboard:
    """Serve the dashboard for ``mount`` on ``host``:``port`` (0: a free port) while inside
    ``async with``.

    ``trace`` shows the live byte traffic with its decoded meaning: ``True`` decodes it as the
    mount's protocol (SynScan for the simulator, whose traffic is that of the servers in front of
    it), a :class:`~scopelink.decode.Protocol` forces one, a function of the link's trace name
    chooses per link (``None``: show that link's bytes undecoded, e.g. an LX200 server's), and
    ``False`` hides the panel. The mount is
    used as it is: connect it before, disconnect it after. ``access`` (default: no limits)
    applies the servers' allow-list, request rate and read-only mode (the page then disables
    its controls, and the API refuses every command).
    """

    def __init__(
        self,
        mount: Mount,
        host: str = "127.0.0.1",
        port: int = 8080,
        *,
        trace: bool | Protocol | ProtocolChooser = True,
        update_interval_s: float = 0.25,
        traffic_lines: int = DEFAULT_CAPACITY,
        access: AccessPolicy | None = None,
    ) -> None:
        if not 0 <= port <= 65535:
            raise ValueError(f"port {port} must lie in [0, 65535]")
        if not 0.05 <= update_interval_s <= 5.0:
            raise ValueError(f"update interval {update_interval_s} s must lie in [0.05, 5]")
        self.mount = mount
        self.host = host
        self.access = AccessControl(access, "dashboard")
        self._requested_port = port
        protocol = _trace_protocol(mount, trace)
        self.traffic = None if protocol is None else TrafficMonitor(protocol, traffic_lines)
        self.hub = LiveHub(mount, self.traffic, interval_s=update_interval_s)
        self._runner: web.AppRunner | None = None
        self._site: web.TCPSite | None = None
        self._port: int | None = None
        self._tracing = contextlib.ExitStack()

    def build_app(self) -> web.Application:
        """The aiohttp application (also usable with aiohttp's test client)."""
        app = web.Application(
            middlewares=[_same_origin, _access_middleware(self.access), error_middleware]
        )
        index = static_dir() / "index.html"

        async def page(request: web.Request) -> web.FileResponse:
            return web.FileResponse(index, headers={"Cache-Control": "no-cache"})

        async def access(request: web.Request) -> web.Response:
            return web.json_response({"read_only": self.access.read_only})

        app.router.add_get("/", page)
        app.router.add_get("/api/access", access)
        app.router.add_get("/ws", self.hub.handle)
        add_api_routes(app, self.mount)
        app.router.add_static("/static/", static_dir(), follow_symlinks=False)
        return app

    @property
    def port(self) -> int:
        """The port listened on (the one chosen when 0 was asked)."""
        if self._port is None:
            raise RuntimeError("the dashboard is not running")
        return self._port

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    async def start(self) -> None:
        if self._runner is not None:
            raise RuntimeError("the dashboard is already running")
        if self.traffic is not None:
            self._tracing.enter_context(self.traffic.attached())
        runner = web.AppRunner(self.build_app(), access_log=None, handle_signals=False)
        await runner.setup()
        site = web.TCPSite(runner, self.host, self._requested_port)
        try:
            await site.start()
        except BaseException:
            await runner.cleanup()
            self._stop_tracing()
            raise
        self._runner, self._site = runner, site
        server = site._server  # aiohttp keeps the listening sockets here
        sockets = getattr(server, "sockets", None) or []
        self._port = int(sockets[0].getsockname()[1]) if sockets else self._requested_port
        logger.info("dashboard on %s", self.url)

    def _stop_tracing(self) -> None:
        self._tracing.close()

    async def stop(self) -> None:
        """Close every page, stop listening, detach from the trace."""
        await self.hub.close()
        runner, self._runner = self._runner, None
        if runner is not None:
            await runner.cleanup()
        self._port = None
        self._stop_tracing()

    async def __aenter__(self) -> Self:
        await self.start()
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        await self.stop()
