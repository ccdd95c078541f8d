"""Hostile text never becomes markup, a header or a file outside the dashboard's static folder
(docs/reliability-injection.md).

Hostile device and object names, query parameters and bodies (``<script>``, quotes, CRLF, NUL,
lone surrogates, 100 kB strings) go through the Alpaca setup pages and API and the dashboard's
page, JSON API and WebSocket, over real sockets: HTML gets them escaped, JSON carries them as
exact data, headers never carry them, and every traversal trick on the static route is a
404/403/400 that never returns a byte of a file outside the folder.
"""

from __future__ import annotations

import asyncio
import json
import re
import shutil
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import replace
from html import unescape
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import quote

import aiohttp
import pytest
from playwright.async_api import async_playwright, expect

from scopelink.servers.alpaca import AlpacaServer
from scopelink.servers.alpaca.telescope import TelescopeConfig
from scopelink.servers.lx200 import LX200Server
from scopelink.sim import EQ6, SimClock, SimulatedMount
from scopelink.web import Dashboard
from scopelink.web.dashboard import static_dir
from tests.support.programs import require_executable
from tests.support.web import SITE, START

SCRIPT = "<script>window.pwned=1</script>"
HOSTILE = [
    SCRIPT,
    '"><img src=x onerror="window.pwned=1">',
    "'; window.pwned=1; '",
    "first line\r\nSet-Cookie: pwned=1\r\n\r\n<h1>body</h1>",
    "nul\x00byte and bell\x07",
    "&lt;already escaped&gt; &amp; </td></tr></table><script>x</script>",
    "\u202eright-to-left override",
    "argv byte that was not UTF-8: \udcff",
]
HUGE = "<b>" + "x" * 100_000 + "</b>"
SECRET = "the-secret-outside-the-static-folder"


class _Tags(HTMLParser):
    """Every start tag with its attributes, and the text (entities decoded)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, list[tuple[str, str | None]]]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, attrs))

    def handle_data(self, data: str) -> None:
        self.text.append(data)


def parse_html(page: str) -> _Tags:
    parser = _Tags()
    parser.feed(page)
    parser.close()
    return parser


def unshowable(character: str) -> bool:
    """What an HTML page shows as U+FFFD: C0 controls but tab and line ends, DEL, surrogates."""
    code = ord(character)
    return (code < 0x20 and character not in "\t\r\n") or code == 0x7F or 0xD800 <= code < 0xE000


def hostile_mount(name: str) -> SimulatedMount:
    """A real simulated mount whose model name (shown by every front end) is ``name``."""
    return SimulatedMount(replace(EQ6, name=name), site=SITE, clock=SimClock(start=START, rate=1.0))


async def raw_request(port: int, head: bytes, body: bytes = b"") -> tuple[int, bytes, bytes]:
    """Send ``head`` (request line and headers, without the final blank line) byte for byte,
    as no HTTP client library would (they normalise ``..`` and refuse CRLF); read the answer to
    the end. Returns status, header block, body."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        writer.write(head + b"\r\nConnection: close\r\n\r\n" + body)
        await writer.drain()
        async with asyncio.timeout(10):
            answer = await reader.read(-1)
    finally:
        writer.close()
    headers, _, content = answer.partition(b"\r\n\r\n")
    status = int(headers.split(b" ", 2)[1])
    return status, headers, content


def header_names(headers: bytes) -> list[str]:
    return [line.split(b":", 1)[0].decode().lower() for line in headers.split(b"\r\n")[1:]]


# --- Alpaca: setup pages, management and device API ---------------------------------------------


@asynccontextmanager
async def alpaca(name: str, tmp_path: Path) -> AsyncIterator[AlpacaServer]:
    mount = hostile_mount(name)
    await mount.connect()
    config = TelescopeConfig(name=name, description=f"description {name}")
    try:
        async with AlpacaServer(
            mount, port=0, discovery_port=None, state_dir=tmp_path, config=config
        ) as server:
            yield server
    finally:
        await mount.disconnect()


