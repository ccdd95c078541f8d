"""The access policy: allow-list, connection limits, request rate and read-only mode, in the
policy itself and in every server over real sockets on 127.0.0.1."""

from __future__ import annotations

import asyncio
import json
import socket
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime
from pathlib import Path

import aiohttp
import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.astro import Site, observed_to_j2000
from scopelink.links import open_tcp
from scopelink.protocol.stellarium import GotoMessage, StellariumClientConnection
from scopelink.protocol.synscan import (
    Ack,
    GetRaDec,
    GotoRaDec,
    Position,
    SynScanClientConnection,
)
from scopelink.servers.access import (
    AccessControl,
    AccessPolicy,
    Refusal,
    TokenBucket,
    parse_network,
)
from scopelink.servers.alpaca import DISCOVERY_MESSAGE, AlpacaServer
from scopelink.servers.lx200 import LX200Server
from scopelink.servers.stellarium import StellariumServer
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from scopelink.web import Dashboard
from tests.support.access import (
    ELSEWHERE_ONLY,
    READ_ONLY,
    HttpClient,
    closed_without_a_byte,
    read_answer,
)
from tests.support.synscan import ask

SITE = Site(48.2, 16.4)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)
DEVICE = "/api/v1/telescope/0"


def simulated_mount() -> SimulatedMount:
    return SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=30.0))


def up_in_the_south(mount: SimulatedMount, alt_deg: float = 50.0) -> tuple[float, float]:
    return observed_to_j2000(alt_deg, 180.0, mount.now(), mount.site)


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


# --- the policy itself ----------------------------------------------------------------------------


def test_the_allow_list_admits_its_networks_and_loopback() -> None:
    policy = AccessPolicy(allow=(parse_network("192.168.1.0/24"), parse_network("fd00::/8")))
    assert policy.allows("192.168.1.77")
    assert policy.allows("fd00::5")
    assert policy.allows("::ffff:192.168.1.9")  # IPv4-mapped, as dual-stack sockets report
    assert policy.allows("127.0.0.1")
    assert policy.allows("::1")
    assert not policy.allows("192.168.2.1")
    assert not policy.allows("not an address")
    assert AccessPolicy().allows("203.0.113.5")  # no list: the bind address is the fence
    assert not ELSEWHERE_ONLY.allows("127.0.0.1")
    assert ELSEWHERE_ONLY.allows("10.9.8.7")


def test_bad_policies_and_networks_are_refused_with_the_reason() -> None:
    with pytest.raises(ValueError, match="not an IP network"):
        parse_network("192.168.1.0/33")
    with pytest.raises(ValueError, match="at least 1"):
        AccessPolicy(max_connections=0)
    with pytest.raises(ValueError, match="rates must be positive"):
        AccessPolicy(requests_per_s=0.0)
    assert "read-only" in AccessPolicy(read_only=True).describe()
    assert "10.9.8.0/24" in ELSEWHERE_ONLY.describe()


def test_connection_limits_count_per_server_and_per_address() -> None:
    control = AccessControl(AccessPolicy(max_connections=3, max_connections_per_client=2))
    first = control.admit("127.0.0.1")
    second = control.admit("127.0.0.1")
    third = control.admit("127.0.0.1")
    assert not isinstance(first, Refusal)
    assert not isinstance(second, Refusal)
    assert isinstance(third, Refusal)
    assert not third.forbidden
    other = control.admit("127.0.0.2")
    assert not isinstance(other, Refusal)
    full = control.admit("127.0.0.3")
    assert isinstance(full, Refusal)
    assert "3 connections" in full.reason
    first.release()
    first.release()  # twice is once
    assert not isinstance(control.admit("127.0.0.3"), Refusal)
    assert control.refused_connections == 2
    assert not isinstance(control.admit(None), Refusal)  # a pty: not counted
    assert control.open_connections == 3


def test_the_bucket_grants_the_burst_then_the_rate() -> None:
    clock = FakeClock()
    control = AccessControl(
        AccessPolicy(requests_per_s=10.0, burst=3, max_delay_s=0.25), clock=clock
    )
    client = control.admit("127.0.0.1")
    assert not isinstance(client, Refusal)
    assert [client.admit_request() for _ in range(3)] == [0.0, 0.0, 0.0]
    assert client.admit_request() == pytest.approx(0.1)
    assert client.admit_request() == pytest.approx(0.2)
    assert client.admit_request() is None  # 0.3 s away: beyond max_delay_s
    assert client.retry_after_s() == pytest.approx(0.3)
    clock.now += 1.0
    assert client.admit_request() == 0.0
    assert control.refused_requests == 1


