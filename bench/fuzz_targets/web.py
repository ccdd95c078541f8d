"""HTTP targets: Alpaca's parameters and its guarded HTTP stack, the dashboard's HTTP stack and
its JSON bodies."""

from __future__ import annotations

import asyncio
import logging
import random
import re
import typing
from collections.abc import Callable
from urllib.parse import parse_qsl

from aiohttp import web

from bench.fuzz_targets.base import (
    FuzzFailureError,
    Target,
    chunks,
    event_loop,
    expect,
)
from scopelink.astro import Site
from scopelink.mount import MountAxis, TrackingMode
from scopelink.servers.access import AccessControl
from scopelink.servers.alpaca.errors import AlpacaError, BadRequest
from scopelink.servers.alpaca.http import AlpacaHttpFront, HttpReply, HttpRequest
from scopelink.servers.alpaca.params import UINT32_MAX, Params, parse_transaction_id
from scopelink.servers.hosts import HostAllowList
from scopelink.servers.http_guard import (
    GuardedAppRunner,
    GuardedRequestHandler,
    GuardedServer,
    HttpGuard,
)
from scopelink.web.params import BadRequestError, read_body

_ALPACA_NAMES = (
    "ClientID",
    "ClientTransactionID",
    "Connected",
    "Tracking",
    "RightAscension",
    "Declination",
    "Azimuth",
    "Altitude",
    "Axis",
    "Rate",
    "Direction",
    "Duration",
    "TrackingRate",
    "SideOfPier",
)


def _read_alpaca_params(params: Params, rng: random.Random) -> None:
    """Every typed read the telescope's members make, each one allowed only its documented
    errors (BadRequest: HTTP 400; AlpacaError: InvalidValue)."""
    names = list(_ALPACA_NAMES) + list(params.values)
    for name in rng.sample(names, min(len(names), 6)):
        for read in ("id", "text", "boolean", "number", "integer"):
            try:
                match read:
                    case "id":
                        value = parse_transaction_id(name, params.optional(name))
                        expect(0 <= value <= UINT32_MAX, f"transaction id {value}")
                    case "text":
                        params.text(name)
                    case "boolean":
                        expect(isinstance(params.boolean(name), bool), "boolean")
                    case "number":
                        number = params.number(name, -90.0, 90.0)
                        expect(-90.0 <= number <= 90.0, f"number {number} out of range")
                    case "integer":
                        integer = params.integer(name, 0, 3)
                        expect(0 <= integer <= 3, f"integer {integer} out of range")
            except (BadRequest, AlpacaError):
                pass


def check_alpaca_params(data: bytes, rng: random.Random) -> None:
    """Query strings and PUT form bodies -> Params -> typed values."""
    text = data.decode("utf-8", "replace")
    exact = rng.random() < 0.5
    params = Params.from_pairs(parse_qsl(text, keep_blank_values=True), exact=exact)
    _read_alpaca_params(params, rng)


class _Transport(asyncio.Transport):
    """Collects what the connection writes; the target is the HTTP stack, not a socket."""

    def __init__(self) -> None:
        super().__init__()
        self.written = bytearray()
        self.closed = False
        self.eof = False

    def write(self, data: bytes | bytearray | memoryview) -> None:
        expect(not self.closed and not self.eof, "wrote after close")
        self.written += data

    def close(self) -> None:
        self.closed = True

    def is_closing(self) -> bool:
        return self.closed

    def can_write_eof(self) -> bool:
        return True

    def write_eof(self) -> None:
        self.eof = True

    def get_extra_info(self, name: str, default: object = None) -> object:
        return ("127.0.0.1", 50000) if name == "peername" else default

    def pause_reading(self) -> None:
        pass

    def resume_reading(self) -> None:
        pass