@pytest.mark.parametrize("name", [*HOSTILE, HUGE], ids=lambda n: repr(n[:12]))
async def test_alpaca_setup_pages_escape_hostile_names(name: str, tmp_path: Path) -> None:
    async with alpaca(name, tmp_path) as server:
        for path in ("/setup", "/setup/v1/telescope/0/setup"):
            status, headers, content = await raw_request(
                server.port, f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1".encode()
            )
            assert status == 200
            assert b"content-type: text/html; charset=utf-8" in headers.lower()
            assert b"\r\nContent-Security-Policy: default-src 'none';" in headers
            assert b"\r\nX-Frame-Options: DENY\r\n" in headers
            assert "set-cookie" not in header_names(headers)
            page = content.decode("utf-8")
            parsed = parse_html(page)
            tags = {tag for tag, _ in parsed.tags}
            assert tags <= {"html", "head", "meta", "title", "body", "h1", "p", "table", "tr"} | {
                "th",
                "td",
            }, tags
            # The only attributes are the page's own (lang, charset): none came from the name.
            attributes = {attribute for _, attrs in parsed.tags for attribute, _ in attrs}
            assert attributes <= {"lang", "charset"}
            assert "\x00" not in page  # a NUL is shown as U+FFFD, never sent raw
            text = "".join(parsed.text)
            shown = "".join("\ufffd" if unshowable(c) else c for c in name)
            assert shown in text or shown in unescape(text)


@pytest.mark.parametrize("name", HOSTILE, ids=lambda n: repr(n[:12]))
async def test_alpaca_json_carries_hostile_names_as_exact_data(name: str, tmp_path: Path) -> None:
    async with (
        alpaca(name, tmp_path) as server,
        aiohttp.ClientSession(base_url=server.url) as http,
    ):
        async with http.get("/management/v1/configureddevices") as response:
            assert response.content_type == "application/json"
            devices = (await response.json())["Value"]
        async with http.get("/api/v1/telescope/0/name") as response:
            device_name = (await response.json())["Value"]
        async with http.get("/api/v1/telescope/0/description") as response:
            description = (await response.json())["Value"]
    expected = name  # JSON escapes everything it must: the name arrives exactly as configured
    assert devices[0]["DeviceName"] == expected
    assert device_name == expected
    assert description == f"description {expected}"


ALPACA_HOSTILE_QUERIES = [
    "/api/v1/telescope/0/rightascension?ClientTransactionID=" + quote(SCRIPT),
    "/api/v1/telescope/0/rightascension?ClientID=" + quote('"><img src=x>'),
    "/api/v1/telescope/0/" + quote(SCRIPT),
    "/api/v1/telescope/0/name?x=" + quote("a\r\nSet-Cookie: pwned=1"),
    "/api/v1/telescope/0/name?x=%00%ff%fe",
    "/setup/../../../../etc/passwd",
    "/setup/%2e%2e/%2e%2e/%2e%2e/etc/passwd",
    "/%2e%2e%2f%2e%2e%2fetc%2fpasswd",
    "/..\\..\\..\\etc\\passwd",
    "/api/v1/telescope/0/../../../../etc/passwd",
    "/setup%00.html",
]


async def test_alpaca_never_reflects_hostile_requests_as_markup_or_headers(
    tmp_path: Path,
) -> None:
    async with alpaca("telescope", tmp_path) as server:
        for target in ALPACA_HOSTILE_QUERIES:
            status, headers, content = await raw_request(
                server.port, f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1".encode()
            )
            lowered = headers.lower()
            assert "set-cookie" not in header_names(headers), target
            assert b"content-type: text/html" not in lowered, target  # only the setup pages
            assert b"x-content-type-options: nosniff" in lowered, target  # text stays text
            assert b"root:" not in content, target
            if status == 200:  # a read that ignored an unknown parameter: JSON
                assert b"application/json" in lowered, target
                json.loads(content)
            else:
                assert status in (400, 404), (target, status)
        put = (
            b"PUT /api/v1/telescope/0/slewtocoordinatesasync HTTP/1.1\r\nHost: 127.0.0.1\r\n"
            b"Content-Type: application/x-www-form-urlencoded\r\nContent-Length: "
        )
        body = ("RightAscension=" + quote(SCRIPT) + "&Declination=" + quote("1\r\nX: y")).encode()
        status, headers, content = await raw_request(
            server.port, put + str(len(body)).encode(), body
        )
        assert status in (200, 400)
        assert b"text/html" not in headers.lower()
        assert "x" not in header_names(headers)
        # The server still answers after all that.
        status, _, content = await raw_request(
            server.port, b"GET /api/v1/telescope/0/connected HTTP/1.1\r\nHost: 127.0.0.1"
        )
        assert status == 200
        assert json.loads(content)["ErrorNumber"] == 0


