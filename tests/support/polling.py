"""Rig for the polling tests: each driver against its emulator on TCP with no wire pacing."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime
from pathlib import Path

from scopelink.astro import Site
from scopelink.drivers.skytracker import SkyTrackerMount
from scopelink.drivers.synscan import SynScanMount
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.skytracker_driver import sky_tracker_mount

SITE = Site(latitude_deg=48.0, longitude_deg=11.0)

START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)

LINE_BYTES_PER_S = 9600 / 10
"""What a 9600-baud 8N1 line carries each way: the default maximum."""


@asynccontextmanager
async def synscan_driver() -> AsyncIterator[SynScanMount]:
    """The SynScan driver against the emulator with no wire pacing (an instant device)."""
    sim = SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=1.0))
    await sim.connect()
    async with SynScanEmulator(sim, wire=None) as emulator:
        _, port = await emulator.on_tcp("127.0.0.1", 0)
        driver = SynScanMount(f"tcp://127.0.0.1:{port}", site=SITE, timeout_s=1.0)
        await driver.connect()
        try:
            yield driver
        finally:
            await driver.disconnect()


@asynccontextmanager
async def skytracker_driver(tmp_path: Path) -> AsyncIterator[SkyTrackerMount]:
    """The Sky Tracker driver against its emulator with no pacing on the emulator's side."""
    sim = sky_tracker_mount(rate=1.0)
    async with SkyTrackerEmulator(sim, tmp_path, pace=False) as emulator:
        _, port = await emulator.on_tcp()
        driver = SkyTrackerMount(f"tcp://127.0.0.1:{port}", site=SITE)
        await driver.connect()
        try:
            yield driver
        finally:
            await driver.disconnect()
