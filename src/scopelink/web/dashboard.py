"""The live web dashboard: an aiohttp server for one mount (``docs/dashboard.md``).

``/`` is the page, ``/static/`` its script and style (package data, served by aiohttp's static
route, which refuses paths outside the folder), ``/api/`` the JSON commands and ``/ws`` the live
updates. Requests for a ``Host`` that is not this machine's are answered 421 (DNS rebinding),
requests from another site's page 403 (``Origin`` must be this server), and every response
forbids framing and foreign scripts. Bound beyond loopback, commands from other machines need
the pairing token ``scopelink serve`` prints (``/pair?token=...`` sets it as a cookie); reads
stay open.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import ipaddress
import logging
import secrets
from importlib import resources
from pathlib import Path
from types import TracebackType
from typing import Self
from urllib.parse import urlsplit

from aiohttp import web
from aiohttp.typedefs import Middleware

from scopelink.decode import Protocol
from scopelink.mount import Mount
from scopelink.servers.access import AccessControl, AccessPolicy, retry_after
from scopelink.servers.hosts import WARNED_MISDIRECTED, HostAllowList, machine_addresses
from scopelink.servers.http_guard import MAX_BODY_BYTES, GuardedAppRunner, HttpGuard
from scopelink.web.api import Handler, add_api_routes, error_middleware
from scopelink.web.deepsky import add_deep_sky_route
from scopelink.web.live import LiveHub
from scopelink.web.live_opens import LiveOpens
from scopelink.web.panel_api import add_panel_routes
from scopelink.web.site_check import SiteStore
from scopelink.web.skycommander import add_skycommander_routes
from scopelink.web.traffic import DEFAULT_CAPACITY, ProtocolChooser, TrafficMonitor

__all__ = ["PAIRING_HEADER", "Dashboard", "static_dir"]

logger = logging.getLogger(__name__)

PAIRING_HEADER = "X-Scopelink-Pairing"
"""A request header that can carry the pairing token instead of the cookie (scripts)."""
PAIRING_TOKEN_BYTES = 16
"""128 random bits: not guessable at any request rate the limits allow."""
PAIRING_DAYS = 30
"""How long a paired browser stays paired (the token changes with every start of serve)."""

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


def _forbidden(message: str, kind: str = "Forbidden", status: int = 403) -> web.Response:
    return web.json_response({"error": message, "kind": kind}, status=status)


def _host_and_origin(hosts: HostAllowList) -> Middleware:
    """421 for a ``Host`` that is not ours; 403 for requests a page of another site makes
    (``Origin`` must name this very server: one of our hosts, and the request's own)."""

    misdirected = [0]

    @web.middleware
    async def same_origin(request: web.Request, handler: Handler) -> web.StreamResponse:
        host = request.headers.get("Host")
        if not hosts.allows(host):
            misdirected[0] += 1
            # A rebinding page retries: warn on the first few, not on every one.
            level = logging.WARNING if misdirected[0] <= WARNED_MISDIRECTED else logging.DEBUG
            logger.log(
                level, "dashboard: request for Host %r from %s refused", host, request.remote
            )
            return _forbidden(
                f"this dashboard does not answer to {host!r}: open it by this machine's name or "
                "address, or list the name in servers.allowed_hosts",
                "MisdirectedRequest",
                421,
            )
        origin = request.headers.get("Origin")
        if origin == "null":
            return _forbidden("requests from opaque origins are not allowed")
        if origin is not None:
            try:
                authority = urlsplit(origin).netloc
            except ValueError:  # "http://[12..." (found by the dashboard-http fuzz target)
                authority = None
            if authority is None or authority != host or not hosts.allows_origin(authority):
                return _forbidden(f"requests from {origin} are not allowed")
        if request.content_length is not None and request.content_length > MAX_BODY_BYTES:
            return _forbidden(
                f"request bodies are limited to {MAX_BODY_BYTES} bytes", "TooLarge", 413
            )
        response = await handler(request)
        response.headers.update(_SECURITY_HEADERS)
        return response

    return same_origin


def _is_loopback(peer: str | None) -> bool:
    if peer is None:
        return True
    try:
        return ipaddress.ip_address(peer.split("%", 1)[0]).is_loopback
    except ValueError:
        return False


def _access_middleware(control: AccessControl, opens: LiveOpens | None) -> Middleware:
    """The allow-list (403), read-only (403 on every POST), the request rate (held up to the
    policy's ``max_delay_s``, then 429 with Retry-After) and, given ``opens``, how often the
    live connection may be opened (429). Connection limits (503) are the guard's
    (``servers/http_guard.py``), applied when a connection is made."""

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
        if opens is not None and request.path == "/ws":
            again = opens.admit(host)
            if again is not None:
                return web.json_response(
                    {"error": "live connections opened too often: retry later", "kind": "TooMany"},
                    status=429,
                    headers={"Retry-After": retry_after(again)},
                )
        # Connections (a live page's WebSocket among them) were counted when they were made.
        return await handler(request)

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
    its controls, and the API refuses every command). ``site_store`` is where the page's
    first-run check saves the site (``scopelink.web.site_check``; None: the page never asks).
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
        allowed_hosts: tuple[str, ...] = (),
        pairing_token: str | None = None,
        pairing_exempts_loopback: bool = True,
        site_store: SiteStore | None = None,
    ) -> None:
        if not 0 <= port <= 65535:
            raise ValueError(f"port {port} must lie in [0, 65535]")
        if not 0.05 <= update_interval_s <= 5.0:
            raise ValueError(f"update interval {update_interval_s} s must lie in [0.05, 5]")
        self.mount = mount
        self.host = host
        self.access = AccessControl(access, "dashboard")
        self._opens = LiveOpens() if access is not None else None
        """How often the live connection may be opened (only under a policy, as every limit)."""
        self.guard = HttpGuard(self.access)
        self.hosts = HostAllowList(host, allowed_hosts)
        if pairing_token is None and self.hosts.beyond_loopback:
            pairing_token = secrets.token_urlsafe(PAIRING_TOKEN_BYTES)
        self.pairing_token = pairing_token or None
        """What other machines' browsers must present to command the mount (None: not needed,
        the dashboard is on loopback only)."""
        self._loopback_exempt = pairing_exempts_loopback
        """A browser on this machine needs no token (tests turn this off to see a refusal)."""
        self._requested_port = port
        self.site_store = site_store
        """Where the first-run check saves the site (None: the page never asks)."""
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
            middlewares=[
                _host_and_origin(self.hosts),
                _access_middleware(self.access, self._opens),
                self._pairing_middleware(),
                error_middleware,
            ],
            client_max_size=MAX_BODY_BYTES,
        )
        index = static_dir() / "index.html"

        async def page(request: web.Request) -> web.FileResponse:
            return web.FileResponse(index, headers={"Cache-Control": "no-cache"})

        async def access(request: web.Request) -> web.Response:
            return web.json_response({"read_only": self.access.read_only})

        app.router.add_get("/", page)
        add_panel_routes(app, self.mount, self.hub, self.site_store)  # and /api/setup
        app.router.add_get("/api/access", access)
        app.router.add_get("/pair", self._pair)
        app.router.add_get("/ws", self.hub.handle)
        add_api_routes(app, self.mount)
        add_skycommander_routes(app, self.mount)
        add_deep_sky_route(app)
        app.router.add_static("/static/", static_dir(), follow_symlinks=False)
        return app

    @property
    def port(self) -> int:
        """The port listened on (the one chosen when 0 was asked)."""
        if self._port is None:
            raise RuntimeError("the dashboard is not running")
        return self._port

    # --- pairing ------------------------------------------------------------------------------

    @property
    def _cookie(self) -> str:
        return f"scopelink_pair_{self._port or self._requested_port}"

    def _paired(self, request: web.Request) -> bool:
        """Whether ``request`` may command the mount: no token needed (loopback-only dashboard,
        or a browser on this machine), or it carries the token (cookie or header)."""
        token = self.pairing_token
        if token is None or (self._loopback_exempt and _is_loopback(request.remote)):
            return True
        presented = request.cookies.get(self._cookie) or request.headers.get(PAIRING_HEADER) or ""
        return hmac.compare_digest(presented.encode(), token.encode())

    def _pairing_middleware(self) -> Middleware:
        @web.middleware
        async def pairing(request: web.Request, handler: Handler) -> web.StreamResponse:
            if request.method in ("GET", "HEAD") or self._paired(request):
                return await handler(request)
            return _forbidden(
                "this dashboard's controls need pairing: open the pairing link (or scan the QR "
                "code) that 'scopelink serve' printed",
                "NotPaired",
                401,
            )

        return pairing

    async def _pair(self, request: web.Request) -> web.StreamResponse:
        """``/pair?token=T``: remember the token in this browser, then show the dashboard."""
        token = self.pairing_token
        given = request.query.get("token", "")
        if token is None or not hmac.compare_digest(given.encode(), token.encode()):
            return _forbidden("wrong pairing token: use the link 'scopelink serve' printed")
        redirect = web.HTTPSeeOther("/")
        redirect.set_cookie(
            self._cookie,
            token,
            httponly=True,
            samesite="Strict",
            path="/",
            max_age=PAIRING_DAYS * 86400,
        )
        raise redirect

    @property
    def pairing_url(self) -> str | None:
        """The link (and QR code) ``serve`` prints for phones and other machines."""
        if self.pairing_token is None:
            return None
        host = self.host
        if host in ("0.0.0.0", "::", ""):
            addresses = sorted(
                a for a in machine_addresses() if ":" not in a and not a.startswith("127.")
            )
            host = addresses[0] if addresses else host
        shown = f"[{host}]" if ":" in host else host
        return f"http://{shown}:{self.port}/pair?token={self.pairing_token}"

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    async def start(self) -> None:
        if self._runner is not None:
            raise RuntimeError("the dashboard is already running")
        if self.traffic is not None:
            self._tracing.enter_context(self.traffic.attached())
        runner = GuardedAppRunner(
            self.build_app(), self.guard, access_log=None, handle_signals=False
        )
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