async def test_alpaca_refuses_a_huge_request_target_and_keeps_serving(tmp_path: Path) -> None:
    async with alpaca("telescope", tmp_path) as server:
        target = "/api/v1/telescope/0/name?x=" + "a" * 2_000_000
        status, _, _ = await raw_request(
            server.port, f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1".encode()
        )
        assert status in (400, 413, 414, 431)
        status, _, _ = await raw_request(
            server.port, b"GET /api/v1/telescope/0/name HTTP/1.1\r\nHost: 127.0.0.1"
        )
        assert status == 200


# --- the dashboard: JSON API, WebSocket, page, static files ---------------------------------------


@asynccontextmanager
async def dashboard(name: str = "EQ6") -> AsyncIterator[tuple[Dashboard, aiohttp.ClientSession]]:
    mount = hostile_mount(name)
    await mount.connect()
    try:
        async with (
            Dashboard(mount, port=0, update_interval_s=0.1) as served,
            aiohttp.ClientSession(base_url=served.url) as http,
        ):
            yield served, http
    finally:
        await mount.disconnect()


async def test_dashboard_json_and_websocket_carry_hostile_names_as_exact_data() -> None:
    for name in HOSTILE:
        expected = name  # JSON carries the exact text; the page sets it with textContent
        async with dashboard(name) as (_, http):
            async with http.get("/api/state") as response:
                assert response.content_type == "application/json"
                assert response.headers["X-Content-Type-Options"] == "nosniff"
                assert "script-src 'self'" in response.headers["Content-Security-Policy"]
                assert "Set-Cookie" not in response.headers
                state = await response.json()
            assert state["mount"]["identity"]["model"] == expected
            async with http.ws_connect("/ws") as socket:
                async with asyncio.timeout(10):
                    message = await socket.receive()
            assert message.type == aiohttp.WSMsgType.TEXT
            hello = json.loads(message.data)
            assert hello["mount"]["identity"]["model"] == expected


async def test_dashboard_api_refuses_or_quotes_hostile_input() -> None:
    async with dashboard() as (served, http):
        for name in [*HOSTILE, "x" * 100]:
            async with http.post("/api/goto", json={"name": name}) as response:
                assert response.status in (400, 404), name
                assert response.content_type == "application/json"
                answer = await response.json()
                assert answer["kind"] in ("UnknownObjectError", "BadRequestError")
                assert "Set-Cookie" not in response.headers
        async with http.post("/api/goto", json={"name": HUGE}) as response:
            assert response.status in (400, 413)
        for query in [*HOSTILE, "a" * 101]:
            async with http.get("/api/search", params={"q": query}) as response:
                assert response.status in (200, 400), query
                assert response.content_type == "application/json"
                await response.json()
                assert "Set-Cookie" not in response.headers
        async with http.get("/api/search", params={"q": "M3", "limit": SCRIPT}) as response:
            assert response.status == 400
        for body in (b"\xff\xfe not UTF-8", b'{"name": "\\ud800"}', b"[" * 10_000, b"\x00"):
            async with http.post(
                "/api/goto", data=body, headers={"Content-Type": "application/json"}
            ) as response:
                assert response.status in (400, 404), body[:20]
                assert response.content_type == "application/json"
        # CRLF in a query never reaches a header.
        status, headers, _ = await raw_request(
            served.port,
            b"GET /api/search?q=%0d%0aSet-Cookie:%20pwned=1%0d%0a HTTP/1.1\r\nHost: 127.0.0.1",
        )
        assert status == 200
        assert "set-cookie" not in header_names(headers)


TRAVERSALS = [
    "/static/../secret.txt",
    "/static/%2e%2e/secret.txt",
    "/static/%2E%2E%2Fsecret.txt",
    "/static/..%2fsecret.txt",
    "/static/..%5csecret.txt",
    "/static/..\\secret.txt",
    "/static/.%2e/secret.txt",
    "/static/%252e%252e/secret.txt",
    "/static/%c0%ae%c0%ae/secret.txt",
    "/static//etc/passwd",
    "/static/%2fetc%2fpasswd",
    "/static/{outside}",
    "/static/%00",
    "/static/app.js%00.png",
    "/static/link-out",
    "/static/link-out-dir/secret.txt",
    "/static/../../../../../../etc/passwd",
    "/../secret.txt",
    "/%2e%2e/secret.txt",
    "/static/",
    "/static/.",
]


