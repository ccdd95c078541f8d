"""Helpers for the Alpaca tests: the simulated mount behind a real AlpacaServer on 127.0.0.1."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from pathlib import Path
from typing import TypeVar

from alpaca.telescope import Telescope

from scopelink.astro import Site, observed_to_j2000
from scopelink.mount import Limits
from scopelink.servers.alpaca import AlpacaServer, TelescopeConfig
from scopelink.sim import EQ6, MountModel, SimClock, SimulatedMount

SITE = Site(latitude_deg=50.0, longitude_deg=10.0, elevation_m=300.0)
SPEED_UP = 50.0
"""Simulated seconds per real second: a 90° slew at 3.3°/s lands in about 0.6 s."""
WATCHABLE_SPEED_UP = 20.0
"""For tests that must see a slew or pulse in progress: a 90° slew then lasts about 1.5 s."""

T = TypeVar("T")


def sim_mount(
    model: MountModel = EQ6, *, limits: Limits | None = None, speed_up: float = SPEED_UP
) -> SimulatedMount:
    return SimulatedMount(model, site=SITE, clock=SimClock.accelerated(speed_up), limits=limits)


@asynccontextmanager
async def serve(
    mount: SimulatedMount | None = None,
    *,
    state_dir: Path,
    config: TelescopeConfig | None = None,
    discovery: bool = False,
) -> AsyncIterator[AlpacaServer]:
    """A running server on free ports of 127.0.0.1 (discovery off unless asked for)."""
    server = AlpacaServer(
        mount or sim_mount(),
        host="127.0.0.1",
        port=0,
        discovery_port=0 if discovery else None,
        state_dir=state_dir,
        config=config,
    )
    async with server:
        yield server


def client(server: AlpacaServer) -> Telescope:
    """alpyca's Telescope for the server's telescope/0."""
    return Telescope(f"127.0.0.1:{server.port}", 0)


async def blocking(call: Callable[[], T]) -> T:
    """Run one blocking alpyca call in a thread, so the server keeps running in this loop."""
    return await asyncio.to_thread(call)


def radec_at(mount: SimulatedMount, alt_deg: float, az_deg: float) -> tuple[float, float]:
    """The J2000 RA/Dec at an observed altitude and azimuth now."""
    return observed_to_j2000(alt_deg, az_deg, mount.now(), mount.site)


async def wait_until(predicate: Callable[[], bool], timeout_s: float, what: str) -> float:
    """Poll ``predicate`` (in a thread: it may call the client) until true; returns seconds."""
    loop = asyncio.get_running_loop()
    start = loop.time()
    while not await asyncio.to_thread(predicate):
        if loop.time() - start > timeout_s:
            raise AssertionError(f"{what} did not happen within {timeout_s} s")
        await asyncio.sleep(0.05)
    return loop.time() - start


API = "/api/v1/telescope/0"


async def read_reply(reader: asyncio.StreamReader) -> tuple[int, dict[str, str], bytes]:
    head = (await reader.readuntil(b"\r\n\r\n")).decode("latin-1")
    status = int(head.split(" ", 2)[1])
    headers = {
        name.strip().lower(): value.strip()
        for name, value in (line.split(":", 1) for line in head.split("\r\n")[1:] if ":" in line)
    }
    body = await reader.readexactly(int(headers.get("content-length", "0")))
    return status, headers, body
