"""The Alpaca HTTP server: device API, management API, setup pages and UDP discovery.

:class:`AlpacaServer` serves one ``telescope/0`` for a :class:`~scopelink.mount.Mount`::

    async with AlpacaServer(mount, port=0, discovery_port=0, state_dir=path) as server:
        print(server.port, server.discovery_port)
        await server.serve_forever()

While it runs it holds ``mount.watching()`` so reads are answered from a fresh state cache.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import logging
import math
from collections.abc import Awaitable, Callable
from pathlib import Path
from types import CoroutineType, TracebackType
from typing import Self
from urllib.parse import parse_qsl

from scopelink import __version__ as scopelink_version
from scopelink.mount import Mount, MountError
from scopelink.servers.access import AccessControl, AccessPolicy
from scopelink.servers.alpaca.discovery import DISCOVERY_PORT, start_discovery
from scopelink.servers.alpaca.errors import (
    AlpacaError,
    BadRequest,
    ErrorNumber,
    from_mount_error,
)
from scopelink.servers.alpaca.http import AlpacaHttpFront, HttpReply, HttpRequest
from scopelink.servers.alpaca.identity import default_state_dir, load_or_create_unique_id
from scopelink.servers.alpaca.params import Params, parse_transaction_id
from scopelink.servers.alpaca.setup_page import render_setup_page
from scopelink.servers.alpaca.telescope import Member, TelescopeConfig, TelescopeDevice
from scopelink.servers.hosts import HostAllowList
from scopelink.servers.http_guard import MAX_BODY_BYTES, GuardedServer, HttpGuard

__all__ = ["ALPACA_PORT", "MAX_REQUEST_BYTES", "AlpacaServer", "StateDirError"]

logger = logging.getLogger(__name__)

ALPACA_PORT = 11111
MAX_REQUEST_BYTES = MAX_BODY_BYTES
"""Largest request body accepted (HTTP 413 above it); real Alpaca requests are < 1 KiB."""
_API_PREFIX = "/api/v1/"
_DEVICE_TYPE = "telescope"
_JSON = "application/json; charset=utf-8"
_METHODS = ("GET", "PUT")
_SETUP_PAGE_HEADERS = (
    # The page is static text: no script, style, image or frame may ever run in it.
    ("Content-Security-Policy", "default-src 'none'; frame-ancestors 'none'; form-action 'none'"),
    ("X-Frame-Options", "DENY"),
    ("Referrer-Policy", "no-referrer"),
)
_READ_ONLY_PUTS = frozenset({"connected", "connect", "disconnect"})
"""PUTs a read-only server still takes: they open or close the client's session, not the mount."""


class StateDirError(ValueError):
    """The state directory cannot hold the Alpaca UniqueID (the message says why and what to
    do)."""


def _load_unique_id(state_dir: Path) -> str:
    try:
        return load_or_create_unique_id(state_dir)
    except ValueError as error:  # a corrupt file: the message names it and the fix
        raise StateDirError(str(error)) from None
    except (NotADirectoryError, FileExistsError):
        raise StateDirError(
            f"the Alpaca state directory {state_dir} (or a folder above it) is a file: move that "
            "file away, or name another directory with --state-dir DIR"
        ) from None
    except OSError as error:
        raise StateDirError(
            f"cannot keep the Alpaca UniqueID in {state_dir}: {error.strerror or error}; "
            "name a writable directory with --state-dir DIR"
        ) from None


def _json_value(value: object) -> str:
    """JSON for a Value: floats by repr (the shortest exact form), the rest by json.dumps."""
    if type(value) is float and math.isfinite(value):
        return repr(value)
    if value is True:
        return "true"
    if value is False:
        return "false"
    return json.dumps(value, allow_nan=False)


def _text(status: int, message: str) -> HttpReply:
    return HttpReply.text(status, message)


