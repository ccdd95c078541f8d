"""Real third-party clients: INDI's LX200 drivers drive the LX200 server over a pty and TCP.

``indi_lx200basic`` (goto, sync, abort) and ``indi_lx200generic`` (adds motion, site and time)
run on their own pipes; nothing listens beyond 127.0.0.1. LX200 speaks JNow and INDI shows it
unchanged, so the comparisons use the simulator's apparent place of date.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime
from pathlib import Path

import pytest

from scopelink.astro import (
    Site,
    angular_separation_deg,
    j2000_to_apparent,
    observed_to_j2000,
)
from scopelink.servers.lx200 import LX200Server
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.indi import IndiDriver, IndiProperty
from tests.support.programs import require_executable

SITE = Site(40.4, 3.7)
TOLERANCE_DEG = 0.01
BASIC = ("indi_lx200basic", "LX200 Basic")
GENERIC = ("indi_lx200generic", "LX200 Generic")


def is_ok(prop: IndiProperty) -> bool:
    return prop.state == "Ok"


@asynccontextmanager
async def connected(
    driver_and_device: tuple[str, str], transport: str, home: Path, rate: float = 20.0
) -> AsyncIterator[tuple[IndiDriver, SimulatedMount]]:
    binary, device = driver_and_device
    require_executable(binary)
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock(start=datetime.now(UTC), rate=rate))
    async with (
        LX200Server(mount) as server,
        IndiDriver.start(binary, home=home, device=device) as driver,
    ):
        await driver.get_properties()
        await driver.wait_for("CONNECTION_MODE")
        if transport == "pty":
            path = await server.on_pty()
            await driver.wait_for("DEVICE_PORT")
            if "DEVICE_AUTO_SEARCH" in driver.properties:
                await driver.set_switch(
                    "DEVICE_AUTO_SEARCH", {"INDI_ENABLED": False, "INDI_DISABLED": True}
                )
            await driver.set_text("DEVICE_PORT", {"PORT": path})
        else:
            host, port = await server.on_tcp(port=0)
            await driver.set_switch(
                "CONNECTION_MODE", {"CONNECTION_SERIAL": False, "CONNECTION_TCP": True}
            )
            await driver.wait_for("DEVICE_ADDRESS")
            await driver.set_text("DEVICE_ADDRESS", {"ADDRESS": host, "PORT": str(port)})
        await driver.set_switch("CONNECTION", {"CONNECT": True, "DISCONNECT": False})
        await driver.wait_for("CONNECTION", lambda p: p.switch("CONNECT") and is_ok(p))
        await driver.wait_for("EQUATORIAL_EOD_COORD")
        await driver.set_number("POLLING_PERIOD", {"PERIOD_MS": 250})
        yield driver, mount


def jnow_of(mount: SimulatedMount) -> tuple[float, float]:
    state = mount.snapshot()
    assert state.ra_of_date_hours is not None
    assert state.dec_of_date_deg is not None
    return state.ra_of_date_hours, state.dec_of_date_deg


def jnow_at(mount: SimulatedMount, alt_deg: float, az_deg: float) -> tuple[float, float]:
    now = mount.now()
    return j2000_to_apparent(*observed_to_j2000(alt_deg, az_deg, now, mount.site), now)


def separation(a: tuple[float, float], b: tuple[float, float]) -> float:
    return angular_separation_deg(a[0] * 15, a[1], b[0] * 15, b[1])


def reported(prop: IndiProperty) -> tuple[float, float]:
    return prop.number("RA"), prop.number("DEC")


async def reading_near(
    driver: IndiDriver, where: tuple[float, float], seconds: float = 20.0
) -> IndiProperty:
    return await driver.wait_for(
        "EQUATORIAL_EOD_COORD",
        lambda p: separation(reported(p), where) < TOLERANCE_DEG,
        seconds=seconds,
    )


@pytest.mark.parametrize("transport", ["pty", "tcp"])
async def test_lx200basic_reads_goes_to_syncs_and_aborts(transport: str, tmp_path: Path) -> None:
    async with connected(BASIC, transport, tmp_path) as (driver, mount):
        # the coordinates INDI shows are the simulator's JNow
        coords = await driver.wait_for("EQUATORIAL_EOD_COORD", lambda p: p.number("DEC") != 0)
        assert separation(reported(coords), jnow_of(mount)) < TOLERANCE_DEG

        # goto, given in JNow as INDI clients do
        target = jnow_at(mount, 60.0, 180.0)
        await driver.set_switch("ON_COORD_SET", {"TRACK": True, "SLEW": False, "SYNC": False})
        await driver.set_number("EQUATORIAL_EOD_COORD", {"RA": target[0], "DEC": target[1]})
        await reading_near(driver, target)
        await mount.wait_for(lambda s: not s.slewing, timeout_s=20)
        assert separation(jnow_of(mount), target) < TOLERANCE_DEG

        # sync half a degree north
        synced = (target[0], target[1] + 0.5)
        await driver.set_switch("ON_COORD_SET", {"TRACK": False, "SLEW": False, "SYNC": True})
        await driver.set_number("EQUATORIAL_EOD_COORD", {"RA": synced[0], "DEC": synced[1]})
        await driver.wait_for_message("Synchronization successful")
        assert separation(jnow_of(mount), synced) < TOLERANCE_DEG

        # abort a long goto
        far = jnow_at(mount, 30.0, 90.0)
        await driver.set_switch("ON_COORD_SET", {"TRACK": True, "SLEW": False, "SYNC": False})
        await driver.set_number("EQUATORIAL_EOD_COORD", {"RA": far[0], "DEC": far[1]})
        await mount.wait_for(lambda s: s.slewing, timeout_s=5)
        await driver.set_switch("TELESCOPE_ABORT_MOTION", {"ABORT": True})
        await driver.wait_for("TELESCOPE_ABORT_MOTION", is_ok)
        await mount.wait_for(lambda s: not s.slewing, timeout_s=5)
        assert separation(jnow_of(mount), far) > 5.0


async def test_lx200basic_goto_below_the_horizon_is_refused(tmp_path: Path) -> None:
    # Over a pty: INDI reads the refusal's first byte and flushes the rest of it (on a TCP
    # socket its flush does nothing, and the leftover text would shift every later reply).
    async with connected(BASIC, "pty", tmp_path) as (driver, mount):
        before = jnow_of(mount)
        below = jnow_at(mount, -20.0, 0.0)
        await driver.set_switch("ON_COORD_SET", {"TRACK": True, "SLEW": False, "SYNC": False})
        started = time.monotonic()
        await driver.set_number("EQUATORIAL_EOD_COORD", {"RA": below[0], "DEC": below[1]})
        await driver.wait_for(
            "EQUATORIAL_EOD_COORD", lambda p: p.state == "Alert", after=started, seconds=10
        )
        # The driver's message may come a moment after the property's Alert (seen under load).
        await driver.wait_for_message("below horizon", seconds=5.0)
        await asyncio.sleep(0.5)
        assert not mount.snapshot().slewing
        assert mount.target is None
        # still in step: the next readings are right
        coords = await driver.wait_for(
            "EQUATORIAL_EOD_COORD", lambda p: p.updated_at > time.monotonic() - 0.1
        )
        assert separation(reported(coords), jnow_of(mount)) < 0.1
        assert separation(jnow_of(mount), before) < 1.0


@pytest.mark.parametrize("transport", ["pty", "tcp"])
async def test_lx200generic_motion_site_and_time(transport: str, tmp_path: Path) -> None:
    async with connected(GENERIC, transport, tmp_path, rate=1.0) as (driver, mount):
        location = await driver.wait_for("GEOGRAPHIC_COORD", lambda p: p.number("LAT") != 0)
        assert location.number("LAT") == pytest.approx(SITE.latitude_deg, abs=0.02)
        assert location.number("LONG") == pytest.approx(SITE.longitude_deg, abs=0.02)

        # move south at the current (slew) rate, then stop
        mount.clock.set_rate(1.0)
        dec_before = jnow_of(mount)[1]
        await driver.set_switch(
            "TELESCOPE_MOTION_NS", {"MOTION_NORTH": False, "MOTION_SOUTH": True}
        )
        # From when the motion has reached the mount (the driver's command may take a while on
        # a loaded machine), not from when it was asked.
        await mount.wait_for(lambda s: s.slewing, timeout_s=5)
        await asyncio.sleep(0.6)
        await driver.set_switch(
            "TELESCOPE_MOTION_NS", {"MOTION_NORTH": False, "MOTION_SOUTH": False}
        )
        await mount.wait_for(lambda s: not s.slewing, timeout_s=5)
        moved = dec_before - jnow_of(mount)[1]
        assert moved > 0.5
        await asyncio.sleep(0.3)
        assert dec_before - jnow_of(mount)[1] == pytest.approx(moved, abs=0.01)

        # site and time from INDI
        await driver.set_number("GEOGRAPHIC_COORD", {"LAT": 28.75, "LONG": 342.1, "ELEV": 2400})
        await driver.wait_for("GEOGRAPHIC_COORD", is_ok, after=time.monotonic())
        await asyncio.sleep(0.3)
        assert mount.site.latitude_deg == pytest.approx(28.75, abs=0.02)
        assert mount.site.longitude_deg == pytest.approx(-17.9, abs=0.02)
        await driver.set_text("TIME_UTC", {"UTC": "2026-05-04T03:02:01", "OFFSET": "2"})
        await driver.wait_for("TIME_UTC", is_ok, after=time.monotonic())
        await asyncio.sleep(0.3)
        expected = datetime(2026, 5, 4, 3, 2, 1, tzinfo=UTC)
        assert abs((mount.now() - expected).total_seconds()) < 30
