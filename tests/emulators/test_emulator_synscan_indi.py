"""A real third-party client: INDI's ``indi_synscan_telescope`` drives our emulator.

The driver runs on its own pipes (no indiserver, nothing listens on the network) and connects to
the emulator over a pty, or over TCP on 127.0.0.1. What INDI reports must match the simulator.
INDI shows JNow: it precesses the hand control's J2000 with libnova to the PC's clock, so the
comparisons go through our mean-of-date conversion at the PC's time (a few arcsec apart).
"""

from __future__ import annotations

import asyncio
import re
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime
from pathlib import Path

import pytest

from scopelink.astro import (
    Site,
    angular_separation_deg,
    j2000_to_mean_of_date,
    observed_to_j2000,
)
from scopelink.mount import TrackingMode
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.indi import IndiDriver, IndiProperty
from tests.support.programs import require_executable

DRIVER = "indi_synscan_telescope"
SITE = Site(40.4, 3.7)  # east longitude: INDI 1.9 sends the E/W flag of W in the wrong byte
TOLERANCE_DEG = 0.01


def is_ok(prop: IndiProperty) -> bool:
    return prop.state == "Ok"


@asynccontextmanager
async def connected(
    transport: str, home: Path
) -> AsyncIterator[tuple[IndiDriver, SimulatedMount, SynScanEmulator]]:
    require_executable(DRIVER)
    # INDI reads `h` until '#': minute or second 35 would desync it over TCP (docs/emulators.md),
    # so connect at real-time rate from minute 10 and only then speed the clock up.
    start = datetime.now(UTC).replace(minute=10, second=0, microsecond=0)
    clock = SimClock(start=start, rate=1.0)
    mount = SimulatedMount(EQ6, site=SITE, clock=clock)
    async with (
        SynScanEmulator(mount) as emulator,
        IndiDriver.start(DRIVER, home=home, device="SynScan") as driver,
    ):
        await driver.get_properties()
        await driver.wait_for("CONNECTION_MODE")
        await driver.wait_for("DEVICE_AUTO_SEARCH")
        if transport == "pty":
            path = await emulator.on_pty()
            await driver.set_switch(
                "DEVICE_AUTO_SEARCH", {"INDI_ENABLED": False, "INDI_DISABLED": True}
            )
            await driver.set_text("DEVICE_PORT", {"PORT": path})
        else:
            host, port = await emulator.on_tcp()
            await driver.set_switch(
                "CONNECTION_MODE", {"CONNECTION_SERIAL": False, "CONNECTION_TCP": True}
            )
            await driver.wait_for("DEVICE_ADDRESS")
            await driver.set_text("DEVICE_ADDRESS", {"ADDRESS": host, "PORT": str(port)})
        await driver.set_switch("CONNECTION", {"CONNECT": True, "DISCONNECT": False})
        await driver.wait_for("CONNECTION", lambda p: p.switch("CONNECT") and is_ok(p))
        time_read = await driver.wait_for("TIME_UTC", is_ok)
        # INDI's own float round trip may show 10:00 as 09:59: compare within a minute.
        # (INDI does not zero-pad the day and hour: "2026-11-2T9:10:00".)
        year, month, day, hour, minute, second = (
            int(part) for part in re.split(r"[-T:]", time_read.text("UTC"))
        )
        read = datetime(year, month, day, hour, minute, second, tzinfo=UTC)
        assert abs((read - start).total_seconds()) < 60, time_read
        clock.set_rate(20.0)
        await driver.set_number("POLLING_PERIOD", {"PERIOD_MS": 250})
        yield driver, mount, emulator


def jnow_of_mount(mount: SimulatedMount) -> tuple[float, float]:
    state = mount.snapshot()
    assert state.ra_j2000_hours is not None
    assert state.dec_j2000_deg is not None
    return j2000_to_mean_of_date(state.ra_j2000_hours, state.dec_j2000_deg, datetime.now(UTC))


def tracking(mount: SimulatedMount) -> TrackingMode:
    return mount.tracking


def separation(a: tuple[float, float], b: tuple[float, float]) -> float:
    return angular_separation_deg(a[0] * 15, a[1], b[0] * 15, b[1])


def _now() -> float:
    return time.monotonic()


@pytest.mark.parametrize("transport", ["pty", "tcp"])
async def test_indi_connects_and_reads_coordinates(transport: str, tmp_path: Path) -> None:
    async with connected(transport, tmp_path) as (driver, mount, _):
        coords = await driver.wait_for("EQUATORIAL_EOD_COORD", lambda p: p.number("DEC") != 0)
        reported = coords.number("RA"), coords.number("DEC")
        assert separation(reported, jnow_of_mount(mount)) < TOLERANCE_DEG
        status = await driver.wait_for("MOUNT_STATUS")
        assert status.text("MI_MOUNT_MODEL") == "EQ6 GOTO Series"
        location = await driver.wait_for("GEOGRAPHIC_COORD")
        assert location.number("LAT") == pytest.approx(SITE.latitude_deg, abs=1e-3)
        assert location.number("LONG") == pytest.approx(SITE.longitude_deg, abs=1e-3)