async def _echo_params(request: HttpRequest) -> HttpReply:
    """A handler that reads what the Alpaca server reads: query or form parameters."""
    if request.method == "PUT":
        pairs = parse_qsl(request.body.decode("utf-8", "replace"), keep_blank_values=True)
        params = Params.from_pairs(pairs, exact=True)
    else:
        params = Params.from_pairs(request.query, exact=False)
    _read_alpaca_params(params, random.Random(len(request.path)))
    return HttpReply(200, b'{"ErrorNumber":0}', "application/json")


_HTTP_MAX_BODY = 1024
_HTTP_REQUESTS = (
    b"GET /api/v1/telescope/0/rightascension?ClientID=1&ClientTransactionID=7 HTTP/1.1\r\n"
    b"Host: 127.0.0.1\r\n\r\n",
    b"PUT /api/v1/telescope/0/slewtocoordinatesasync HTTP/1.1\r\nHost: x\r\n"
    b"Content-Type: application/x-www-form-urlencoded\r\nContent-Length: 40\r\n\r\n"
    b"RightAscension=12.5&Declination=-30&Cl=1",
    b"PUT /api/v1/telescope/0/tracking HTTP/1.1\r\nHost: x\r\nExpect: 100-continue\r\n"
    b"Transfer-Encoding: chunked\r\n\r\n5\r\nTrack\r\n9\r\ning=False\r\n0\r\n\r\n",
    b"GET /management/apiversions HTTP/1.1\r\nHost: [::1]:11111\r\nConnection: keep-alive\r\n\r\n",
    b"GET /setup HTTP/1.0\r\n\r\n",  # not kept alive: only ever last in a valid stream
)


def check_alpaca_http(data: bytes, rng: random.Random) -> None:
    """Raw bytes into one guarded aiohttp connection: replies well formed, no crash logged;
    then valid pipelined requests on a fresh connection get one 200 each (after any 100)."""
    crashes: list[dict[str, object]] = []
    event_loop().set_exception_handler(lambda _, context: crashes.append(context))
    _HTTP_ERRORS.clear()
    statuses = _statuses(_serve(data, rng))
    expect(not crashes, f"the event loop saw {crashes!r}")
    expect(not _HTTP_ERRORS, f"logged as errors: {_HTTP_ERRORS[:3]}")
    expect(500 not in statuses, "a request reached 'internal server error'")
    valid = [rng.choice(_HTTP_REQUESTS[:-1]) for _ in range(rng.randint(1, 3))]
    stream = b"".join(valid)
    expected = [100] * stream.count(b"100-continue") + [200] * len(valid)
    statuses = _statuses(_serve(stream, rng))
    expect(sorted(statuses) == expected, f"valid requests answered {statuses}")
    expect(statuses[-1] == 200 and not crashes, f"valid requests answered {statuses}, {crashes}")


def _alpaca_server() -> GuardedServer:
    front = AlpacaHttpFront(
        _echo_params, AccessControl(), HostAllowList("127.0.0.1", ("x",)), _HTTP_MAX_BODY
    )
    return GuardedServer(front, guard=HttpGuard(AccessControl()), access_log=None)


def _serve(
    stream: bytes, rng: random.Random, make_server: Callable[[], GuardedServer] = _alpaca_server
) -> bytes:
    return event_loop().run_until_complete(_serve_on_loop(stream, rng, make_server))


async def _serve_on_loop(
    stream: bytes, rng: random.Random, make_server: Callable[[], GuardedServer]
) -> bytes:
    """The real guarded aiohttp connection handler (Alpaca's front, or the dashboard's app), on
    a transport that records what it writes. Afterwards nothing of the connection is left in the
    guard: memory stays bounded however many inputs run."""
    transport = _Transport()
    server = make_server()
    connection = server()
    connection.connection_made(transport)
    try:
        for chunk in chunks(stream, rng):
            if transport.closed:
                break
            connection.data_received(chunk)
            await _settle(connection, transport)
        await _settle(connection, transport)
    finally:
        connection.connection_lost(None)
        await asyncio.sleep(0)
    expect(not server.guard.connections, "a closed connection stayed registered")
    return bytes(transport.written)


