"""No front end points the mount at the Sun (issue #11 part 3), and the guard stops a rate motion
before the Sun's zone.

Behind every front end: the SynScan driver on TCP to the SynScan emulator, whose simulated mount
has no Sun avoidance of its own (a hand control has none), on a clock that starts at
2026-06-21 12:00 UTC at 51.5° N 0° E, where the Sun stands at altitude 62.0°, azimuth 179.1°.
The tests assert on the commands the device received and, for the guard, on the true position.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime
from pathlib import Path

import aiohttp
import pytest
from alpaca.exceptions import InvalidValueException
from alpaca.telescope import Telescope, TelescopeAxes

from scopelink.astro import Site, j2000_to_apparent
from scopelink.drivers.synscan import SynScanMount
from scopelink.links.tcp import TcpLink
from scopelink.mount import Limits
from scopelink.mount.sun import SunZone
from scopelink.mount.types import AlignmentMode
from scopelink.protocol.stellarium import GotoMessage, StellariumClientConnection
from scopelink.protocol.synscan import (
    Ack,
    AnyCommand,
    AnyReply,
    GotoAzAlt,
    GotoRaDec,
    SynScanClientConnection,
)
from scopelink.servers.alpaca import AlpacaServer
from scopelink.servers.lx200 import LX200Server
from scopelink.servers.stellarium import StellariumServer
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import AZ_GTI, EQ6, MountModel, SimClock, SimulatedMount
from tests.support.safety import Rig, place
from tests.support.synscan import ask

SITE = Site(51.5, 0.0, pressure_hpa=0.0)
"""No refraction: the driver's and the simulator's altitudes are the same geometry."""
NOON = datetime(2026, 6, 21, 12, 0, tzinfo=UTC)
RADIUS_DEG = 15.0


def sun_now(rig: Rig) -> SunZone:
    return SunZone(RADIUS_DEG, SITE, rig.sim.now(), AlignmentMode.ALT_AZ)


@asynccontextmanager
async def sun_rig(
    *, model: MountModel = EQ6, at: tuple[float, float] = (30.0, 100.0)
) -> AsyncIterator[Rig]:
    """The SynScan driver (Sun avoidance 15°, horizon 0°) on TCP to the SynScan emulator in
    front of a simulated ``model`` with no Sun avoidance, pointing at ``at`` (alt, az) at noon;
    the simulator's clock then runs in real time."""
    clock = SimClock.accelerated(500.0, NOON)
    device_limits = Limits(horizon_deg=-10.0, sun_avoidance_deg=0.0)
    sim = SimulatedMount(model, site=SITE, clock=clock, limits=device_limits)
    await sim.connect()
    await place(sim, *at)
    clock.set_rate(1.0)
    async with SynScanEmulator(sim, SynScanConfig(model=model.synscan_model_code or 0)) as device:
        host, port = await device.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(
            f"tcp://{host}:{port}",
            site=SITE,
            clock=sim.now,
            limits=Limits(horizon_deg=0.0, sun_avoidance_deg=RADIUS_DEG),
        )
        rig = Rig(mount, sim)
        answer = device.hand_control.answer

        async def recording_answer(command: AnyCommand) -> AnyReply:
            rig.received.append(command)
            return await answer(command)

        device.hand_control.answer = recording_answer  # type: ignore[method-assign]
        await mount.connect()
        try:
            yield rig
        finally:
            await mount.disconnect()


def sun_apparent(rig: Rig) -> tuple[float, float]:
    zone = sun_now(rig)
    return j2000_to_apparent(zone.ra_j2000_hours, zone.dec_j2000_deg, rig.sim.now())


async def test_alpaca_refuses_the_sun_with_0x401_and_the_reason(tmp_path: Path) -> None:
    async with sun_rig() as rig:
        server = AlpacaServer(
            rig.mount, host="127.0.0.1", port=0, discovery_port=None, state_dir=tmp_path
        )
        async with server:
            telescope = Telescope(f"127.0.0.1:{server.port}", 0)
            await asyncio.to_thread(setattr, telescope, "Connected", True)
            ra, dec = sun_apparent(rig)
            with pytest.raises(InvalidValueException, match="Sun avoidance zone"):
                await asyncio.to_thread(telescope.SlewToCoordinatesAsync, ra, dec)
            with pytest.raises(InvalidValueException, match="sync position is"):
                await asyncio.to_thread(telescope.SyncToCoordinates, ra, dec)
            await asyncio.to_thread(setattr, telescope, "Tracking", False)
            zone = sun_now(rig)
            with pytest.raises(InvalidValueException, match="Sun avoidance zone"):
                await asyncio.to_thread(telescope.SlewToAltAzAsync, zone.az_deg, zone.alt_deg - 5)
        assert rig.gotos_received() == []


async def test_alpaca_slew_through_the_sun_is_refused(tmp_path: Path) -> None:
    """AZ-GTi at the Sun's altitude 60° of azimuth east of it, to 60° west: the short way round
    sweeps through the Sun."""
    async with sun_rig(model=AZ_GTI, at=(62.0, 120.0)) as rig:
        server = AlpacaServer(
            rig.mount, host="127.0.0.1", port=0, discovery_port=None, state_dir=tmp_path
        )
        async with server:
            telescope = Telescope(f"127.0.0.1:{server.port}", 0)
            await asyncio.to_thread(setattr, telescope, "Connected", True)
            await asyncio.to_thread(setattr, telescope, "Tracking", False)
            with pytest.raises(InvalidValueException, match="would pass"):
                await asyncio.to_thread(telescope.SlewToAltAzAsync, 240.0, 62.0)
        assert rig.gotos_received() == []


