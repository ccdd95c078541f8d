"""Issue #12, part 1: DNS rebinding. A web page whose name an attacker points at 127.0.0.1 sends
requests with ``Host: evil.example:PORT``; they must be answered 421 and change nothing. Only
127.0.0.1 is ever contacted: the hostile names exist only in the headers."""

from __future__ import annotations

import asyncio
import json
import socket
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

import pytest

from scopelink.servers.alpaca import AlpacaServer
from scopelink.sim import SimulatedMount
from scopelink.web import Dashboard
from tests.support.alpaca import sim_mount

MOVE = b'{"axis":"primary","rate_deg_s":0.5}'


async def exchange(port: int, request: bytes) -> tuple[int, dict[str, str], bytes]:
    """One raw request to 127.0.0.1:port; the status, headers (lower-case names) and body."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        writer.write(request)
        async with asyncio.timeout(5):
            head = (await reader.readuntil(b"\r\n\r\n")).decode("latin-1")
            headers = {
                name.strip().lower(): value.strip()
                for name, value in (line.split(":", 1) for line in head.split("\r\n")[1:] if line)
            }
            body = await reader.readexactly(int(headers.get("content-length", "0")))
        return int(head.split(" ", 2)[1]), headers, body
    finally:
        writer.close()


def post(path: str, host: str, body: bytes, origin: str | None = None, extra: str = "") -> bytes:
    origin_line = f"Origin: {origin}\r\n" if origin else ""
    return (
        f"POST {path} HTTP/1.1\r\nHost: {host}\r\n{origin_line}{extra}"
        f"Content-Type: application/json\r\nContent-Length: {len(body)}\r\n"
        "Connection: close\r\n\r\n"
    ).encode() + body


def get(path: str, host: str) -> bytes:
    return f"GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n".encode()


@asynccontextmanager
async def dashboard(**kwargs: object) -> AsyncIterator[tuple[SimulatedMount, Dashboard]]:
    mount = sim_mount()
    await mount.connect()
    try:
        async with Dashboard(mount, port=0, trace=False, **kwargs) as served:  # type: ignore[arg-type]
            yield mount, served
    finally:
        await mount.disconnect()


async def assert_still(mount: SimulatedMount, az_before: float | None) -> None:
    await asyncio.sleep(0.3)
    state = await mount.refresh()
    assert state.az_deg is not None
    assert az_before is not None
    assert abs(state.az_deg - az_before) < 1.0, "the mount moved"


async def test_a_rebinding_page_cannot_move_the_mount_through_the_dashboard() -> None:
    async with dashboard() as (mount, served):
        port = served.port
        before = (await mount.refresh()).az_deg
        evil = f"evil.example:{port}"
        status, _, body = await exchange(
            port, post("/api/move", evil, MOVE, origin=f"http://{evil}")
        )
        assert status == 421, body
        assert json.loads(body)["kind"] == "MisdirectedRequest"
        # reads too: the page must not learn where the telescope is
        status, _, _ = await exchange(port, get("/api/state", evil))
        assert status == 421
        await assert_still(mount, before)


async def test_a_rebinding_page_cannot_slew_through_alpaca(tmp_path: Path) -> None:
    mount = sim_mount()
    async with AlpacaServer(mount, port=0, discovery_port=None, state_dir=tmp_path) as server:
        port = server.port
        before = (await mount.refresh()).az_deg
        evil = f"evil.example:{port}"
        form = b"Connected=True&ClientTransactionID=1"
        head = (
            f"PUT /api/v1/telescope/0/connected HTTP/1.1\r\nHost: {evil}\r\n"
            f"Content-Type: application/x-www-form-urlencoded\r\nContent-Length: {len(form)}\r\n"
            "Connection: close\r\n\r\n"
        )
        status, _, body = await exchange(port, head.encode() + form)
        assert status == 421, body
        assert server.telescope.connected is False
        status, _, _ = await exchange(port, get("/api/v1/telescope/0/rightascension", evil))
        assert status == 421
        await assert_still(mount, before)


@pytest.mark.parametrize("host", ["127.0.0.1", "localhost", "LOCALHOST.", "[::1]"])
async def test_this_machines_loopback_names_are_answered(tmp_path: Path, host: str) -> None:
    async with AlpacaServer(sim_mount(), port=0, discovery_port=None, state_dir=tmp_path) as server:
        request = get("/management/apiversions", f"{host}:{server.port}")
        status, _, _ = await exchange(server.port, request)
        assert status == 200
    async with dashboard() as (_, served):
        status, _, _ = await exchange(served.port, get("/api/access", f"{host}:{served.port}"))
        assert status == 200


async def test_allowed_hosts_adds_names(tmp_path: Path) -> None:
    async with AlpacaServer(
        sim_mount(),
        port=0,
        discovery_port=None,
        state_dir=tmp_path,
        allowed_hosts=("scope.lan",),
    ) as server:
        status, _, _ = await exchange(server.port, get("/management/apiversions", "scope.lan"))
        assert status == 200
        status, _, _ = await exchange(server.port, get("/management/apiversions", "scope.lan2"))
        assert status == 421
    async with dashboard(allowed_hosts=("scope.lan",)) as (_, served):
        status, _, _ = await exchange(served.port, get("/api/access", f"scope.lan:{served.port}"))
        assert status == 200


async def test_a_page_on_another_local_port_is_another_site() -> None:
    """Origin must be this very server: a page on localhost:OTHER is cross-site even though
    ``localhost`` is one of our names."""
    async with dashboard() as (mount, served):
        port = served.port
        before = (await mount.refresh()).az_deg
        host = f"localhost:{port}"
        for origin in (
            f"http://localhost:{port + 1}",
            "http://evil.example",
            "null",
            "http://12]]]7.0.0.1",  # not a URL at all (found by fuzzing: it was a 500)
        ):
            status, _, _ = await exchange(port, post("/api/move", host, MOVE, origin=origin))
            assert status == 403, origin
        await assert_still(mount, before)
        status, _, body = await exchange(
            port, post("/api/abort", host, b"{}", origin=f"http://{host}")
        )
        assert status == 200, body


def test_the_allow_list_beyond_loopback_holds_the_machines_names_and_addresses() -> None:
    from scopelink.servers.hosts import HostAllowList  # here: the file also runs on old code

    local = HostAllowList("127.0.0.1")
    wide = HostAllowList("0.0.0.0", ("scope.example",))
    hostname = socket.gethostname()
    assert not local.beyond_loopback
    assert wide.beyond_loopback
    assert wide.allows(f"{hostname}:8080")
    assert wide.allows(f"{hostname}.local")
    assert wide.allows("scope.example:11111")
    assert not local.allows("scope.example")
    assert wide.allows("127.0.0.1:1")
    assert wide.allows("[::1]:1")
    assert local.allows("127.0.0.2")
    assert not wide.allows("evil.example")
    assert wide.allows("0.0.0.0:8080")  # the printed URL of a wildcard bind
    assert not local.allows("0.0.0.0")
    assert not wide.allows("[::1")
    assert not wide.allows("")
    assert local.allows(None)  # HTTP/1.0 without Host: browsers always send one


async def test_beyond_loopback_commands_need_the_pairing_token_and_reads_stay_open() -> None:
    async with dashboard(pairing_token="s3cret", pairing_exempts_loopback=False) as (
        mount,
        served,
    ):
        port = served.port
        host = f"127.0.0.1:{port}"
        before = (await mount.refresh()).az_deg
        status, _, body = await exchange(port, post("/api/move", host, MOVE))
        assert status == 401
        assert json.loads(body)["kind"] == "NotPaired"
        await assert_still(mount, before)
        status, _, _ = await exchange(port, get("/api/state", host))
        assert status == 200  # reads stay open
        status, _, _ = await exchange(port, get("/pair?token=guess", host))
        assert status == 403
        status, headers, _ = await exchange(port, get("/pair?token=s3cret", host))
        assert status == 303
        assert headers["location"] == "/"
        cookie = headers["set-cookie"].split(";", 1)[0]
        assert "HttpOnly" in headers["set-cookie"]
        assert "SameSite=Strict" in headers["set-cookie"]
        status, _, body = await exchange(
            port, post("/api/abort", host, b"{}", extra=f"Cookie: {cookie}\r\n")
        )
        assert status == 200, body
        status, _, body = await exchange(
            port, post("/api/abort", host, b"{}", extra="X-Scopelink-Pairing: s3cret\r\n")
        )
        assert status == 200, body
        assert served.pairing_url == f"http://127.0.0.1:{port}/pair?token=s3cret"


async def test_a_dashboard_on_loopback_needs_no_pairing_and_one_beyond_it_gets_a_token() -> None:
    async with dashboard() as (_, served):
        assert served.pairing_token is None
        assert served.pairing_url is None
    mount = sim_mount()
    wide = Dashboard(mount, host="0.0.0.0", port=0, trace=False)  # built, never started
    assert wide.pairing_token is not None
    assert len(wide.pairing_token) >= 20
