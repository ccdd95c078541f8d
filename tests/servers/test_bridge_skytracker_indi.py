"""A bridge nobody else has: INDI's own ``indi_synscan_telescope`` drives a Sky Tracker.

The chain is all real code: the Sky Tracker + Sky Commander emulator (on TCP) <- our Sky Tracker
driver <- our SynScan server over that driver (on a pty) <- INDI's SynScan driver binary, spoken
to with INDI XML on its pipes (nothing listens on the network). The Sky Tracker is an alt-az box
that only goes to RA/Dec, so the SynScan server reports an AZ-GTi. INDI 1.9.9 sends RA/Dec gotos
(``r``) even then; clients that send alt-az gotos (``b``) get an RA/Dec GOTO to the same place on
the sky (checked with our own client below).
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime
from pathlib import Path

from scopelink.astro import (
    Site,
    angular_separation_deg,
    j2000_to_mean_of_date,
    observed_to_j2000,
)
from scopelink.drivers.skytracker import SkyTrackerMount
from scopelink.links import open_serial
from scopelink.mount import MountAxis
from scopelink.protocol.synscan import (
    GotoAzAlt,
    GotoInProgress,
    IsGotoInProgress,
    SynScanClientConnection,
)
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import SKY_TRACKER, SimClock, SimulatedMount
from tests.support.indi import IndiDriver, IndiProperty
from tests.support.programs import require_executable
from tests.support.synscan import ask

DRIVER = "indi_synscan_telescope"
SITE = Site(48.0, 11.0)
TOLERANCE_DEG = 0.05
"""The Sky Commander rounds RA/Dec to 0.001 h / 0.001°; INDI precesses with libnova."""


def separation(a: tuple[float, float], b: tuple[float, float]) -> float:
    return angular_separation_deg(a[0] * 15, a[1], b[0] * 15, b[1])


def is_ok(prop: IndiProperty) -> bool:
    return prop.state == "Ok"


@asynccontextmanager
async def sky_tracker_bridge(
    data_dir: Path,
) -> AsyncIterator[tuple[SimulatedMount, SynScanEmulator]]:
    """The emulated Sky Tracker (on TCP, in real time: INDI converts its targets with the PC's
    clock) <- our Sky Tracker driver <- our SynScan server over it, not yet on any link."""
    sim = SimulatedMount(SKY_TRACKER, site=SITE, clock=SimClock(start=datetime.now(UTC), rate=1.0))
    sim.set_axis_position(MountAxis.PRIMARY, 150.0)  # near the target: a short real-time GOTO
    sim.set_axis_position(MountAxis.SECONDARY, 40.0)
    async with SkyTrackerEmulator(sim, data_dir / "commander") as box:
        host, port = await box.on_tcp()
        tracker = SkyTrackerMount(f"tcp://{host}:{port}", site=SITE, clock=sim.clock.now)
        await tracker.connect()
        try:
            async with (
                tracker.watching(),
                SynScanEmulator(tracker, SynScanConfig(model=165), wire=None) as bridge,
            ):
                yield sim, bridge
        finally:
            await tracker.disconnect()


async def test_indi_reads_and_slews_a_sky_tracker_through_the_synscan_server(
    tmp_path: Path,
) -> None:
    require_executable(DRIVER)
    async with (
        sky_tracker_bridge(tmp_path) as (sim, bridge),
        IndiDriver.start(DRIVER, home=tmp_path, device="SynScan") as indi,
    ):
        path = await bridge.on_pty()
        await indi.get_properties()
        await indi.wait_for("DEVICE_AUTO_SEARCH")
        await indi.set_switch("DEVICE_AUTO_SEARCH", {"INDI_ENABLED": False, "INDI_DISABLED": True})
        await indi.set_text("DEVICE_PORT", {"PORT": path})
        await indi.set_switch("CONNECTION", {"CONNECT": True, "DISCONNECT": False})
        await indi.wait_for("CONNECTION", lambda p: p.switch("CONNECT") and is_ok(p), seconds=20)
        status = await indi.wait_for("MOUNT_STATUS")
        assert status.text("MI_MOUNT_MODEL") == "AZ-GTi GOTO Series"
        site = await indi.wait_for("GEOGRAPHIC_COORD")
        assert abs(site.number("LAT") - SITE.latitude_deg) < 1e-3

        # INDI shows where the Sky Tracker points (JNow)
        coords = await indi.wait_for(
            "EQUATORIAL_EOD_COORD", lambda p: p.number("DEC") != 0, seconds=20
        )
        here = j2000_to_mean_of_date(*sim.j2000_at(sim.elapsed()), datetime.now(UTC))
        shown = (coords.number("RA"), coords.number("DEC"))
        assert separation(shown, here) < TOLERANCE_DEG

        # and slews it: INDI's alt-az goto becomes the box's RA/Dec GOTO
        target_j2000 = observed_to_j2000(44.0, 154.0, sim.clock.now(), SITE)
        target = j2000_to_mean_of_date(*target_j2000, datetime.now(UTC))
        await indi.set_switch("ON_COORD_SET", {"TRACK": True, "SLEW": False, "SYNC": False})
        await indi.set_number("EQUATORIAL_EOD_COORD", {"RA": target[0], "DEC": target[1]})
        await indi.wait_for("EQUATORIAL_EOD_COORD", lambda p: p.state == "Busy", seconds=10)
        await indi.wait_for("EQUATORIAL_EOD_COORD", lambda p: p.state != "Busy", seconds=40)
        landed = sim.j2000_at(sim.elapsed())
        assert separation(landed, target_j2000) < TOLERANCE_DEG


async def test_an_alt_az_goto_reaches_a_sky_tracker_as_an_ra_dec_goto(tmp_path: Path) -> None:
    async with sky_tracker_bridge(tmp_path) as (sim, bridge):
        link = await open_serial(await bridge.on_pty())
        async with link:
            client = SynScanClientConnection()

            # that place on the sky when asked; the box then tracks it
            target = observed_to_j2000(44.0, 154.0, sim.clock.now(), SITE)
            await ask(link, client, GotoAzAlt.from_degrees(154.0, 44.0))
            async with asyncio.timeout(30):
                while True:
                    busy = await ask(link, client, IsGotoInProgress())
                    assert isinstance(busy, GotoInProgress)
                    if not busy.in_progress:
                        break
                    await asyncio.sleep(0.2)
    assert separation(sim.j2000_at(sim.elapsed()), target) < TOLERANCE_DEG
