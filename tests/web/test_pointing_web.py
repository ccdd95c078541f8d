"""The dashboard's pointing API and panel (docs/pointing.md): syncs through the dashboard are
kept on the PC and listed with residuals; remove and clear, over HTTP and in headless Chromium."""

from __future__ import annotations

import pytest
from playwright.async_api import Browser, expect

from scopelink.astro import observed_to_j2000
from tests.support.browser import TIMEOUT_MS, open_page, screenshot
from tests.support.web import Served, served, sim_mount

pytestmark = pytest.mark.asyncio(loop_scope="module")


async def sync_twice(s: Served) -> None:
    """Two syncs, 1° from the readings, at two places of the sky (through POST /api/sync)."""
    s.mount.syncs_on_device = False  # as the SynScan driver
    for alt, az in ((40.0, 200.0), (55.0, 100.0)):
        await s.mount.goto_horizontal(alt, az)
        await s.mount.wait_for_slew(timeout_s=30.0)
        ra, dec = observed_to_j2000(alt + 1.0, az, s.mount.now(), s.mount.site)
        status, body = await s.post("/api/sync", {"ra_hours": ra, "dec_deg": dec})
        assert status == 200, body


async def test_the_pointing_api_lists_removes_and_clears() -> None:
    async with served(sim_mount(rate=60.0)) as s:
        status, empty = await s.get("/api/pointing")
        assert status == 200
        assert empty["syncs"] == []
        assert empty["active"] is False
        await sync_twice(s)
        status, model = await s.get("/api/pointing")
        assert [sync["number"] for sync in model["syncs"]] == [1, 2]
        assert model["fitted"] == ["IH", "ID", "MA", "ME"]  # two syncs: a turn and ID
        assert model["rms_arcmin"] < 60.0
        status, body = await s.post("/api/pointing", {"remove": 3})
        assert status == 400
        assert "there is no sync 3" in body["error"]
        status, body = await s.post("/api/pointing", {"nothing": 1})
        assert status == 400
        status, body = await s.post("/api/pointing", {"remove": 1.5})
        assert status == 400
        assert "not 1.5" in body["error"]
        status, model = await s.post("/api/pointing", {"remove": 1})
        assert status == 200
        assert len(model["syncs"]) == 1
        status, model = await s.post("/api/pointing", {"clear": True})
        assert model["syncs"] == []
        assert not s.mount.pointing.active


async def test_the_pointing_panel_shows_the_syncs_and_removes_one(browser: Browser) -> None:
    async with served(sim_mount(rate=60.0)) as s:
        await sync_twice(s)
        async with open_page(browser, s) as page:
            summary = page.locator("#pointing-summary")
            await expect(summary).to_contain_text("2 sync(s) kept on the PC", timeout=TIMEOUT_MS)
            await expect(summary).to_contain_text("IH")
            await expect(page.locator("#pointing-syncs tbody tr")).to_have_count(2)
            await screenshot(page, "pointing-panel")
            await page.click("button[aria-label='Remove sync 1']")
            await expect(summary).to_contain_text("1 sync(s) kept on the PC", timeout=TIMEOUT_MS)
            await page.click("#pointing-clear")
            await expect(summary).to_have_text("no syncs kept on the PC", timeout=TIMEOUT_MS)
        assert not s.mount.pointing.active