async def test_lx200_goto_the_sun_is_refused_with_2() -> None:
    async with sun_rig() as rig, LX200Server(rig.mount) as server:
        host, port = await server.on_tcp(port=0)
        reader, writer = await asyncio.open_connection(host, port)
        ra, dec = sun_apparent(rig)
        seconds_ra, seconds_dec = round(ra * 3600), round(abs(dec) * 3600)
        sign = "-" if dec < 0 else "+"
        writer.write(
            f":Sr {seconds_ra // 3600:02d}:{seconds_ra // 60 % 60:02d}:{seconds_ra % 60:02d}#"
            f":Sd {sign}{seconds_dec // 3600:02d}*{seconds_dec // 60 % 60:02d}:"
            f"{seconds_dec % 60:02d}#:MS#".encode()
        )
        async with asyncio.timeout(5):
            assert await reader.readexactly(2) == b"11"  # both coordinates accepted
            assert await reader.readuntil(b"#") == b"2Too close to the Sun#"
        writer.close()
        await writer.wait_closed()
        assert rig.gotos_received() == []


async def test_stellarium_goto_the_sun_is_ignored_and_logged(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING, logger="scopelink")
    async with sun_rig() as rig, StellariumServer(rig.mount, "127.0.0.1", 0) as server:
        reader, writer = await asyncio.open_connection("127.0.0.1", server.port)
        zone = sun_now(rig)
        codec = StellariumClientConnection()
        writer.write(codec.send(GotoMessage.from_degrees(zone.ra_j2000_hours, zone.dec_j2000_deg)))
        await writer.drain()
        await reader.read(100)  # a position report: the goto has been handled
        for _ in range(50):
            if "Sun avoidance zone" in caplog.text:
                break
            await asyncio.sleep(0.05)
        writer.close()
        await writer.wait_closed()
        assert rig.gotos_received() == []
    assert "refused" in caplog.text
    assert "Sun avoidance zone" in caplog.text


async def test_synscan_server_gotos_to_the_sun_are_acknowledged_ignored_and_logged(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING, logger="scopelink")  # scopelink serve's default level
    async with sun_rig() as rig, SynScanEmulator(rig.mount, wire=None) as server:
        host, port = await server.on_tcp("127.0.0.1", 0)
        link = TcpLink(*await asyncio.open_connection(host, port), name="phone app")
        client = SynScanClientConnection()
        zone = sun_now(rig)
        for precise in (True, False):
            goto = GotoRaDec.from_hours_degrees(zone.ra_j2000_hours, zone.dec_j2000_deg, precise)
            assert isinstance(await ask(link, client, goto), Ack)
            goto_altaz = GotoAzAlt.from_degrees(zone.az_deg, zone.alt_deg, precise)
            assert isinstance(await ask(link, client, goto_altaz), Ack)
        await link.close()
        assert rig.gotos_received() == []
    assert "Sun avoidance zone" in caplog.text


async def test_dashboard_goto_the_sun_is_409_with_the_reason() -> None:
    from scopelink.web import Dashboard

    async with (
        sun_rig() as rig,
        Dashboard(rig.mount, port=0) as dashboard,
        aiohttp.ClientSession(base_url=dashboard.url) as http,
    ):
        zone = sun_now(rig)
        for body in (
            {"name": "Sun"},
            {"ra_hours": zone.ra_j2000_hours, "dec_deg": zone.dec_j2000_deg},
            {"alt_deg": zone.alt_deg, "az_deg": zone.az_deg},
        ):
            async with http.post("/api/goto", json=body) as response:
                assert response.status == 409, await response.text()
                assert "Sun avoidance zone" in (await response.json())["error"]
        assert rig.gotos_received() == []


async def test_guard_stops_a_rate_motion_before_the_zone(tmp_path: Path) -> None:
    """Alpaca MoveAxis at 3°/s along the Sun's altitude towards it: stopped outside the zone
    (the device itself would carry on into the Sun)."""
    async with sun_rig(model=AZ_GTI, at=(62.0, 130.0)) as rig:
        server = AlpacaServer(
            rig.mount, host="127.0.0.1", port=0, discovery_port=None, state_dir=tmp_path
        )
        closest = math.inf
        async with server:
            telescope = Telescope(f"127.0.0.1:{server.port}", 0)
            await asyncio.to_thread(setattr, telescope, "Connected", True)
            await asyncio.to_thread(telescope.MoveAxis, TelescopeAxes.axisPrimary, 3.0)
            loop = asyncio.get_running_loop()
            deadline = loop.time() + 30.0
            still = 0
            last = rig.sim.observed_at(rig.sim.elapsed())
            while loop.time() < deadline and still < 5:
                await asyncio.sleep(0.02)
                alt, az = rig.sim.observed_at(rig.sim.elapsed())
                closest = min(closest, sun_now(rig).distance_deg(alt, az))
                still = still + 1 if abs(az - last[1]) < 0.001 else 0
                last = (alt, az)
        assert rig.mount.guard.stops >= 1
        assert closest >= RADIUS_DEG, closest
        assert any("Sun avoidance zone" in p for p in rig.mount.state.problems)
        with contextlib.suppress(Exception):
            await rig.mount.abort()
