"""Issue #12, part 5: serve's default access policy never delays a client polling 20 properties
at 10 Hz, refuses a client far beyond its rate with 429 + Retry-After instead of queueing it, and
the defaults the docs state are the code's."""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

import pytest

from scopelink.cli.main import build_parser
from scopelink.cli.serve_command import plan_from
from scopelink.servers.access import DEFAULT_POLICY
from scopelink.servers.alpaca import AlpacaServer
from scopelink.servers.http_guard import MAX_BODY_BYTES, MAX_HEADER_BYTES, MAX_REQUEST_LINE_BYTES
from tests.support.alpaca import sim_mount

DOCS = Path(__file__).resolve().parents[2] / "docs"
PROPERTIES = [
    "rightascension",
    "declination",
    "altitude",
    "azimuth",
    "siderealtime",
    "utcdate",
    "tracking",
    "slewing",
    "atpark",
    "athome",
    "sideofpier",
    "targetrightascension",
    "targetdeclination",
    "trackingrate",
    "canslew",
    "connected",
    "name",
    "description",
    "driverversion",
    "interfaceversion",
]


def test_serve_uses_the_default_policy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SCOPELINK_CONFIG", str(tmp_path / "none.toml"))
    _, plan = plan_from(build_parser().parse_args(["serve"]))
    assert plan.access == DEFAULT_POLICY
    assert plan.alpaca_access.allow == ()  # loopback: no subnet list needed


def _row(text: str, key: str) -> str:
    for line in text.splitlines():
        if line.startswith("|") and key in line:
            return line
    raise AssertionError(f"no table row with {key!r}")


def _number(cell: str) -> float:
    match = re.search(r"[\d.]+", cell)
    assert match, cell
    return float(match.group())


def test_docs_serve_states_the_codes_defaults() -> None:
    text = (DOCS / "serve.md").read_text(encoding="utf-8")
    policy = DEFAULT_POLICY
    for key, value in (
        ("`max_connections`", policy.max_connections),
        ("`max_connections_per_client`", policy.max_connections_per_client),
        ("`requests_per_second`", policy.requests_per_s),
        ("`server_requests_per_second`", policy.server_requests_per_s),
    ):
        assert _number(_row(text, key).split("|")[3]) == value, key
    assert _number(_row(text, "429").split("|")[3]) == policy.max_delay_s
    assert _number(_row(text, "idle timeout").split("|")[3]) == policy.idle_timeout_s
    assert _number(_row(text, "header timeout").split("|")[3]) == policy.header_timeout_s
    access_line = next(line for line in text.splitlines() if "  Access  " in line)
    assert f"{policy.requests_per_s:g} requests/s per client" in access_line
    assert f"{policy.server_requests_per_s:g} per server" in access_line


def test_docs_security_table_states_the_codes_defaults_and_limits() -> None:
    text = (DOCS / "reliability-security.md").read_text(encoding="utf-8")
    policy = DEFAULT_POLICY

    def cell(key: str) -> str:
        return _row(text, key).split("|")[2]

    assert _number(cell("| connections per server")) == policy.max_connections
    assert _number(cell("| connections per client address")) == policy.max_connections_per_client
    assert f"{policy.requests_per_s:g}/s, burst {policy.burst}" in cell("| requests per client")
    assert f"{policy.server_requests_per_s:g}/s, burst {policy.server_burst}" in cell(
        "| requests per server"
    )
    assert _number(cell("| HTTP hold before 429")) == policy.max_delay_s
    assert _number(cell("| idle timeout")) == policy.idle_timeout_s
    assert _number(cell("| HTTP header timeout")) == policy.header_timeout_s
    assert _number(cell("| HTTP request line")) * 1024 == MAX_REQUEST_LINE_BYTES
    assert _number(cell("| HTTP headers")) * 1024 == MAX_HEADER_BYTES
    assert _number(cell("| HTTP body")) * 1024 == MAX_BODY_BYTES


async def _poller(port: int, rounds: int, statuses: list[int]) -> None:
    """One connection reading its share of the 20 properties every 0.1 s."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        for _ in range(rounds):
            for name in PROPERTIES[: len(PROPERTIES) // 8 + 1]:
                writer.write(
                    f"GET /api/v1/telescope/0/{name} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode()
                )
            for _ in range(len(PROPERTIES) // 8 + 1):
                async with asyncio.timeout(5):
                    head = await reader.readuntil(b"\r\n\r\n")
                statuses.append(int(head.split(b" ", 2)[1]))
                length = re.search(rb"Content-Length: (\d+)", head, re.I)
                assert length is not None
                await reader.readexactly(int(length.group(1)))
            await asyncio.sleep(0.1)
    finally:
        writer.close()


async def test_20_properties_at_10_hz_on_8_connections_are_never_held_or_refused(
    tmp_path: Path,
) -> None:
    async with AlpacaServer(
        sim_mount(), port=0, discovery_port=None, state_dir=tmp_path, access=DEFAULT_POLICY
    ) as server:
        statuses: list[int] = []
        await asyncio.gather(*(_poller(server.port, 20, statuses) for _ in range(8)))
        assert set(statuses) == {200}
        assert server.access.delayed == 0
        assert server.access.refused_requests == 0


async def _greedy(port: int, count: int, statuses: list[int]) -> None:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    writer.write(b"GET /api/v1/telescope/0/name HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n" * count)
    try:
        for _ in range(count):
            head = await reader.readuntil(b"\r\n\r\n")
            statuses.append(int(head.split(b" ", 2)[1]))
            length = re.search(rb"Content-Length: (\d+)", head, re.I)
            assert length is not None
            await reader.readexactly(int(length.group(1)))
    finally:
        writer.close()


async def test_a_client_beyond_its_rate_is_paced_never_queued_beyond_the_hold(
    tmp_path: Path,
) -> None:
    """16 connections (the most one address may open) pipelining twice the burst: each waits
    at most 16 requests' worth of the rate (64 ms at 250/s), under the 0.25 s hold, so the
    client is paced (answers come at the rate), every request answered, none queued for
    seconds; 429 is for what would wait longer (tests/security/test_security_access.py)."""
    policy = DEFAULT_POLICY
    assert policy.max_connections_per_client / policy.requests_per_s <= policy.max_delay_s
    async with AlpacaServer(
        sim_mount(), port=0, discovery_port=None, state_dir=tmp_path, access=policy
    ) as server:
        statuses: list[int] = []
        per_connection = 2 * policy.burst // policy.max_connections_per_client
        async with asyncio.timeout(30):
            await asyncio.gather(
                *(
                    _greedy(server.port, per_connection, statuses)
                    for _ in range(policy.max_connections_per_client)
                )
            )
        assert len(statuses) == per_connection * policy.max_connections_per_client
        assert set(statuses) == {200}
        assert server.access.delayed > 0  # paced: beyond the burst, requests waited their turn
