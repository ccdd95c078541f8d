"""Shared rig for the dashboard tests: a simulated mount on an accelerated clock behind a real
dashboard on 127.0.0.1:0, and an aiohttp client for it."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

import aiohttp

from scopelink.astro import Site
from scopelink.mount import Limits
from scopelink.sim import EQ6, SimClock, SimulatedMount
from scopelink.web import Dashboard
from scopelink.web.site_check import SiteStore

SITE = Site(latitude_deg=45.0, longitude_deg=7.0, elevation_m=300.0)
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)  # Capella high in the west, Acrux never up
NEVER_UP = "Acrux"
HIGH_UP = "Capella"


def sim_mount(rate: float = 30.0, limits: Limits | None = None) -> SimulatedMount:
    return SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=rate), limits=limits)


@dataclass
class Served:
    mount: SimulatedMount
    dashboard: Dashboard
    http: aiohttp.ClientSession

    async def post(self, path: str, body: object = None) -> tuple[int, dict[str, Any]]:
        async with self.http.post(path, json=body if body is not None else {}) as response:
            return response.status, await response.json()

    async def get(self, path: str, **params: str) -> tuple[int, dict[str, Any]]:
        async with self.http.get(path, params=params) as response:
            return response.status, await response.json()


@asynccontextmanager
async def served(
    mount: SimulatedMount | None = None,
    *,
    interval_s: float = 0.1,
    connect: bool = True,
    site_store: SiteStore | None = None,
) -> AsyncIterator[Served]:
    mount = mount or sim_mount()
    if connect:
        await mount.connect()
    try:
        async with (
            Dashboard(
                mount, port=0, update_interval_s=interval_s, site_store=site_store
            ) as dashboard,
            aiohttp.ClientSession(base_url=dashboard.url) as http,
        ):
            yield Served(mount, dashboard, http)
    finally:
        await mount.disconnect()
