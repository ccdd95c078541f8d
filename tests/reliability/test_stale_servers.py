"""Issue #11 part 5: LX200, Stellarium and SynScan servers stop reporting positions they lack.

The stack is ``scopelink serve --device synscan:tcp://...``'s: the SynScan driver on TCP to the
SynScan emulator, and in front of the driver the LX200, Stellarium and SynScan (bridge) servers on
TCP, talked to with raw bytes as their clients would. The device is stalled: once the driver's
last reading is older than ``stale_after_s`` each server's honest form applies (LX200 and SynScan
answer position reads with nothing, Stellarium sends no position packet), and everything comes
back once the device answers again. The dashboard's state carries the reading's age.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from datetime import UTC, datetime

from scopelink.astro import Site
from scopelink.drivers.synscan import SynScanMount
from scopelink.links import Link, open_link
from scopelink.protocol.stellarium import CURRENT_POSITION_LENGTH
from scopelink.protocol.synscan import GetRaDec, Position, SynScanClientConnection
from scopelink.servers.faults import ANY, Fault, FaultKind
from scopelink.servers.lx200 import LX200Server
from scopelink.servers.stellarium import StellariumServer
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from scopelink.web.snapshot import state_json
from tests.support.synscan import ask

SITE = Site(latitude_deg=48.0, longitude_deg=11.0)
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
STALE_AFTER_S = 1.0
QUIET_S = 1.2
"""How long a client waits to be sure no reply (or packet) comes."""


@dataclass
class Rig:
    device: SynScanEmulator
    driver: SynScanMount
    lx200_port: int
    stellarium_port: int
    synscan_port: int


@asynccontextmanager
async def rig() -> AsyncIterator[Rig]:
    sim = SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=1.0))
    await sim.connect()
    async with SynScanEmulator(sim, wire=None) as device:
        _, port = await device.on_tcp("127.0.0.1", 0)
        driver = SynScanMount(f"tcp://127.0.0.1:{port}", site=SITE, timeout_s=1.0)
        driver.stale_after_s = STALE_AFTER_S
        await driver.connect()
        async with (
            LX200Server(driver) as lx200,
            StellariumServer(driver, port=0, interval_s=0.1) as stellarium,
            SynScanEmulator(driver, wire=None) as bridge,
        ):
            _, lx200_port = await lx200.on_tcp("127.0.0.1", 0)
            _, bridge_port = await bridge.on_tcp("127.0.0.1", 0)
            yield Rig(device, driver, lx200_port, stellarium.port, bridge_port)
        await driver.disconnect()


async def lx200_reply(port: int, command: bytes) -> bytes:
    """The reply to one LX200 command on a new connection; b"" when none comes in QUIET_S."""
    link = await open_link(f"tcp://127.0.0.1:{port}")
    received = b""
    try:
        await link.write(command)
        async with asyncio.timeout(QUIET_S):
            while not received.endswith(b"#"):
                received += await link.read()
    except TimeoutError:
        pass
    finally:
        await link.close()
    return received


async def synscan_position(port: int) -> Position | None:
    """The bridge's answer to ``e``, or None when it gives none within QUIET_S."""
    link = await open_link(f"tcp://127.0.0.1:{port}")
    try:
        reply = await ask(link, SynScanClientConnection(), GetRaDec(precise=False), QUIET_S)
    except TimeoutError:
        return None
    finally:
        await link.close()
    assert isinstance(reply, Position)
    return reply


async def stellarium_bytes(link: Link, seconds: float) -> int:
    """How many bytes of position packets arrive within ``seconds``."""
    received = 0
    try:
        async with asyncio.timeout(seconds):
            while True:
                received += len(await link.read())
    except TimeoutError:
        return received


async def wait_stale(driver: SynScanMount) -> None:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + STALE_AFTER_S + 3.0
    while driver.state.position_age_s() <= STALE_AFTER_S + 0.1:
        assert loop.time() < deadline, "the reading never aged"
        await asyncio.sleep(0.05)


async def wait_fresh(driver: SynScanMount, seconds: float) -> None:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + seconds
    while not (driver.state.connected and driver.state.position_age_s() < 0.5):
        assert loop.time() < deadline, f"no fresh reading within {seconds} s"
        await asyncio.sleep(0.05)


async def test_servers_stop_reporting_positions_they_do_not_have() -> None:
    async with rig() as r:
        assert (await lx200_reply(r.lx200_port, b":GR#")).endswith(b"#")
        assert (await lx200_reply(r.lx200_port, b":GW#")).endswith(b"#")
        assert await synscan_position(r.synscan_port) is not None
        stellarium = await open_link(f"tcp://127.0.0.1:{r.stellarium_port}")
        try:
            assert await stellarium_bytes(stellarium, 0.5) >= CURRENT_POSITION_LENGTH
            fresh = state_json(r.driver, r.driver.state)
            assert fresh["stale"] is False
            assert isinstance(fresh["age_s"], float)
            assert fresh["stale_after_s"] == STALE_AFTER_S

            r.device.faults.add(Fault(FaultKind.STALL, ANY))
            await wait_stale(r.driver)
            for command in (b":GR#", b":GD#", b":GA#", b":GZ#", b":GW#", b":D#"):
                assert await lx200_reply(r.lx200_port, command) == b"", command
            assert (await lx200_reply(r.lx200_port, b":GC#")).endswith(b"#"), "dates still answer"
            assert await synscan_position(r.synscan_port) is None
            await stellarium_bytes(stellarium, 0.3)  # a packet already under way
            assert await stellarium_bytes(stellarium, QUIET_S) == 0
            stale = state_json(r.driver, r.driver.state)
            assert stale["stale"] is True
            assert isinstance(stale["age_s"], float)
            assert stale["age_s"] > STALE_AFTER_S
            assert stale["slewing"] is False

            r.device.faults.clear()
            await wait_fresh(r.driver, 5.0 + 4.0)
            assert (await lx200_reply(r.lx200_port, b":GR#")).endswith(b"#")
            assert await synscan_position(r.synscan_port) is not None
            assert await stellarium_bytes(stellarium, 0.5) >= CURRENT_POSITION_LENGTH
        finally:
            await stellarium.close()
