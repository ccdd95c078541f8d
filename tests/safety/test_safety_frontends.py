"""Nothing below scopelink's horizon reaches the device, from any front end.

Behind every front end: the SynScan driver on TCP to the SynScan emulator, whose simulated mount
would obey a goto down to -10°. The targets sit at 2° (below scopelink's 10° horizon, above the
device's), so a goto that slipped through would be carried out; the tests assert on the commands
the device received and on the true altitude the simulated mount reached.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

import aiohttp
import pytest
from alpaca.exceptions import InvalidValueException
from alpaca.telescope import Telescope, TelescopeAxes

from scopelink.astro import j2000_to_apparent
from scopelink.links.tcp import TcpLink
from scopelink.protocol.stellarium import GotoMessage, StellariumClientConnection
from scopelink.protocol.synscan import (
    Ack,
    GotoAzAlt,
    GotoRaDec,
    SynScanClientConnection,
    VariableRateSlew,
)
from scopelink.protocol.synscan import Axis as SynScanAxis
from scopelink.servers.alpaca import AlpacaServer
from scopelink.servers.lx200 import LX200Server
from scopelink.servers.stellarium import StellariumServer
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import AZ_GTI
from scopelink.web import Dashboard
from tests.support.safety import (
    HORIZON_DEG,
    TOLERANCE_DEG,
    Rig,
    j2000_at,
    synscan_rig,
    wait_until_still,
)
from tests.support.synscan import ask

LOW = (2.0, 200.0)
"""A target below scopelink's horizon (alt, az) that the device itself would slew to."""
WEST_LOW = (13.0, 250.0)
"""Where rate-motion tests start: low in the west, where the polar axis forwards lowers the tube."""


def assert_no_goto_reached_the_device(rig: Rig) -> None:
    assert rig.gotos_received() == [], rig.gotos_received()
    assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg


def assert_guarded_stop(rig: Rig) -> None:
    assert rig.mount.guard.stops >= 1
    assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg
    assert any("below the configured horizon" in p for p in rig.mount.state.problems)


# --- ASCOM Alpaca --------------------------------------------------------------------------------


async def test_alpaca_gotos_below_the_horizon_never_reach_the_device(tmp_path: Path) -> None:
    async with synscan_rig() as rig:
        server = AlpacaServer(
            rig.mount, host="127.0.0.1", port=0, discovery_port=None, state_dir=tmp_path
        )
        async with server:
            telescope = Telescope(f"127.0.0.1:{server.port}", 0)
            await asyncio.to_thread(setattr, telescope, "Connected", True)
            ra, dec = j2000_to_apparent(*j2000_at(rig.sim, *LOW), rig.sim.now())
            with pytest.raises(InvalidValueException, match="below the configured horizon"):
                await asyncio.to_thread(telescope.SlewToCoordinatesAsync, ra, dec)
            await asyncio.to_thread(setattr, telescope, "Tracking", False)
            with pytest.raises(InvalidValueException, match="below the configured horizon"):
                await asyncio.to_thread(telescope.SlewToAltAzAsync, LOW[1], LOW[0])
        assert_no_goto_reached_the_device(rig)


async def test_alpaca_move_axis_is_stopped_above_the_horizon(tmp_path: Path) -> None:
    async with synscan_rig(at=WEST_LOW, rate=2.0) as rig:
        server = AlpacaServer(
            rig.mount, host="127.0.0.1", port=0, discovery_port=None, state_dir=tmp_path
        )
        async with server:
            telescope = Telescope(f"127.0.0.1:{server.port}", 0)
            await asyncio.to_thread(setattr, telescope, "Connected", True)
            await asyncio.to_thread(telescope.MoveAxis, TelescopeAxes.axisPrimary, 3.0)
            await wait_until_still(rig)
            assert await asyncio.to_thread(lambda: telescope.Slewing) is False
        assert_guarded_stop(rig)


# --- LX200 ---------------------------------------------------------------------------------------


