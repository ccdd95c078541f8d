"""``/api/track`` under the dashboard's access policy and hostile bodies (issue #16,
docs/tracking.md "Tried to break it"): nothing starts following unless the request may command
the mount, and a bad body changes nothing. A real dashboard over HTTP, the simulator behind it."""

from __future__ import annotations

import aiohttp

from scopelink.astro.targets import solar_system_target
from scopelink.sim import EQ6, SimClock, SimulatedMount
from scopelink.web import Dashboard
from tests.support.targets import site_under
from tests.support.web import START


async def test_unpaired_foreign_or_malformed_requests_start_nothing() -> None:
    site = site_under(*solar_system_target("Moon", None).position(START), START)
    mount = SimulatedMount(EQ6, site=site, clock=SimClock.stepped(START))
    await mount.connect()
    try:
        async with (
            Dashboard(
                mount, port=0, pairing_token="s3cret", pairing_exempts_loopback=False
            ) as dashboard,
            aiohttp.ClientSession(base_url=dashboard.url) as http,
        ):
            moon = {"target": "moon"}
            async with http.post("/api/track", json=moon) as response:
                assert (response.status, (await response.json())["kind"]) == (401, "NotPaired")
            paired = {"X-Scopelink-Pairing": "s3cret"}
            foreign = {**paired, "Origin": "http://evil.example"}
            async with http.post("/api/track", json=moon, headers=foreign) as response:
                assert response.status == 403
            for body in (b"[1]", b'"moon"', b'{"target": ["moon"]}', b'{"target": "' + b"m" * 5000):
                async with http.post(
                    "/api/track",
                    data=body,
                    headers={**paired, "Content-Type": "application/json"},
                ) as response:
                    assert response.status in (400, 413), body[:20]
            async with http.get("/api/track") as response:
                assert (await response.json())["target"] is None  # reads stay open
            assert mount.target is None
            assert mount.tracking_rates.zero
    finally:
        await mount.disconnect()