class AlpacaServer:
    """ASCOM Alpaca for ``mount`` on ``host:port`` (0 picks a free port), as ``telescope/0``.

    ``discovery_port=None`` turns discovery off; it listens on ``discovery_host`` (default
    ``host``). ``state_dir`` holds the persistent UniqueID (default: ``$XDG_STATE_HOME/scopelink``).
    ``access`` (default: no limits) decides who connects (403 otherwise; discovery ignores them),
    how many (503), how fast (held up to its ``max_delay_s``, then 429 with Retry-After) and
    whether PUTs that change the mount are refused (ASCOM InvalidOperation, 0x40B).
    """

    def __init__(
        self,
        mount: Mount,
        *,
        host: str = "127.0.0.1",
        port: int = ALPACA_PORT,
        discovery_port: int | None = DISCOVERY_PORT,
        discovery_host: str | None = None,
        state_dir: Path | None = None,
        config: TelescopeConfig | None = None,
        max_request_bytes: int = MAX_REQUEST_BYTES,
        access: AccessPolicy | None = None,
        allowed_hosts: tuple[str, ...] = (),
    ) -> None:
        self.mount = mount
        self.host = host
        self.port = port
        self.discovery_port = discovery_port
        self._discovery_host = discovery_host or host
        self.state_dir = state_dir if state_dir is not None else default_state_dir()
        self.config = config or TelescopeConfig()
        self.telescope = TelescopeDevice(mount, self.config)
        self.unique_id = ""
        self._max_request_bytes = max_request_bytes
        self.access = AccessControl(access, "Alpaca")
        self.guard = HttpGuard(self.access)
        self.hosts = HostAllowList(host, allowed_hosts)
        """The ``Host`` names answered (others get 421: DNS rebinding)."""
        self._transactions = itertools.count(1)
        self._http: GuardedServer | None = None
        self._listener: asyncio.Server | None = None
        self._pages: dict[str, Callable[[HttpRequest], Awaitable[HttpReply]]] = {
            "/management/apiversions": self._api_versions,
            "/management/v1/description": self._description,
            "/management/v1/configureddevices": self._configured_devices,
            "/setup": self._setup,
            "/setup/v1/telescope/0/setup": self._setup,
        }
        self._discovery: asyncio.DatagramTransport | None = None
        self._stack = contextlib.AsyncExitStack()

    @property
    def url(self) -> str:
        return f"http://{self.host}:{self.port}"

    # --- lifecycle -------------------------------------------------------------------------------

    async def start(self) -> None:
        self.unique_id = _load_unique_id(self.state_dir)
        # Reads are answered from mount.state: keep the mount's poller running while we serve.
        await self._stack.enter_async_context(self.mount.watching())
        # aiohttp's low-level server, guarded (http_guard.py), with our own dispatch: no router
        # or middleware on the path of the property reads clients poll many times a second.
        loop = asyncio.get_running_loop()
        front = AlpacaHttpFront(self._handle, self.access, self.hosts, self._max_request_bytes)
        self._http = GuardedServer(front, guard=self.guard, access_log=None)
        self._listener = await loop.create_server(
            self._http, self.host, self.port, reuse_address=True
        )
        self.port = int(self._listener.sockets[0].getsockname()[1])
        if self.discovery_port is not None:
            transport, _ = await start_discovery(
                self._discovery_host, self.discovery_port, self.port, admits=self.access.allows
            )
            self._discovery = transport
            self.discovery_port = int(transport.get_extra_info("sockname")[1])
        logger.info("Alpaca telescope on %s (discovery port %s)", self.url, self.discovery_port)

    async def close(self) -> None:
        if self._discovery is not None:
            self._discovery.close()
            self._discovery = None
        if self._listener is not None:
            self._listener.close()
            # Idle keep-alive connections close now; a synchronous slew in progress gets 1 s.
            if self._http is not None:
                self._http.pre_shutdown()  # wakes idle connections so that they close now
                await self._http.shutdown(1.0)
            await self._listener.wait_closed()
            self._listener = None
        await self.telescope.close()
        await self._stack.aclose()

    async def serve_forever(self) -> None:
        await asyncio.Event().wait()

    async def __aenter__(self) -> Self:
        try:
            await self.start()
        except BaseException:
            await self.close()
            raise
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        await self.close()

    # --- replies ---------------------------------------------------------------------------------

    def _reply(
        self,
        client_transaction_id: int,
        *,
        value: object = None,
        has_value: bool = False,
        error: AlpacaError | None = None,
    ) -> HttpReply:
        # Assembled by hand: property reads are the hot path, and json.dumps of a whole dict
        # costs more than the rest of our handling together.
        server_id = next(self._transactions)
        if error is None:
            head = f'{{"Value":{_json_value(value)},' if has_value else "{"
            text = (
                f'{head}"ClientTransactionID":{client_transaction_id},'
                f'"ServerTransactionID":{server_id},"ErrorNumber":0,"ErrorMessage":""}}'
            )
        else:
            text = (
                f'{{"ClientTransactionID":{client_transaction_id},'
                f'"ServerTransactionID":{server_id},"ErrorNumber":{int(error.number)},'
                f'"ErrorMessage":{json.dumps(error.message)}}}'
            )
        return HttpReply(200, text.encode(), _JSON)

    @staticmethod
    def _query_ids(request: HttpRequest) -> tuple[int, int]:
        params = Params.from_pairs(request.query, exact=False)
        client_id = parse_transaction_id("ClientID", params.optional("ClientID"))
        transaction = parse_transaction_id(
            "ClientTransactionID", params.optional("ClientTransactionID")
        )
        return client_id, transaction

    # --- device API ------------------------------------------------------------------------------

    async def _handle(self, request: HttpRequest) -> HttpReply:
        path = request.path
        if path.startswith(_API_PREFIX):
            parts = path[len(_API_PREFIX) :].split("/")
            if len(parts) == 3:
                return await self._api(request, *parts)
        page = self._pages.get(path)
        if page is None:
            return _text(404, f"nothing at {path} (Alpaca devices are under {_API_PREFIX})")
        if request.method != "GET":
            return _text(405, f"{path} is read with GET")
        return await page(request)

    async def _api(
        self, request: HttpRequest, device_type: str, number: str, name: str
    ) -> HttpReply:
        if device_type != _DEVICE_TYPE:
            return _text(404, f"no device of type {device_type!r} here (only 'telescope')")
        if number != "0":
            return _text(404, f"no telescope number {number!r} here (only 0)")
        member = self.telescope.members.get(name)
        if member is None:
            return _text(404, f"the telescope has no member {name!r}")
        if request.method not in _METHODS:
            return _text(405, f"{request.method} is not an Alpaca method: use GET or PUT")
        try:
            if request.method == "GET":
                params = Params.from_pairs(request.query, exact=False)
            else:
                params = self._form(request)
            client_id = params.optional("ClientID")
            parse_transaction_id("ClientID", client_id)
            transaction = parse_transaction_id(
                "ClientTransactionID", params.optional("ClientTransactionID")
            )
            return await self._invoke(request.method, member, name, params, transaction)
        except BadRequest as error:
            return _text(400, str(error))

    @staticmethod
    def _form(request: HttpRequest) -> Params:
        # The size limit is enforced while the body arrives (http.py answers 413).
        try:
            text = request.body.decode("utf-8")
            pairs = parse_qsl(text, keep_blank_values=True, strict_parsing=False)
        except (UnicodeDecodeError, ValueError):
            raise BadRequest("the PUT body must be UTF-8 form data (name=value&...)") from None
        return Params.from_pairs(pairs, exact=True)

    async def _invoke(
        self, method: str, member: Member, name: str, params: Params, transaction: int
    ) -> HttpReply:
        handler = member.get if method == "GET" else member.put
        if handler is None:
            other = "PUT" if method == "GET" else "GET"
            return _text(405, f"{name} takes {other}, not {method}")
        if method == "PUT" and self.access.read_only and name not in _READ_ONLY_PUTS:
            refusal = AlpacaError(
                ErrorNumber.INVALID_OPERATION, f"{name}: this server is read-only"
            )
            return self._reply(transaction, error=refusal)
        try:
            if member.needs_connection:
                self.telescope.require_connected()
            value = handler(params)
            if type(value) is CoroutineType:  # an async handler (the cheapest test there is)
                value = await value
        except AlpacaError as error:
            return self._reply(transaction, error=error)
        except MountError as error:
            return self._reply(transaction, error=from_mount_error(error))
        except BadRequest:
            raise
        except Exception as error:
            logger.exception("Alpaca %s %s failed", method, name)
            failure = AlpacaError(ErrorNumber.DRIVER_ERROR, f"internal error: {error}")
            return self._reply(transaction, error=failure)
        has_value = method == "GET" or value is not None
        return self._reply(transaction, value=value, has_value=has_value)

    # --- management API and setup pages ----------------------------------------------------------

    async def _management(self, request: HttpRequest, value: object) -> HttpReply:
        try:
            _, transaction = self._query_ids(request)
        except BadRequest as error:
            return _text(400, str(error))
        return self._reply(transaction, value=value, has_value=True)

    async def _api_versions(self, request: HttpRequest) -> HttpReply:
        return await self._management(request, [1])

    async def _description(self, request: HttpRequest) -> HttpReply:
        description = {
            "ServerName": "scopelink",
            "Manufacturer": "scopelink developers",
            "ManufacturerVersion": scopelink_version,
            "Location": (
                f"{self.mount.site.latitude_deg:.4f}, {self.mount.site.longitude_deg:.4f}"
            ),
        }
        return await self._management(request, description)

    async def _configured_devices(self, request: HttpRequest) -> HttpReply:
        devices = [
            {
                "DeviceName": self.config.name,
                "DeviceType": "Telescope",
                "DeviceNumber": 0,
                "UniqueID": self.unique_id,
            }
        ]
        return await self._management(request, devices)

    async def _setup(self, _: HttpRequest) -> HttpReply:
        page = render_setup_page(
            self.mount,
            self.config,
            unique_id=self.unique_id,
            port=self.port,
            discovery_port=self.discovery_port,
        )
        return HttpReply(200, page.encode(), "text/html; charset=utf-8", _SETUP_PAGE_HEADERS)
