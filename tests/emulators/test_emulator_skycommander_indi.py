"""INDI's own Sky Commander driver reads the emulated Sky Commander over a pty and over TCP."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

import pytest

from scopelink.servers.skytracker import SkyCommanderEmulator
from scopelink.sim import SimulatedMount
from tests.support.indi import IndiDriver
from tests.support.programs import require_executable
from tests.support.skytracker_emulator import sky_tracker_mount

DRIVER = "indi_skycommander_telescope"
TOLERANCE = 0.0015  # the wire's three decimals, and INDI's sexagesimal rounding


@asynccontextmanager
async def connected(transport: str, home: Path) -> AsyncIterator[tuple[IndiDriver, SimulatedMount]]:
    require_executable(DRIVER)
    mount = sky_tracker_mount()
    mount.axes[1].slew_to(35.0)  # point somewhere off the horizon
    mount.axes[0].slew_to(120.0)
    mount.clock.advance(120.0)
    async with (
        SkyCommanderEmulator(mount, home / "data") as emulator,
        IndiDriver.start(DRIVER, home=home) as driver,
    ):
        await driver.get_properties()
        await driver.wait_for("CONNECTION_MODE")
        if transport == "pty":
            path = await emulator.on_pty()
            await driver.wait_for("DEVICE_PORT")
            await driver.set_text("DEVICE_PORT", {"PORT": path})
        else:
            host, port = await emulator.on_tcp()
            await driver.set_switch(
                "CONNECTION_MODE", {"CONNECTION_SERIAL": False, "CONNECTION_TCP": True}
            )
            await driver.wait_for("DEVICE_ADDRESS")
            await driver.set_text("DEVICE_ADDRESS", {"ADDRESS": host, "PORT": str(port)})
        await driver.set_switch("CONNECTION", {"CONNECT": True, "DISCONNECT": False})
        await driver.wait_for("CONNECTION", lambda p: p.switch("CONNECT") and p.state == "Ok")
        yield driver, mount


@pytest.mark.parametrize("transport", ["pty", "tcp"])
async def test_indi_reads_the_coordinates_of_the_simulated_scope(
    transport: str, tmp_path: Path
) -> None:
    async with connected(transport, tmp_path) as (driver, mount):
        coords = await driver.wait_for(
            "EQUATORIAL_EOD_COORD", lambda p: p.number("DEC") != 0, seconds=10
        )
        ra, dec = mount.j2000_at(mount.clock.elapsed())
        assert coords.number("RA") == pytest.approx(ra, abs=TOLERANCE)
        assert coords.number("DEC") == pytest.approx(dec, abs=TOLERANCE)