class LX200Client:
    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader, self.writer = reader, writer

    async def send(self, command: str, reply_bytes: int = 0) -> bytes:
        self.writer.write(command.encode())
        await self.writer.drain()
        if reply_bytes == 0:
            return b""
        async with asyncio.timeout(5):
            return await self.reader.readexactly(reply_bytes)

    async def until_hash(self) -> bytes:
        async with asyncio.timeout(5):
            return await self.reader.readuntil(b"#")


@asynccontextmanager
async def lx200_client(rig: Rig) -> AsyncIterator[LX200Client]:
    async with LX200Server(rig.mount) as server:
        host, port = await server.on_tcp(port=0)
        reader, writer = await asyncio.open_connection(host, port)
        try:
            yield LX200Client(reader, writer)
        finally:
            writer.close()
            await writer.wait_closed()


def sexagesimal(value: float, *, signed: bool, separator: str) -> str:
    sign = ("-" if value < 0 else "+") if signed else ""
    seconds = round(abs(value) * 3600)
    return f"{sign}{seconds // 3600:02d}{separator}{seconds // 60 % 60:02d}:{seconds % 60:02d}"


async def test_lx200_goto_below_the_horizon_is_refused_with_1() -> None:
    async with synscan_rig() as rig, lx200_client(rig) as lx200:
        ra, dec = j2000_to_apparent(*j2000_at(rig.sim, *LOW), rig.sim.now())
        assert await lx200.send(f":Sr {sexagesimal(ra, signed=False, separator=':')}#", 1) == b"1"
        assert await lx200.send(f":Sd {sexagesimal(dec, signed=True, separator='*')}#", 1) == b"1"
        assert await lx200.send(":MS#", 1) == b"1"  # 1: below the horizon
        assert b"below horizon" in await lx200.until_hash()
    assert_no_goto_reached_the_device(rig)


async def test_lx200_move_south_on_an_altaz_mount_stops_above_the_horizon() -> None:
    async with (
        synscan_rig(model=AZ_GTI, at=(13.0, 180.0), rate=2.0) as rig,
        lx200_client(rig) as lx200,
    ):
        await lx200.send(":RS#")  # the slew rate
        await lx200.send(":Ms#")  # south on an alt-az mount: down
        await wait_until_still(rig)
        assert rig.slews_received()  # the move did reach the device...
        assert_guarded_stop(rig)  # ...and was stopped in time
        # Pressed again and again: each press is stopped in time again.
        for _ in range(2):
            await lx200.send(":Ms#")
            await wait_until_still(rig)
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg


async def test_lx200_client_that_drops_mid_slew_stops_the_motion() -> None:
    async with synscan_rig(model=AZ_GTI, at=(40.0, 180.0)) as rig:
        async with lx200_client(rig) as lx200:
            await lx200.send(":RS#")
            await lx200.send(":Mn#")  # up, far from every limit
            await asyncio.sleep(0.3)
            assert rig.mount.guard.rate_motions
        # The connection is gone: the dead-man stopped the axis.
        rest = await wait_until_still(rig, timeout_s=5.0)
        assert rest < 45.0
        assert rig.mount.guard.rate_motions == {}
        assert not rig.mount.state.slewing


# --- Stellarium ----------------------------------------------------------------------------------


async def test_stellarium_goto_below_the_horizon_never_reaches_the_device() -> None:
    async with synscan_rig() as rig:
        server = StellariumServer(rig.mount, "127.0.0.1", 0)
        async with server:
            reader, writer = await asyncio.open_connection("127.0.0.1", server.port)
            codec = StellariumClientConnection()
            writer.write(codec.send(GotoMessage.from_degrees(*j2000_at(rig.sim, *LOW))))
            await writer.drain()
            await reader.read(100)  # a position report: the goto has been handled
            await asyncio.sleep(0.3)
            writer.close()
            await writer.wait_closed()
        assert_no_goto_reached_the_device(rig)


# --- the SynScan server --------------------------------------------------------------------------