@pytest.mark.parametrize("transport", ["pty", "tcp"])
async def test_indi_goto_sync_abort_motion_tracking_time_and_site(
    transport: str, tmp_path: Path
) -> None:
    async with connected(transport, tmp_path) as (driver, mount, emulator):
        # goto a point 60° up in the south, given in JNow as INDI clients do
        now = mount.now()
        ra, dec = observed_to_j2000(60.0, 180.0, now, mount.site)
        target = j2000_to_mean_of_date(ra, dec, datetime.now(UTC))
        await driver.set_switch("ON_COORD_SET", {"TRACK": True, "SLEW": False, "SYNC": False})
        await driver.set_number("EQUATORIAL_EOD_COORD", {"RA": target[0], "DEC": target[1]})
        await driver.wait_for("EQUATORIAL_EOD_COORD", lambda p: p.state == "Busy", seconds=5)
        coords = await driver.wait_for("EQUATORIAL_EOD_COORD", is_ok, seconds=20)
        assert separation((coords.number("RA"), coords.number("DEC")), target) < TOLERANCE_DEG
        assert tracking(mount) is TrackingMode.SIDEREAL
        assert separation(jnow_of_mount(mount), target) < TOLERANCE_DEG

        # sync half a degree north
        synced = (target[0], target[1] + 0.5)
        await driver.set_switch("ON_COORD_SET", {"TRACK": False, "SLEW": False, "SYNC": True})
        await driver.set_number("EQUATORIAL_EOD_COORD", {"RA": synced[0], "DEC": synced[1]})
        await driver.wait_for("EQUATORIAL_EOD_COORD", is_ok, after=_now())
        assert separation(jnow_of_mount(mount), synced) < TOLERANCE_DEG

        # motion north at the driver's default (maximum) rate, then stop
        dec_before = jnow_of_mount(mount)[1]
        await driver.set_switch(
            "TELESCOPE_MOTION_NS", {"MOTION_NORTH": True, "MOTION_SOUTH": False}
        )
        await asyncio.sleep(0.3)
        await driver.set_switch(
            "TELESCOPE_MOTION_NS", {"MOTION_NORTH": False, "MOTION_SOUTH": False}
        )
        await asyncio.sleep(0.5)
        assert jnow_of_mount(mount)[1] > dec_before + 1.0

        # tracking off and on
        await driver.set_switch("TELESCOPE_TRACK_STATE", {"TRACK_ON": False, "TRACK_OFF": True})
        await driver.wait_for("TELESCOPE_TRACK_STATE", lambda p: p.switch("TRACK_OFF"))
        await asyncio.sleep(0.2)
        assert tracking(mount) is TrackingMode.OFF
        await driver.set_switch("TELESCOPE_TRACK_STATE", {"TRACK_ON": True, "TRACK_OFF": False})
        await driver.wait_for("TELESCOPE_TRACK_STATE", lambda p: p.switch("TRACK_ON"))
        await asyncio.sleep(0.2)
        assert tracking(mount) is TrackingMode.SIDEREAL

        # abort a long goto: INDI stops tracking and cancels twice
        far = j2000_to_mean_of_date(
            *observed_to_j2000(30.0, 90.0, mount.now(), mount.site), datetime.now(UTC)
        )
        await driver.set_switch("ON_COORD_SET", {"TRACK": True, "SLEW": False, "SYNC": False})
        await driver.set_number("EQUATORIAL_EOD_COORD", {"RA": far[0], "DEC": far[1]})
        await driver.wait_for("EQUATORIAL_EOD_COORD", lambda p: p.state == "Busy", seconds=5)
        await driver.set_switch("TELESCOPE_ABORT_MOTION", {"ABORT": True})
        await driver.wait_for("TELESCOPE_ABORT_MOTION", is_ok)
        await asyncio.sleep(0.5)
        assert not mount.snapshot().slewing
        assert tracking(mount) is TrackingMode.OFF
        assert separation(jnow_of_mount(mount), far) > 5.0

        # time and site
        await driver.set_text("TIME_UTC", {"UTC": "2026-05-04T03:02:01", "OFFSET": "2"})
        await driver.wait_for("TIME_UTC", is_ok, after=_now())
        await asyncio.sleep(0.3)
        clock = emulator.hand_control.now()
        assert abs((clock - datetime(2026, 5, 4, 3, 2, 1, tzinfo=UTC)).total_seconds()) < 30
        await driver.set_number("GEOGRAPHIC_COORD", {"LAT": 28.75, "LONG": 17.9, "ELEV": 2400})
        await driver.wait_for("GEOGRAPHIC_COORD", is_ok, after=_now())
        await asyncio.sleep(0.3)
        assert mount.site.latitude_deg == pytest.approx(28.75, abs=1e-3)
        assert mount.site.longitude_deg == pytest.approx(17.9, abs=1e-3)