_DASHBOARD_REQUESTS = (
    b"GET /api/state HTTP/1.1\r\nHost: 127.0.0.1:8080\r\n\r\n",
    b"GET /api/search?q=M31 HTTP/1.1\r\nHost: localhost\r\nAccept: */*\r\n\r\n",
    b"POST /api/tracking HTTP/1.1\r\nHost: 127.0.0.1\r\nOrigin: http://127.0.0.1\r\n"
    b'Content-Type: application/json\r\nContent-Length: 20\r\n\r\n{"mode": "sidereal"}',
    b"POST /api/abort HTTP/1.1\r\nHost: [::1]:8080\r\nContent-Type: application/json\r\n"
    b"Transfer-Encoding: chunked\r\n\r\n2\r\n{}\r\n0\r\n\r\n",
    b"GET /api/access HTTP/1.1\r\nHost: 127.0.0.1\r\nCookie: a=b\r\n\r\n",
)


def check_dashboard_http(data: bytes, rng: random.Random) -> None:
    """Raw bytes into the dashboard's guarded aiohttp stack (its real application: Host and
    Origin checks, access, pairing, API): replies well formed, no 500, no crash logged; then
    valid pipelined requests get one 2xx each."""
    crashes: list[dict[str, object]] = []
    event_loop().set_exception_handler(lambda _, context: crashes.append(context))
    _set_up_dashboard()
    _HTTP_ERRORS.clear()
    statuses = _statuses(_serve(data, rng, _dashboard_server))
    expect(not crashes, f"the event loop saw {crashes!r}")
    expect(not _HTTP_ERRORS, f"logged as errors: {_HTTP_ERRORS[:3]}")
    expect(500 not in statuses, "a request reached 'internal server error'")
    valid = [rng.choice(_DASHBOARD_REQUESTS) for _ in range(rng.randint(1, 3))]
    statuses = _statuses(_serve(b"".join(valid), rng, _dashboard_server))
    expect(len(statuses) == len(valid), f"valid requests answered {statuses}")
    expect(all(s in (200, 409) for s in statuses), f"valid requests answered {statuses}")


_DASHBOARD: list[GuardedServer] = []


def _dashboard_server() -> GuardedServer:
    """One dashboard application for every input (set up by :func:`_set_up_dashboard`)."""
    return _DASHBOARD[0]


def _set_up_dashboard() -> None:
    if _DASHBOARD:
        return
    import aiohttp.web_fileresponse

    from scopelink.sim import EQ6, SimulatedMount
    from scopelink.web import Dashboard

    # Static files go out by sendfile(2) on a real socket; the recording transport takes writes.
    aiohttp.web_fileresponse.NOSENDFILE = True  # type: ignore[misc]

    dashboard = Dashboard(SimulatedMount(EQ6, site=Site(50.0, 10.0)), port=0, trace=False)
    runner = GuardedAppRunner(dashboard.build_app(), dashboard.guard, access_log=None)
    event_loop().run_until_complete(runner.setup())
    assert isinstance(runner.server, GuardedServer)
    _DASHBOARD.append(runner.server)


class _ErrorRecords(logging.Handler):
    """Collects what the HTTP stack logs as an error (an unhandled exception in a handler)."""

    def emit(self, record: logging.LogRecord) -> None:
        _HTTP_ERRORS.append(record.getMessage())


_HTTP_ERRORS: list[str] = []
for _name in ("aiohttp.server", "aiohttp.web", "scopelink.servers", "scopelink.web"):
    logging.getLogger(_name).addHandler(_ErrorRecords(logging.ERROR))

_STATUS_LINE = re.compile(rb"HTTP/\d\.\d \d{3} ")


def _statuses(written: bytes) -> list[int]:
    statuses = []
    rest = written
    while rest:
        # aiohttp answers in the request's version (HTTP/1.0 for a line it cannot read)
        expect(_STATUS_LINE.match(rest) is not None, f"not an HTTP reply: {rest[:40]!r}")
        status = int(rest[9:12])
        statuses.append(status)
        head_end = rest.index(b"\r\n\r\n") + 4
        length = 0
        for line in rest[:head_end].split(b"\r\n"):
            if line.lower().startswith(b"content-length:"):
                length = int(line.split(b":", 1)[1])
        rest = rest[head_end + length :]
    return statuses