async def test_synscan_server_gotos_below_the_horizon_never_reach_the_device() -> None:
    async with synscan_rig() as rig, SynScanEmulator(rig.mount, wire=None) as server:
        host, port = await server.on_tcp("127.0.0.1", 0)
        link_reader, link_writer = await asyncio.open_connection(host, port)
        link = TcpLink(link_reader, link_writer, name="phone app")
        client = SynScanClientConnection()
        ra, dec = j2000_at(rig.sim, *LOW)
        for precise in (True, False):  # r and b, then R and B
            goto = GotoRaDec.from_hours_degrees(ra, dec, precise)
            assert isinstance(await ask(link, client, goto), Ack)  # acknowledged, not obeyed
            goto_altaz = GotoAzAlt.from_degrees(LOW[1], LOW[0], precise)
            assert isinstance(await ask(link, client, goto_altaz), Ack)
        await link.close()
    assert_no_goto_reached_the_device(rig)


async def test_synscan_server_rate_slew_is_stopped_and_a_dropped_client_stops_it() -> None:
    async with (
        synscan_rig(at=WEST_LOW, rate=2.0) as rig,
        SynScanEmulator(rig.mount, wire=None, dead_man=True) as server,
    ):
        host, port = await server.on_tcp("127.0.0.1", 0)
        link = TcpLink(*await asyncio.open_connection(host, port), name="phone app")
        client = SynScanClientConnection()
        west = VariableRateSlew.from_arcsec_per_second(SynScanAxis.AZM_RA, 3.0 * 3600.0)
        await ask(link, client, west)
        await wait_until_still(rig)
        assert_guarded_stop(rig)
        # Upwards (east), then the phone drops: the dead-man stops the slew.
        east = VariableRateSlew.from_arcsec_per_second(SynScanAxis.AZM_RA, -1.0 * 3600.0)
        await ask(link, client, east)
        await asyncio.sleep(0.3)
        await link.close()
        rest = await wait_until_still(rig, timeout_s=5.0)
        assert rest < 13.0
        assert rig.mount.guard.rate_motions == {}


# --- the dashboard -------------------------------------------------------------------------------


async def test_dashboard_goto_below_the_horizon_is_409_and_never_reaches_the_device() -> None:
    async with (
        synscan_rig() as rig,
        Dashboard(rig.mount, port=0) as dashboard,
        aiohttp.ClientSession(base_url=dashboard.url) as http,
    ):
        ra, dec = j2000_at(rig.sim, *LOW)
        for body in ({"alt_deg": LOW[0], "az_deg": LOW[1]}, {"ra_hours": ra, "dec_deg": dec}):
            async with http.post("/api/goto", json=body) as response:
                assert response.status == 409, await response.text()
                assert "below the configured horizon" in (await response.json())["error"]
    assert_no_goto_reached_the_device(rig)


async def test_dashboard_pad_is_stopped_at_the_horizon_and_by_a_closed_page() -> None:
    async with (
        synscan_rig(at=WEST_LOW, rate=2.0) as rig,
        Dashboard(rig.mount, port=0) as dashboard,
        aiohttp.ClientSession(base_url=dashboard.url) as http,
    ):
        async with http.ws_connect("/ws") as page:
            session = json.loads((await page.receive()).data)["session"]
            move = {"axis": "primary", "rate_deg_s": 3.0, "session": session}
            async with http.post("/api/move", json=move) as response:
                assert response.status == 200
            await wait_until_still(rig)
            assert_guarded_stop(rig)
            up = {"axis": "primary", "rate_deg_s": -1.0, "session": session}
            async with http.post("/api/move", json=up) as response:
                assert response.status == 200
            await asyncio.sleep(0.3)
        # The page closed while its pad move ran: the dead-man stopped it.
        rest = await wait_until_still(rig, timeout_s=5.0)
        assert rest < 13.0
        assert rig.mount.guard.rate_motions == {}
        # A move naming the closed page (sent while its link was down, or late) would have no
        # owner, so nothing would stop it when the page goes: it is refused, nothing moves.
        async with http.post("/api/move", json=up) as response:
            assert response.status == 409, await response.text()
            assert (await response.json())["kind"] == "SessionGone"
        await asyncio.sleep(0.3)
        assert rig.mount.guard.rate_motions == {}