@given(
    rate=st.floats(0.5, 1000.0),
    burst=st.integers(1, 50),
    gaps=st.lists(st.floats(0.0, 0.5), min_size=1, max_size=200),
)
def test_no_schedule_of_requests_gets_more_than_burst_plus_rate(
    rate: float, burst: int, gaps: list[float]
) -> None:
    """Whatever the arrival times, requests served by any instant t (each at its arrival plus
    its wait) never exceed burst + rate x t."""
    bucket = TokenBucket(rate, burst, 0.0)
    now = 0.0
    served_at: list[float] = []
    for gap in gaps:
        now += gap
        wait = bucket.reserve(now)
        assert wait is not None
        assert wait >= 0.0
        served_at.append(now + wait)
    served_at.sort()
    for count, instant in enumerate(served_at, start=1):
        assert count <= burst + rate * instant + 1e-6


# --- Alpaca -------------------------------------------------------------------------------------


@asynccontextmanager
async def alpaca(
    policy: AccessPolicy, tmp_path: Path, mount: SimulatedMount | None = None
) -> AsyncIterator[AlpacaServer]:
    server = AlpacaServer(
        mount or simulated_mount(),
        port=0,
        discovery_port=0,
        state_dir=tmp_path,
        access=policy,
    )
    async with server:
        yield server


async def test_alpaca_refuses_a_stranger_with_403_and_discovery_ignores_it(
    tmp_path: Path,
) -> None:
    async with alpaca(ELSEWHERE_ONLY, tmp_path) as server:
        client = await HttpClient.connect(server.port)
        answer = await client.request("GET", f"{DEVICE}/connected")
        assert answer.status == 403
        assert b"allow-list" in answer.body
        assert await client.closed_by_server()
        await client.close()
        assert server.discovery_port is not None
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp:
            udp.setblocking(False)
            udp.bind(("127.0.0.1", 0))
            loop = asyncio.get_running_loop()
            await loop.sock_sendto(udp, DISCOVERY_MESSAGE, ("127.0.0.1", server.discovery_port))
            with pytest.raises(TimeoutError):
                async with asyncio.timeout(0.4):
                    await loop.sock_recvfrom(udp, 256)
        assert server.access.forbidden >= 2


async def test_alpaca_over_the_connection_limit_answers_503_and_closes(tmp_path: Path) -> None:
    policy = AccessPolicy(max_connections=4, max_connections_per_client=2)
    async with alpaca(policy, tmp_path) as server:
        kept = [await HttpClient.connect(server.port) for _ in range(2)]
        for client in kept:
            assert (await client.request("GET", "/management/apiversions")).status == 200
        extra = await HttpClient.connect(server.port)
        answer = await extra.request("GET", "/management/apiversions")
        assert answer.status == 503
        assert answer.headers["retry-after"] == "1"
        assert await extra.closed_by_server()
        await extra.close()
        await kept[0].close()
        await asyncio.sleep(0.1)
        again = await HttpClient.connect(server.port)
        assert (await again.request("GET", "/management/apiversions")).status == 200
        for client in (again, kept[1]):
            await client.close()


async def test_alpaca_holds_requests_over_the_rate_then_answers_429(tmp_path: Path) -> None:
    policy = AccessPolicy(requests_per_s=20.0, burst=2, max_delay_s=0.12)
    async with alpaca(policy, tmp_path) as server:
        client = await HttpClient.connect(server.port)
        started = time.monotonic()
        statuses = [
            (await client.request("GET", "/management/apiversions")).status for _ in range(4)
        ]
        held = time.monotonic() - started
        assert statuses == [200, 200, 200, 200]
        assert held >= 0.08  # two requests waited ~50 ms each for their tokens
        # One connection is served in order, so it is only ever paced; several connections
        # from one address at once outrun the rate, and the excess is told when to come back.
        request = b"GET /management/apiversions HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
        others = [await HttpClient.connect(server.port) for _ in range(5)]
        for other in [client, *others]:
            other.writer.write(request * 3)
        answers = [await read_answer(other.reader) for other in [client, *others] for _ in range(3)]
        refused = [answer for answer in answers if answer.status == 429]
        assert refused, [answer.status for answer in answers]
        assert all(int(answer.headers["retry-after"]) >= 1 for answer in refused)
        assert {answer.status for answer in answers} <= {200, 429}  # every request answered
        assert server.access.refused_requests == len(refused)
        for other in others:
            await other.close()
        await client.close()