async def test_no_static_route_trick_reads_a_file_outside_the_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A copy of the installed folder next to a secret, with symlinks pointing out of it.
    folder = tmp_path / "static"
    shutil.copytree(static_dir(), folder)
    secret = tmp_path / "secret.txt"
    secret.write_text(SECRET)
    (folder / "link-out").symlink_to(secret)
    (folder / "link-out-dir").symlink_to(tmp_path, target_is_directory=True)
    monkeypatch.setattr("scopelink.web.dashboard.static_dir", lambda: folder)
    async with dashboard() as (served, _):
        status, _, content = await raw_request(
            served.port, b"GET /static/app.js HTTP/1.1\r\nHost: 127.0.0.1"
        )
        assert status == 200  # the route works: the refusals below are refusals, not a dead route
        assert content == (folder / "app.js").read_bytes()
        for path in TRAVERSALS:
            target = path.format(outside=quote(str(secret), safe=""))
            status, headers, content = await raw_request(
                served.port, f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1".encode()
            )
            assert status in (400, 403, 404), (target, status)
            assert SECRET.encode() not in content, target
            assert b"root:" not in content, target
            assert "location" not in header_names(headers), target  # no redirect to follow


def test_the_page_script_never_turns_text_into_markup() -> None:
    """Everything the page shows comes from the API or the WebSocket and is set as text: the
    script has no HTML sink (innerHTML and kin) and evaluates no strings."""
    ours = [
        static_dir() / "app.js",
        static_dir() / "chart.js",
        *(static_dir() / "chart").glob("*.js"),
    ]
    script = "\n".join(path.read_text(encoding="utf-8") for path in ours)
    code = re.sub(r"//[^\n]*", "", script)  # comments may name the sinks they avoid
    sinks = ["innerHTML", "outerHTML", "insertAdjacentHTML", "document.write", "eval(", "Function("]
    assert [sink for sink in sinks if sink in code] == []
    assert 'setTimeout("' not in code
    assert "textContent" in code  # the positive half: text is set as text


async def test_websocket_ignores_hostile_messages_and_closes_on_huge_ones() -> None:
    async with dashboard() as (_, http):
        async with http.ws_connect("/ws") as socket:
            async with asyncio.timeout(10):
                assert json.loads((await socket.receive()).data)["type"] == "hello"
                for text in HOSTILE:  # the lone surrogate goes as the bytes it came from
                    await socket.send_bytes(text.encode("utf-8", "surrogateescape"))
                    await socket.send_str(text.encode("utf-8", "replace").decode())
                await socket.send_bytes(b"\x00\xff" * 100)
                # Still live: the next update arrives, as JSON.
                update = await socket.receive()
                assert update.type == aiohttp.WSMsgType.TEXT
                json.loads(update.data)
        async with http.ws_connect("/ws") as socket:
            async with asyncio.timeout(10):
                await socket.receive()  # the hello
                await socket.send_str(HUGE)
                while (message := await socket.receive()).type == aiohttp.WSMsgType.TEXT:
                    pass
            assert message.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED)
            assert socket.close_code == aiohttp.WSCloseCode.MESSAGE_TOO_BIG
        async with http.get("/api/state") as response:
            assert response.status == 200  # the dashboard serves on


async def test_hostile_names_and_bytes_are_text_in_the_browser() -> None:
    """The real page in headless Chromium shows a hostile model name, and hostile bytes a
    network client sent to a server (the traffic panel), as text: no element is made of them
    and no script in them runs."""
    executable = require_executable("chromium")
    name = '<img src=x onerror="window.pwned=1"><script>window.pwned=2</script>'
    async with (
        dashboard(name) as (served, _),
        LX200Server(served.mount) as lx200,
        async_playwright() as playwright,
    ):
        browser = await playwright.chromium.launch(executable_path=executable)
        try:
            page = await browser.new_page()
            errors: list[str] = []
            page.on("pageerror", lambda error: errors.append(str(error)))
            await page.goto(served.url)
            await expect(page.locator("#hl-identity")).to_contain_text(name, timeout=10_000)
            host, port = await lx200.on_tcp(port=0)
            _, writer = await asyncio.open_connection(host, port)
            writer.write(b':<img src=x onerror="window.pwned=3">#:GR#')
            await writer.drain()
            await expect(page.locator("#traffic")).to_contain_text("img src=x", timeout=10_000)
            writer.close()
            assert await page.locator("#hl-identity img, #hl-identity script").count() == 0
            assert await page.locator("#traffic img, #traffic script").count() == 0
            assert await page.locator("img[src=x]").count() == 0
            assert await page.evaluate("window.pwned === undefined")
            assert errors == []
        finally:
            await browser.close()
