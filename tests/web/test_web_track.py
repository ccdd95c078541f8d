"""GET/POST /api/track on a real dashboard over HTTP, the simulator behind it (accelerated
clock): start following the Moon, its error and path, refusals, stop; read-only refuses."""

from __future__ import annotations

import asyncio

import aiohttp

from scopelink.astro.targets import solar_system_target
from scopelink.servers.access import AccessPolicy
from scopelink.sim import EQ6, SimClock, SimulatedMount
from scopelink.web import Dashboard
from tests.support.targets import site_under
from tests.support.web import START, served


async def test_follow_the_moon_from_the_dashboard_api() -> None:
    site = site_under(*solar_system_target("Moon", None).position(START), START)
    mount = SimulatedMount(EQ6, site=site, clock=SimClock(start=START, rate=50.0))
    async with served(mount) as s:
        assert await s.get("/api/track") == (
            200,
            {
                "target": None,
                "kind": None,
                "error_arcsec": None,
                "path": [],
                "phase": None,
                "ended": None,
            },
        )
        status, answer = await s.post("/api/track", {"target": "moon"})
        assert status == 200, answer
        assert (answer["target"], answer["kind"]) == ("Moon", "moon")
        for _ in range(100):
            status, track = await s.get("/api/track")
            if track["phase"] == "following" and track["error_arcsec"] is not None:
                break
            await asyncio.sleep(0.1)
        assert track["phase"] == "following", track
        assert 0.0 <= track["error_arcsec"] < 3600.0
        assert len(track["path"]) == 60
        ra, dec = solar_system_target("Moon", site).position(s.mount.now())
        assert abs(track["path"][0][0] - ra * 15.0) < 0.5
        assert abs(track["path"][0][1] - dec) < 0.5
        # Refused before anything changes: the Sun (avoidance on), an unknown body, a star.
        status, refused = await s.post("/api/track", {"target": "sun"})
        assert (status, refused["kind"]) == (409, "SunAvoidanceError")
        status, refused = await s.post("/api/track", {"target": "Vega"})
        assert status == 400
        assert "not a body of the solar system" in refused["error"]
        assert (await s.get("/api/track"))[1]["target"] == "Moon"  # still following
        status, stopped = await s.post("/api/track", {"target": None})
        assert status == 200
        assert stopped["target"] is None
        assert stopped["ended"] == "stopped"
        assert s.mount.tracking_rates.zero


async def test_a_read_only_dashboard_refuses_to_start_following() -> None:
    mount = SimulatedMount(EQ6, site=site_under(0.0, 0.0, START), clock=SimClock.stepped(START))
    await mount.connect()
    try:
        async with (
            Dashboard(mount, port=0, access=AccessPolicy(read_only=True)) as dashboard,
            aiohttp.ClientSession(base_url=dashboard.url) as http,
            http.post("/api/track", json={"target": "moon"}) as response,
        ):
            assert response.status == 403
            assert (await response.json())["kind"] == "ReadOnly"
    finally:
        await mount.disconnect()