async def test_read_only_alpaca_reads_and_connects_but_refuses_every_change(
    tmp_path: Path,
) -> None:
    mount = simulated_mount()
    async with alpaca(READ_ONLY, tmp_path, mount) as server:
        client = await HttpClient.connect(server.port)
        ids = "ClientID=1&ClientTransactionID=7"
        connected = await client.request("PUT", f"{DEVICE}/connected", f"Connected=True&{ids}")
        assert connected.json()["ErrorNumber"] == 0
        ra = (await client.request("GET", f"{DEVICE}/rightascension")).json()
        assert ra["ErrorNumber"] == 0
        target_ra, target_dec = up_in_the_south(mount)
        for member, form in [
            ("slewtocoordinatesasync", f"RightAscension={target_ra}&Declination={target_dec}"),
            ("moveaxis", "Axis=0&Rate=1.0"),
            ("tracking", "Tracking=False"),
            ("park", ""),
            ("abortslew", ""),
            ("sitelatitude", "SiteLatitude=10"),
        ]:
            answer = (await client.request("PUT", f"{DEVICE}/{member}", f"{form}&{ids}")).json()
            assert answer["ErrorNumber"] == 0x40B, (member, answer)
            assert "read-only" in str(answer["ErrorMessage"])
        await asyncio.sleep(0.2)
        assert not mount.state.slewing
        assert mount.target is None
        assert mount.site.latitude_deg == SITE.latitude_deg
        await client.close()


# --- LX200 and SkyFi ------------------------------------------------------------------------------


async def lx200_text(
    reader: asyncio.StreamReader, writer: asyncio.StreamWriter, command: bytes
) -> bytes:
    writer.write(command)
    await writer.drain()
    async with asyncio.timeout(5):
        return await reader.readuntil(b"#")


async def lx200_char(
    reader: asyncio.StreamReader, writer: asyncio.StreamWriter, command: bytes
) -> bytes:
    writer.write(command)
    await writer.drain()
    async with asyncio.timeout(5):
        return await reader.readexactly(1)


async def test_read_only_lx200_answers_reads_and_refuses_gotos_syncs_and_motion() -> None:
    mount = simulated_mount()
    async with LX200Server(mount, access=READ_ONLY) as server:
        _, port = await server.on_tcp(port=0)
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        try:
            assert (await lx200_text(reader, writer, b":GR#")).count(b":") == 2
            assert await lx200_char(reader, writer, b":Sr 10:00:00#") == b"1"
            assert await lx200_char(reader, writer, b":Sd +45*00:00#") == b"1"
            assert await lx200_text(reader, writer, b":MS#") == b"2Read-only server#"
            assert await lx200_text(reader, writer, b":CM#") == b"1Read-only server#"
            assert await lx200_char(reader, writer, b":St+10*00#") == b"0"
            writer.write(b":Mn#:Me#:Q#")  # no replies exist: ignored
            # The next reply is the next command's: nothing was queued by the ignored ones.
            assert await lx200_char(reader, writer, b":SG+02.0#") == b"0"
            await asyncio.sleep(0.3)
            assert not mount.state.slewing
            assert mount.target is None
            assert mount.site.latitude_deg == SITE.latitude_deg
        finally:
            writer.close()
            await writer.wait_closed()


async def test_lx200_closes_strangers_and_connections_over_the_limit() -> None:
    mount = simulated_mount()
    async with LX200Server(mount, access=ELSEWHERE_ONLY) as server:
        _, port = await server.on_tcp(port=0)
        assert await closed_without_a_byte(port, b":GR#")
        assert server.access.forbidden == 1
        responder = await server.on_skyfi(port=0)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp:
            udp.setblocking(False)
            udp.bind(("127.0.0.1", 0))
            loop = asyncio.get_running_loop()
            await loop.sock_sendto(udp, b"skyfi?", ("127.0.0.1", responder.port))
            with pytest.raises(TimeoutError):
                async with asyncio.timeout(0.4):
                    await loop.sock_recvfrom(udp, 256)
        assert responder.answered == 0
    limited = AccessPolicy(max_connections_per_client=1)
    async with LX200Server(mount, access=limited) as server:
        _, port = await server.on_tcp(port=0)
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        try:
            assert (await lx200_text(reader, writer, b":GR#")).endswith(b"#")
            assert await closed_without_a_byte(port, b":GR#")
            assert (await lx200_text(reader, writer, b":GD#")).endswith(b"#")  # still served
        finally:
            writer.close()
            await writer.wait_closed()


async def test_lx200_commands_over_the_rate_wait_and_none_is_lost() -> None:
    mount = simulated_mount()
    async with LX200Server(mount, access=AccessPolicy(requests_per_s=40.0, burst=2)) as server:
        _, port = await server.on_tcp(port=0)
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        try:
            started = time.monotonic()
            writer.write(b":GR#" * 10)
            async with asyncio.timeout(5):
                replies = [await reader.readuntil(b"#") for _ in range(10)]
            elapsed = time.monotonic() - started
            assert len(replies) == 10
            assert elapsed >= 0.15  # 8 commands beyond the burst at 40/s: about 0.2 s
            # Each of them waits for a token, unless a stall of the loop (a loaded machine)
            # refilled the bucket meanwhile: some wait in any case.
            assert server.access.delayed >= 3
        finally:
            writer.close()
            await writer.wait_closed()