async def _settle(connection: GuardedRequestHandler, transport: _Transport) -> None:
    """Let the connection answer what it has: until its output stops growing for a few turns."""
    quiet = 0
    size = len(transport.written)
    for _ in range(2000):
        await asyncio.sleep(0)
        if len(transport.written) == size:
            quiet += 1
            if quiet >= 20:  # a request waiting for the rest of its body stays busy: fine
                return
        else:
            quiet = 0
            size = len(transport.written)
    raise FuzzFailureError(f"the connection kept writing for 2000 loop turns ({connection!r})")


# ------------------------------------------------------------------------------------- dashboard


class _JsonRequest:
    """What read_body uses of aiohttp's request: the target is our parsing, not aiohttp's."""

    def __init__(self, body: bytes, content_type: str, declared: int | None) -> None:
        self.content_type = content_type
        self.content_length = declared
        self.content = self
        self._body = body

    async def read(self, limit: int) -> bytes:
        return self._body[:limit]


_DASHBOARD_KEYS = ("name", "ra_hours", "dec_deg", "alt_deg", "az_deg", "axis", "rate_deg_s")


def check_dashboard_params(data: bytes, rng: random.Random) -> None:
    """A dashboard command body (JSON) -> Body -> every field read the API makes."""
    declared = rng.choice((None, len(data), len(data) + 1))
    content_type = "application/json" if rng.random() < 0.95 else "text/plain"
    request = _JsonRequest(data, content_type, declared)
    try:
        body = event_loop().run_until_complete(read_body(typing.cast(web.Request, request)))
    except BadRequestError:
        return
    for key in (*_DASHBOARD_KEYS, "utc", "mode", "latitude_deg"):
        body.has(key)
        for read in ("number", "text", "axis", "mode"):
            try:
                match read:
                    case "number":
                        value = body.number(key, -90.0, 90.0)
                        expect(-90.0 <= value <= 90.0, f"number {value} out of range")
                    case "text":
                        text = body.text(key, max_length=40)
                        expect(0 < len(text) <= 40, f"text {text!r}")
                    case "axis":
                        body.choice(key, MountAxis)
                    case "mode":
                        body.choice(key, TrackingMode)
            except BadRequestError:
                pass


TARGETS: tuple[Target, ...] = (
    Target(
        "alpaca-params",
        (
            b"ClientID=1&ClientTransactionID=4294967295",
            b"RightAscension=12.5&Declination=-30.25",
            b"Tracking=True&Connected=false",
            b"Axis=0&Rate=1.5e-1",
            b"Direction=2&Duration=500&clientid=3",
            b"Declination=nan&Azimuth=%2B1e999&Rate=1_0",
        ),
        check_alpaca_params,
        b"=&%+.eE-0123456789",
    ),
    Target("alpaca-http", _HTTP_REQUESTS, check_alpaca_http, b"\r\n: /?=&%0", max_size=1024),
    Target(
        "dashboard-http",
        _DASHBOARD_REQUESTS,
        check_dashboard_http,
        b'\r\n: /?=&%0{}"[]',
        max_size=1024,
    ),
    Target(
        "dashboard-params",
        (
            b'{"name": "M31"}',
            b'{"ra_hours": 5.5875, "dec_deg": -5.391}',
            b'{"alt_deg": 45, "az_deg": 180.5}',
            b'{"axis": "primary", "rate_deg_s": -1.5}',
            b'{"mode": "sidereal"}',
            b'{"utc": "2026-11-23T00:00:00Z", "latitude_deg": 51.5, "longitude_deg": 0}',
        ),
        check_dashboard_params,
        b'{}[]":,0123456789.eE-',
        max_size=4200,  # past read_body's 4096-byte limit
    ),
)
