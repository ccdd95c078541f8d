"""The dashboard's JSON API over real HTTP, on a real simulated mount: every command goes
through the Mount's checked methods, and every refusal is a clear JSON error."""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime

import aiohttp
import pytest

from scopelink.mount import Limits, TrackingMode
from tests.support.web import HIGH_UP, NEVER_UP, SITE, served, sim_mount


async def test_page_and_static_files_are_served_with_protective_headers() -> None:
    async with served() as s:
        async with s.http.get("/") as response:
            assert response.status == 200
            page = await response.text()
            assert '<canvas id="sky"' in page
            csp = response.headers["Content-Security-Policy"]
            assert "script-src 'self'" in csp
            assert "frame-ancestors 'none'" in csp
            assert response.headers["X-Frame-Options"] == "DENY"
            assert response.headers["X-Content-Type-Options"] == "nosniff"
        for name, kind in [("app.js", "javascript"), ("style.css", "text/css")]:
            async with s.http.get(f"/static/{name}") as response:
                assert response.status == 200
                assert kind in response.headers["Content-Type"]


async def raw_get(port: int, path: str) -> tuple[int, bytes]:
    """A raw request: HTTP clients tidy ".." away before sending, attackers do not."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    writer.write(f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n".encode())
    await writer.drain()
    reply = await reader.read()
    writer.close()
    await writer.wait_closed()
    return int(reply.split(b" ", 2)[1]), reply


@pytest.mark.parametrize(
    "path",
    [
        "/static/../dashboard.py",
        "/static/%2e%2e/dashboard.py",
        "/static/..%2fdashboard.py",
        "/static/%2e%2e%2f%2e%2e%2f__init__.py",
        "/static//etc/passwd",
        "/static/../../../../etc/passwd",
    ],
)
async def test_static_files_never_leave_the_static_folder(path: str) -> None:
    async with served() as s:
        status, reply = await raw_get(s.dashboard.port, path)
        assert status in (400, 403, 404), reply[:200]
        assert b"import" not in reply
        assert b"root:" not in reply
        status, reply = await raw_get(s.dashboard.port, "/static/style.css")
        assert status == 200
        assert b"--bg" in reply


async def test_search_as_you_type_finds_names_best_first() -> None:
    async with served() as s:
        status, body = await s.get("/api/search", q="veg")
        assert status == 200
        assert body["matches"][0]["name"] == "Vega"
        status, body = await s.get("/api/search", q="jup")
        assert body["matches"][0]["name"] == "Jupiter"
        assert body["matches"][0]["kind"] == "planet"
        status, body = await s.get("/api/search", q="")
        assert (status, body["matches"]) == (200, [])
        status, body = await s.get("/api/search", q="M", limit="many")
        assert status == 400
        assert "limit" in body["error"]
        status, body = await s.get("/api/search", q="M", limit="500")
        assert status == 400


async def test_goto_by_name_starts_the_slew_and_sets_the_target() -> None:
    async with served() as s:
        status, body = await s.post("/api/goto", {"name": "capella"})
        assert status == 200, body
        assert body["object"]["name"] == HIGH_UP
        state = await s.mount.refresh()
        assert state.slewing
        assert s.mount.target is not None
        assert s.mount.target.name == HIGH_UP
        _, state_body = await s.get("/api/state")
        assert state_body["state"]["target"]["name"] == HIGH_UP
        assert state_body["state"]["slewing"] is True


async def test_goto_below_the_horizon_is_refused_and_nothing_moves() -> None:
    async with served() as s:
        before = await s.mount.refresh()
        status, body = await s.post("/api/goto", {"name": NEVER_UP})
        assert status == 409
        assert body["kind"] == "LimitError"
        assert "below the configured horizon" in body["error"]
        after = await s.mount.refresh()
        assert not after.slewing
        assert s.mount.target is None
        assert after.alt_deg == pytest.approx(before.alt_deg, abs=0.01)


async def test_goto_respects_a_raised_horizon_and_a_horizontal_target() -> None:
    mount = sim_mount(limits=Limits(horizon_deg=30.0))
    async with served(mount) as s:
        status, body = await s.post("/api/goto", {"alt_deg": 20.0, "az_deg": 180.0})
        assert status == 409
        assert "30.00°" in body["error"]
        status, body = await s.post("/api/goto", {"alt_deg": 50.0, "az_deg": 200.0})
        assert status == 200, body
        assert s.mount.target is not None
        assert s.mount.target.alt_deg == 50.0


async def test_unknown_names_get_a_404_with_suggestions() -> None:
    async with served() as s:
        status, body = await s.post("/api/goto", {"name": "Vegga"})
        assert status == 404
        assert body["kind"] == "UnknownObjectError"
        assert "Vega" in body["suggestions"]


@pytest.mark.parametrize(
    ("body", "words"),
    [
        ({}, "give 'name'"),
        ({"name": ""}, "must not be empty"),
        ({"name": 42}, "must be a string"),
        ({"name": "x" * 101}, "at most 100"),
        ({"ra_hours": 25.0, "dec_deg": 0.0}, "'ra_hours' must lie in"),
        ({"ra_hours": 1.0}, "'dec_deg' is required"),
        ({"ra_hours": "1", "dec_deg": 0.0}, "must be a number"),
        ({"ra_hours": True, "dec_deg": 0.0}, "must be a number"),
        ({"alt_deg": 95.0, "az_deg": 0.0}, "'alt_deg' must lie in"),
    ],
)
async def test_bad_goto_parameters_get_a_clear_400(body: dict[str, object], words: str) -> None:
    async with served() as s:
        status, reply = await s.post("/api/goto", body)
        assert status == 400
        assert words in reply["error"]
        assert not (await s.mount.refresh()).slewing


async def test_non_json_bodies_are_refused() -> None:
    async with served() as s:
        async with s.http.post("/api/goto", data="name=Vega") as response:
            assert response.status == 400
            assert "application/json" in (await response.json())["error"]
        for raw in (b"{not json", b"[1, 2]", b'"Vega"', b"x" * 5000):
            async with s.http.post(
                "/api/goto", data=raw, headers={"Content-Type": "application/json"}
            ) as response:
                assert response.status == 400, raw[:20]
        async with s.http.post(
            "/api/goto",
            data=b'{"ra_hours": NaN, "dec_deg": 0}',
            headers={"Content-Type": "application/json"},
        ) as response:
            assert response.status == 400
            assert "ra_hours" in (await response.json())["error"]
        assert not (await s.mount.refresh()).slewing


async def test_another_sites_page_cannot_command_the_mount() -> None:
    async with served() as s:
        for origin in ("http://evil.example", "null"):
            async with s.http.post(
                "/api/goto", json={"name": HIGH_UP}, headers={"Origin": origin}
            ) as response:
                assert response.status == 403
        assert not (await s.mount.refresh()).slewing
        same = s.dashboard.url.rstrip("/")
        async with s.http.post(
            "/api/goto", json={"name": HIGH_UP}, headers={"Origin": same}
        ) as response:
            assert response.status == 200


async def test_abort_stops_a_slew() -> None:
    async with served() as s:
        await s.post("/api/goto", {"name": HIGH_UP})
        assert (await s.mount.refresh()).slewing
        status, _ = await s.post("/api/abort")
        assert status == 200
        state = await s.mount.wait_for(lambda st: not st.slewing, timeout_s=10)
        assert not state.slewing


async def test_move_axis_runs_and_stops_within_the_rate_limit() -> None:
    async with served() as s:
        limit = s.mount.capabilities.max_axis_rate_deg_s
        status, body = await s.post("/api/move", {"axis": "primary", "rate_deg_s": limit * 2})
        assert status == 400
        assert "rate_deg_s" in body["error"]
        status, body = await s.post("/api/move", {"axis": "sideways", "rate_deg_s": 1.0})
        assert status == 400
        assert "primary" in body["error"]
        status, body = await s.post("/api/move", {"axis": "secondary", "rate_deg_s": 1.0})
        assert status == 200, body
        first = await s.mount.refresh()
        await asyncio.sleep(0.2)
        second = await s.mount.refresh()
        assert second.dec_j2000_deg != first.dec_j2000_deg
        status, _ = await s.post("/api/move", {"axis": "secondary", "rate_deg_s": 0})
        assert status == 200
        await asyncio.sleep(0.5)  # deceleration ramp at x30
        a = await s.mount.refresh()
        await asyncio.sleep(0.1)
        b = await s.mount.refresh()
        assert a.dec_j2000_deg == pytest.approx(b.dec_j2000_deg, abs=0.01)


async def test_tracking_park_and_unpark() -> None:
    async with served() as s:
        status, body = await s.post("/api/tracking", {"mode": "sidereal"})
        assert status == 200, body
        assert (await s.mount.refresh()).tracking is TrackingMode.SIDEREAL
        status, body = await s.post("/api/tracking", {"mode": "warp"})
        assert status == 400
        assert "sidereal" in body["error"]
        status, body = await s.post("/api/tracking", {"mode": "off"})
        assert (await s.mount.refresh()).tracking is TrackingMode.OFF
        status, body = await s.post("/api/park")
        assert status == 200, body
        await s.mount.wait_for(lambda st: st.parked, timeout_s=20)
        status, body = await s.post("/api/goto", {"name": HIGH_UP})
        assert status == 409
        assert body["kind"] == "ParkedError"
        status, body = await s.post("/api/unpark")
        assert status == 200
        assert not (await s.mount.refresh()).parked


async def test_sync_by_name_and_by_coordinates() -> None:
    async with served() as s:
        # Point near it first: a sync farther than limits.max_sync_deg is refused (issue #11).
        status, body = await s.post("/api/goto", {"name": HIGH_UP})
        assert status == 200, body
        await s.mount.wait_for_slew(timeout_s=30.0)
        status, body = await s.post("/api/sync", {"name": HIGH_UP})
        assert status == 200, body
        state = await s.mount.refresh()
        assert state.ra_j2000_hours == pytest.approx(5.278, abs=0.01)
        status, body = await s.post("/api/sync", {"ra_hours": 1.0, "dec_deg": 100.0})
        assert status == 400


async def test_site_and_time_are_pushed_to_the_mount() -> None:
    async with served() as s:
        status, body = await s.post(
            "/api/site", {"latitude_deg": -33.9, "longitude_deg": 18.4, "elevation_m": 10}
        )
        assert status == 200, body
        assert s.mount.site.latitude_deg == -33.9
        assert s.mount.site.temperature_c == SITE.temperature_c
        assert body["mount"]["site"]["longitude_deg"] == 18.4
        status, body = await s.post("/api/site", {"latitude_deg": 91, "longitude_deg": 0})
        assert status == 400
        assert s.mount.site.latitude_deg == -33.9
        status, body = await s.post("/api/time", {"utc": "2027-06-01T22:00:00Z"})
        assert status == 200, body
        assert abs((s.mount.now() - datetime(2027, 6, 1, 22, tzinfo=UTC)).total_seconds()) < 60
        status, body = await s.post("/api/time", {"utc": "2027-06-01T22:00:00"})
        assert status == 400
        assert "time zone" in body["error"]
        status, body = await s.post("/api/time", {"utc": "tomorrow"})
        assert status == 400


async def test_a_disconnected_mount_refuses_with_409() -> None:
    async with served(connect=False) as s:
        status, body = await s.post("/api/abort")
        assert status == 409
        assert body["kind"] == "NotConnectedError"


async def test_unknown_api_paths_and_methods() -> None:
    async with served() as s:
        async with s.http.get("/api/goto") as response:
            assert response.status == 405
        async with s.http.post("/api/nothing", json={}) as response:
            assert response.status == 404
        with pytest.raises(aiohttp.ClientResponseError):
            async with s.http.get("/nothing", raise_for_status=True):
                pass