# --- SynScan and Stellarium -----------------------------------------------------------------------


async def test_read_only_synscan_acknowledges_gotos_without_moving() -> None:
    mount = simulated_mount()
    async with SynScanEmulator(mount, wire=None, access=READ_ONLY) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        link = await open_tcp(host, port)
        client = SynScanClientConnection()
        try:
            ra, dec = up_in_the_south(mount)
            assert isinstance(await ask(link, client, GotoRaDec.from_hours_degrees(ra, dec)), Ack)
            assert isinstance(await ask(link, client, GetRaDec()), Position)
            await asyncio.sleep(0.3)
            assert not mount.state.slewing
            assert mount.target is None
        finally:
            await link.close()


async def test_synscan_closes_strangers() -> None:
    async with SynScanEmulator(simulated_mount(), wire=None, access=ELSEWHERE_ONLY) as emulator:
        _, port = await emulator.on_tcp("127.0.0.1", 0)
        assert await closed_without_a_byte(port, b"e")


async def test_read_only_stellarium_ignores_gotos_and_strangers_are_closed() -> None:
    mount = simulated_mount()
    async with StellariumServer(mount, port=0, interval_s=0.1, access=READ_ONLY) as server:
        reader, writer = await asyncio.open_connection("127.0.0.1", server.port)
        try:
            ra, dec = up_in_the_south(mount)
            writer.write(StellariumClientConnection().send(GotoMessage.from_degrees(ra, dec)))
            await writer.drain()
            async with asyncio.timeout(5):
                assert await reader.read(24)  # positions still flow
            await asyncio.sleep(0.3)
            assert not mount.state.slewing
            assert mount.target is None
        finally:
            writer.close()
            await writer.wait_closed()
    async with StellariumServer(mount, port=0, access=ELSEWHERE_ONLY) as server:
        assert await closed_without_a_byte(server.port, b"\x00")


# --- dashboard ------------------------------------------------------------------------------------


@asynccontextmanager
async def dashboard(
    policy: AccessPolicy,
) -> AsyncIterator[tuple[SimulatedMount, aiohttp.ClientSession]]:
    mount = simulated_mount()
    await mount.connect()
    try:
        async with (
            Dashboard(mount, port=0, access=policy) as served,
            aiohttp.ClientSession(base_url=served.url) as http,
        ):
            yield mount, http
    finally:
        await mount.disconnect()


async def test_read_only_dashboard_says_so_and_refuses_every_command() -> None:
    async with dashboard(READ_ONLY) as (mount, http):
        async with http.get("/api/access") as response:
            assert await response.json() == {"read_only": True}
        async with http.get("/api/state") as response:
            assert response.status == 200
        ra, dec = up_in_the_south(mount)
        for path, body in [
            ("/api/goto", {"ra_hours": ra, "dec_deg": dec}),
            ("/api/abort", {}),
            ("/api/move", {"axis": "primary", "rate_deg_s": 1.0}),
            ("/api/park", {}),
        ]:
            async with http.post(path, json=body) as response:
                assert response.status == 403, path
                assert (await response.json())["kind"] == "ReadOnly"
        assert not mount.state.slewing
        async with http.get("/static/app.js") as response:
            assert "read-only-note" in await response.text()  # the page greys its controls


async def test_dashboard_refuses_strangers_and_floods() -> None:
    async with dashboard(ELSEWHERE_ONLY) as (_, http), http.get("/") as response:
        assert response.status == 403
    policy = AccessPolicy(requests_per_s=5.0, burst=3, max_delay_s=0.0)
    async with dashboard(policy) as (_, http):
        statuses = []
        for _ in range(5):
            async with http.get("/api/state") as response:
                statuses.append(response.status)
                if response.status == 429:
                    assert int(response.headers["Retry-After"]) >= 1
                    assert json.loads(await response.text())["kind"] == "TooManyRequests"
        assert statuses[:3] == [200, 200, 200]
        assert 429 in statuses[3:]


async def test_dashboard_live_pages_count_against_the_connection_limits() -> None:
    async with dashboard(AccessPolicy(max_connections_per_client=1)) as (_, http):
        first = await http.ws_connect("/ws")
        try:
            with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
                await http.ws_connect("/ws")
            assert refused.value.status == 503
            async with http.get("/api/state") as response:
                assert response.status == 503  # every connection counts (issue #12)
        finally:
            await first.close()
        await asyncio.sleep(0.1)
        again = await http.ws_connect("/ws")
        assert (await again.receive_json(timeout=5))["type"] == "hello"
        await again.close()
