"""Issue #12, part 3: the line protocols' idle timeout. An LX200 or SynScan connection that
sends nothing for the policy's ``idle_timeout_s`` is closed (its slot freed); one that keeps
talking stays open. Stellarium is exempt: its clients send only to command a goto."""

from __future__ import annotations

import asyncio
import time

import pytest

from scopelink.servers.access import DEFAULT_POLICY, OPEN_POLICY, AccessPolicy
from scopelink.servers.hosting import HostedDevice
from scopelink.servers.lx200 import LX200Server
from scopelink.servers.synscan import SynScanEmulator
from tests.support.alpaca import sim_mount

SHORT = AccessPolicy(idle_timeout_s=0.5)
# a command each protocol answers without moving anything
PINGS = {"lx200": b":GR#", "synscan": b"Ka"}


def build(kind: str, policy: AccessPolicy) -> HostedDevice:
    mount = sim_mount()
    if kind == "lx200":
        return LX200Server(mount, access=policy)
    return SynScanEmulator(mount, wire=None, access=policy)


@pytest.mark.parametrize("kind", sorted(PINGS))
async def test_a_silent_client_is_closed_after_the_idle_timeout(kind: str) -> None:
    async with build(kind, SHORT) as server:
        _, port = await server.on_tcp("127.0.0.1", 0)
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        started = time.monotonic()
        async with asyncio.timeout(5):
            assert await reader.read() == b""  # closed by the server
        assert 0.4 < time.monotonic() - started < 3.0
        writer.close()
        async with asyncio.timeout(3):  # its slot is freed as the handler ends
            while server.access.open_connections:  # noqa: ASYNC110 - a counter, not an event
                await asyncio.sleep(0.02)


@pytest.mark.parametrize("kind", sorted(PINGS))
async def test_a_client_that_keeps_talking_stays_connected(kind: str) -> None:
    async with build(kind, SHORT) as server:
        _, port = await server.on_tcp("127.0.0.1", 0)
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        for _ in range(6):  # 1.2 s in all, never 0.5 s of silence
            writer.write(PINGS[kind])
            async with asyncio.timeout(3):
                assert await reader.read(100)
            await asyncio.sleep(0.2)
        writer.close()


def test_the_default_idle_timeout_lets_a_planetarium_poll_once_a_minute() -> None:
    assert DEFAULT_POLICY.idle_timeout_s >= 120.0
    assert OPEN_POLICY.idle_timeout_s == DEFAULT_POLICY.idle_timeout_s
    with pytest.raises(ValueError, match="timeouts"):
        AccessPolicy(idle_timeout_s=0.0)
