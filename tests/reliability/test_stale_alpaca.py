"""Issue #11 part 5: a lost or stalled device never looks healthy over ASCOM Alpaca.

The stack is the one ``scopelink serve --device synscan:tcp://...`` builds: the SynScan driver on
TCP to the SynScan emulator (its simulated mount behind it), the Alpaca server in front of the
driver, and alpyca as the client. The device is stalled (it reads commands and answers none) or
killed (its TCP server closes); Alpaca must then answer position and state reads with an error
naming the reading's age (0x407 once the link is down), Connected must follow the link, and the
reads must come back by themselves once the device does.
"""

from __future__ import annotations

import asyncio
import re
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import pytest
from alpaca.exceptions import DriverException, NotConnectedException
from alpaca.telescope import Telescope

from scopelink.astro import Site
from scopelink.drivers.synscan import SynScanMount
from scopelink.servers.alpaca import AlpacaServer
from scopelink.servers.faults import ANY, Fault, FaultKind
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(latitude_deg=48.0, longitude_deg=11.0)
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
STALE_AFTER_S = 1.0
"""Short for the tests (the default is 2 s): the bound below is what the test checks."""
REPLY_TIMEOUT_S = 1.0
"""The driver's reply timeout (the spec's 5 s by default): a stall is noticed sooner."""


@dataclass
class Stack:
    sim: SimulatedMount
    emulator: SynScanEmulator
    port: int
    driver: SynScanMount
    alpaca: AlpacaServer
    client: Telescope


@asynccontextmanager
async def stack(tmp_path: Path) -> AsyncIterator[Stack]:
    sim = SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=1.0))
    await sim.connect()
    emulator = SynScanEmulator(sim)
    await emulator.__aenter__()
    try:
        _, port = await emulator.on_tcp("127.0.0.1", 0)
        driver = SynScanMount(f"tcp://127.0.0.1:{port}", site=SITE, timeout_s=REPLY_TIMEOUT_S)
        driver.stale_after_s = STALE_AFTER_S
        await driver.connect()
        server = AlpacaServer(driver, port=0, discovery_port=None, state_dir=tmp_path)
        async with server:
            client = Telescope(f"127.0.0.1:{server.port}", 0)
            await asyncio.to_thread(setattr, client, "Connected", True)
            yield Stack(sim, emulator, port, driver, server, client)
            await driver.disconnect()
    finally:
        await emulator.close()


async def read(client: Telescope, name: str) -> object:
    return await asyncio.to_thread(getattr, client, name)


async def failure_of(client: Telescope, name: str) -> Exception | None:
    """The exception reading ``name`` raises, or None when it answers."""
    try:
        await read(client, name)
    except Exception as error:
        return error
    return None


async def within(seconds: float, what: str, check: object) -> float:
    """Call ``check`` (an async callable returning bool) until true; the seconds it took."""
    loop = asyncio.get_running_loop()
    start = loop.time()
    while not await check():  # type: ignore[operator]
        if loop.time() - start > seconds:
            raise AssertionError(f"{what} did not happen within {seconds} s")
        await asyncio.sleep(0.05)
    return loop.time() - start


async def test_a_stalled_device_is_not_served_as_current(tmp_path: Path) -> None:
    async with stack(tmp_path) as s:
        assert isinstance(await read(s.client, "Altitude"), float)
        s.emulator.faults.add(Fault(FaultKind.STALL, ANY))

        async def position_refused() -> bool:
            return await failure_of(s.client, "Altitude") is not None

        # Once the last reading is older than stale_after_s, reads fail (naming the age); a
        # read may take a few polls' time to age, hence the margin.
        took = await within(STALE_AFTER_S + 1.5, "Altitude refused", position_refused)
        assert took >= STALE_AFTER_S * 0.5, "fresh readings are served"
        error = await failure_of(s.client, "Altitude")
        assert isinstance(error, DriverException | NotConnectedException), error
        assert re.search(r"\d+\.\d s old", str(error)), error
        for name in ("Azimuth", "RightAscension", "Declination", "Slewing", "Tracking"):
            assert await failure_of(s.client, name) is not None, name

        # The poll times out and its resynchronisation too: the link is declared down.
        async def link_down() -> bool:
            return not await read(s.client, "Connected")

        await within(4 * REPLY_TIMEOUT_S + 2.0, "Connected false", link_down)
        error = await failure_of(s.client, "Altitude")
        assert isinstance(error, NotConnectedException), error
        assert not s.driver.state.slewing, "no motion is claimed while disconnected"

        s.emulator.faults.clear()
        s.emulator.faults.resume()

        async def back() -> bool:
            return await failure_of(s.client, "Altitude") is None

        await within(5.0 + 4 * REPLY_TIMEOUT_S, "the position back", back)
        assert await read(s.client, "Connected") is True


async def test_a_killed_device_reads_as_disconnected_and_reconnects_on_the_same_port(
    tmp_path: Path,
) -> None:
    async with stack(tmp_path) as s:
        assert isinstance(await read(s.client, "Altitude"), float)
        await s.emulator.close()

        async def refused_not_connected() -> bool:
            return isinstance(await failure_of(s.client, "Altitude"), NotConnectedException)

        await within(STALE_AFTER_S + 3.0, "Altitude refused with 0x407", refused_not_connected)
        assert await read(s.client, "Connected") is False
        error = await failure_of(s.client, "Altitude")
        assert re.search(r"\d+\.\d s", str(error)), error

        # The device comes back on the same port: the driver reopens the link by itself.
        s.emulator = SynScanEmulator(s.sim)
        await s.emulator.__aenter__()
        await s.emulator.on_tcp("127.0.0.1", s.port)

        async def connected() -> bool:
            return await read(s.client, "Connected") is True

        await within(5.0, "Connected again", connected)
        assert isinstance(await read(s.client, "Altitude"), float)


async def test_device_state_leaves_out_what_is_stale(tmp_path: Path) -> None:
    async with stack(tmp_path) as s:
        names = {item["Name"] for item in await read(s.client, "DeviceState")}  # type: ignore[attr-defined]
        assert {"Altitude", "Slewing", "TimeStamp"} <= names
        s.emulator.faults.add(Fault(FaultKind.STALL, ANY))

        async def position_left_out() -> bool:
            try:
                items = await read(s.client, "DeviceState")
            except (DriverException, NotConnectedException):
                return False
            return "Altitude" not in {item["Name"] for item in items}  # type: ignore[attr-defined]

        await within(STALE_AFTER_S + 1.5, "DeviceState without Altitude", position_left_out)


@pytest.fixture(autouse=True)
def _no_proxy(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("http_proxy", raising=False)
