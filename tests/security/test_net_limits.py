"""Issue #12, parts 2 and 3: request size limits (414, 431, 413) answered as soon as crossed,
memory back near its baseline after oversized requests, header-read and idle timeouts, and a
normal client answered within 1 s while 200 slow connections from many loopback addresses
(127.0.0.2-21: distinct clients to the policy, all on this machine) hold on."""

from __future__ import annotations

import asyncio
import contextlib
import subprocess
import sys
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager
from pathlib import Path

import pytest

from scopelink.servers.access import DEFAULT_POLICY, AccessPolicy
from scopelink.servers.alpaca import AlpacaServer
from scopelink.servers.http_guard import EVICTABLE_AFTER_S
from scopelink.web import Dashboard
from tests.support.alpaca import sim_mount

Connect = Callable[[], Awaitable[tuple[asyncio.StreamReader, asyncio.StreamWriter]]]


@asynccontextmanager
async def alpaca(tmp_path: Path, **timeouts: float) -> AsyncIterator[int]:
    server = AlpacaServer(
        sim_mount(), port=0, discovery_port=None, state_dir=tmp_path, access=DEFAULT_POLICY
    )
    for name, value in timeouts.items():
        setattr(server.guard, name, value)
    async with server:
        yield server.port


@asynccontextmanager
async def dashboard(tmp_path: Path, **timeouts: float) -> AsyncIterator[int]:
    mount = sim_mount()
    await mount.connect()
    served = Dashboard(mount, port=0, trace=False, access=DEFAULT_POLICY)
    for name, value in timeouts.items():
        setattr(served.guard, name, value)
    try:
        async with served:
            yield served.port
    finally:
        await mount.disconnect()


SERVERS = {"alpaca": alpaca, "dashboard": dashboard}
PATHS = {"alpaca": "/api/v1/telescope/0/name", "dashboard": "/api/access"}


async def status_of(reader: asyncio.StreamReader, timeout_s: float = 3.0) -> int:
    async with asyncio.timeout(timeout_s):
        line = await reader.readline()
    return int(line.split(b" ", 2)[1])


@pytest.mark.parametrize("kind", sorted(SERVERS))
async def test_a_long_request_line_is_answered_414_before_it_ends(
    tmp_path: Path, kind: str
) -> None:
    async with SERVERS[kind](tmp_path) as port:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.write(b"GET /" + b"a" * (9 * 1024))  # and never the end of the line
        assert await status_of(reader) == 414
        writer.close()


@pytest.mark.parametrize("kind", sorted(SERVERS))
async def test_long_headers_are_answered_431_before_they_end(tmp_path: Path, kind: str) -> None:
    async with SERVERS[kind](tmp_path) as port:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.write(f"GET {PATHS[kind]} HTTP/1.1\r\nHost: 127.0.0.1\r\n".encode())
        for n in range(40):  # 40 headers of 500 bytes: 20 KB, no blank line
            writer.write(f"X-Pad-{n}: {'p' * 490}\r\n".encode())
        assert await status_of(reader) == 431
        writer.close()
        # one header of 20 KB too
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.write(f"GET {PATHS[kind]} HTTP/1.1\r\nX-Big: {'b' * 20_000}".encode())
        assert await status_of(reader) == 431
        writer.close()


@pytest.mark.parametrize("kind", sorted(SERVERS))
async def test_a_slow_request_head_is_cut_off(tmp_path: Path, kind: str) -> None:
    async with SERVERS[kind](tmp_path, header_timeout_s=0.5) as port:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.write(f"GET {PATHS[kind]} HTTP/1.1\r\n".encode())
        started = time.monotonic()
        closed = False
        for n in range(50):  # one header every 0.1 s for up to 5 s: never a complete head
            await asyncio.sleep(0.1)
            try:
                writer.write(f"X-{n}: y\r\n".encode())
                await writer.drain()
            except ConnectionError:
                closed = True
                break
            if reader.at_eof() or reader._buffer:  # type: ignore[attr-defined]
                closed = True
                break
        assert closed, "a head trickled in for 5 s and the connection stayed open"
        assert time.monotonic() - started >= 0.5  # not before the timeout
        writer.close()


