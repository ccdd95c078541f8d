"""A real dashboard in front of the Sky Commander driver on the Sky Commander emulator (TCP),
for the dashboard's Sky Commander panel tests (API and browser)."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import aiohttp
import pytest

from scopelink.astro import Site
from scopelink.drivers.skytracker import SkyCommanderMount
from scopelink.mount import MountAxis
from scopelink.servers.skytracker import SkyCommanderEmulator
from scopelink.sim import SKY_TRACKER, SimClock, SimulatedMount
from scopelink.web import Dashboard
from tests.support.web import Served

SITE = Site(latitude_deg=48.0, longitude_deg=11.0)


@dataclass
class Panel:
    emulator: SkyCommanderEmulator
    http: aiohttp.ClientSession
    served: Served
    """The same dashboard as :mod:`tests.support.browser` opens it (``mount`` is the simulated
    mount whose axes the Sky Commander reads)."""

    async def post(self, path: str, body: object) -> tuple[int, dict[str, Any]]:
        async with self.http.post(path, json=body) as response:
            return response.status, await response.json()

    async def get(self, path: str, **params: str) -> tuple[int, dict[str, Any]]:
        async with self.http.get(path, params=params) as response:
            return response.status, await response.json()


@asynccontextmanager
async def panel(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> AsyncIterator[Panel]:
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))  # the mirror's directory
    sim = SimulatedMount(SKY_TRACKER, site=SITE, clock=SimClock())
    sim.set_axis_position(MountAxis.PRIMARY, 200.0)
    sim.set_axis_position(MountAxis.SECONDARY, 30.0)
    async with SkyCommanderEmulator(sim, tmp_path / "eeprom") as emulator:
        host, port = await emulator.on_tcp()
        mount = SkyCommanderMount(f"tcp://{host}:{port}", site=SITE, clock=sim.clock.now)
        await mount.connect()
        try:
            async with (
                Dashboard(mount, port=0, update_interval_s=0.1, trace=False) as dashboard,
                aiohttp.ClientSession(base_url=dashboard.url) as http,
            ):
                yield Panel(emulator, http, Served(sim, dashboard, http))
        finally:
            await mount.disconnect()