@pytest.mark.parametrize("kind", sorted(SERVERS))
async def test_an_idle_connection_is_closed(tmp_path: Path, kind: str) -> None:
    async with SERVERS[kind](tmp_path, idle_timeout_s=0.5) as port:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.write(f"GET {PATHS[kind]} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
        assert await status_of(reader) == 200
        async with asyncio.timeout(3):  # kept alive, then closed after 0.5 s of silence
            while await reader.read(4096):
                pass
        writer.close()


async def _slow_client(port: int, source: str, held: list[asyncio.StreamWriter]) -> None:
    with contextlib.suppress(OSError):
        _, writer = await asyncio.open_connection("127.0.0.1", port, local_addr=(source, 0))
        writer.write(b"GET / HTTP/1.1\r\nX-Slow: ")  # and nothing more
        held.append(writer)


@pytest.mark.parametrize("kind", sorted(SERVERS))
async def test_a_normal_client_is_answered_within_a_second_under_200_slow_connections(
    tmp_path: Path, kind: str
) -> None:
    async with SERVERS[kind](tmp_path) as port:
        held: list[asyncio.StreamWriter] = []
        sources = [f"127.0.0.{2 + n % 20}" for n in range(200)]
        await asyncio.gather(*(_slow_client(port, source, held) for source in sources))
        await asyncio.sleep(EVICTABLE_AFTER_S + 0.2)  # they have held their slots a while
        try:
            for _ in range(3):
                started = time.monotonic()
                reader, writer = await asyncio.open_connection("127.0.0.1", port)
                head = f"GET {PATHS[kind]} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n"
                writer.write(head.encode() + b"\r\n")
                assert await status_of(reader, timeout_s=1.0) == 200
                assert time.monotonic() - started < 1.0
                writer.close()
        finally:
            for writer in held:
                writer.transport.abort()


_SERVER_SCRIPT = """
import asyncio, sys, tempfile
from pathlib import Path
from scopelink.servers.alpaca import AlpacaServer
from scopelink.servers.http_guard import EVICTABLE_AFTER_S
from scopelink.astro import Site
from scopelink.sim import EQ6, SimulatedMount

async def main():
    server = AlpacaServer(SimulatedMount(EQ6, site=Site(50.0, 10.0)), port=0, discovery_port=None,
                          state_dir=Path(tempfile.mkdtemp()))
    async with server:
        print(server.port, flush=True)
        await asyncio.Event().wait()

asyncio.run(main())
"""


def _rss_kib(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise AssertionError("no VmRSS")


async def _flood(port: int, head: bytes, body_mib: int) -> None:
    """Send ``head`` then ``body_mib`` MiB of one unending URL or header, until refused."""
    with contextlib.suppress(OSError):
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.write(head)
        chunk = b"x" * (1 << 20)
        for _ in range(body_mib):
            writer.write(chunk)
            await writer.drain()
            if reader.at_eof():
                break
        writer.transport.abort()


async def _normal_requests(port: int, count: int) -> None:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    for _ in range(count):
        writer.write(b"GET /api/v1/telescope/0/name HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
        assert await status_of(reader) == 200
        await reader.readuntil(b"}")
    writer.close()


async def test_memory_returns_near_its_baseline_after_oversized_requests() -> None:
    process = subprocess.Popen(  # noqa: ASYNC220 - started once, read in a thread
        [sys.executable, "-c", _SERVER_SCRIPT], stdout=subprocess.PIPE, text=True
    )
    try:
        assert process.stdout is not None
        port = int(await asyncio.to_thread(process.stdout.readline))
        await _normal_requests(port, 200)
        baseline = _rss_kib(process.pid)
        # one 64 MiB header, eight 16 MiB URLs at once (the attack, scaled down)
        await _flood(port, b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: ", 64)
        await asyncio.gather(*(_flood(port, b"GET /", 16) for _ in range(8)))
        await asyncio.sleep(0.5)
        await _normal_requests(port, 20)
        grown_mib = (_rss_kib(process.pid) - baseline) / 1024
        assert grown_mib < 10.0, f"RSS grew by {grown_mib:.1f} MiB"
    finally:
        process.terminate()
        process.wait(timeout=10)


async def test_only_idle_connections_of_other_addresses_make_room_not_an_address_at_its_cap(
    tmp_path: Path,
) -> None:
    policy = AccessPolicy(max_connections=4, max_connections_per_client=2)
    async with AlpacaServer(
        sim_mount(), port=0, discovery_port=None, state_dir=tmp_path, access=policy
    ) as server:
        port = server.port
        held = []
        for source in ("127.0.0.2", "127.0.0.2", "127.0.0.3", "127.0.0.3"):
            held.append(await asyncio.open_connection("127.0.0.1", port, local_addr=(source, 0)))
        await asyncio.sleep(EVICTABLE_AFTER_S + 0.2)
        request = b"GET /management/apiversions HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
        # 127.0.0.2 at its cap: refused, and nobody is evicted for it
        reader, writer = await asyncio.open_connection(
            "127.0.0.1", port, local_addr=("127.0.0.2", 0)
        )
        writer.write(request)
        assert await status_of(reader) == 503
        writer.close()
        assert server.guard.evicted == 0
        # a new address: the connection idle longest (127.0.0.2's first) makes room
        reader, writer = await asyncio.open_connection(
            "127.0.0.1", port, local_addr=("127.0.0.4", 0)
        )
        writer.write(request)
        assert await status_of(reader) == 200
        writer.close()
        assert server.guard.evicted == 1
        first_reader, _ = held[0]
        async with asyncio.timeout(3):
            assert await first_reader.read() == b""  # the evicted one was closed
        for _, held_writer in held:
            held_writer.close()
