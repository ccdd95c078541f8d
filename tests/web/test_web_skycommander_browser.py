"""The dashboard's push-to and Sky Commander memory panel in headless Chromium: push-to figures
shown live for a simulated mount; on a Sky Commander, a name stored from the page lands in the
emulated EEPROM and is listed, and "clear" writes the pole over it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from playwright.async_api import Browser, expect

from scopelink.servers.skytracker.objects import StoredObject
from tests.support.browser import TIMEOUT_MS, open_page, screenshot
from tests.support.skycommander_web import panel
from tests.support.web import HIGH_UP, served

pytestmark = pytest.mark.asyncio(loop_scope="module")


async def test_push_to_figures_show_live_and_the_memory_hides_without_a_sky_commander(
    browser: Browser,
) -> None:
    async with served() as s, open_page(browser, s) as page:
        await page.fill("#pushto-name", HIGH_UP)
        await page.click("#pushto-form button[type=submit]")
        figures = page.locator("#pushto-figures")
        await expect(figures).to_contain_text(f"{HIGH_UP}: ", timeout=TIMEOUT_MS)
        await expect(figures).to_contain_text("° away", timeout=TIMEOUT_MS)
        await expect(page.locator("#skycommander-memory")).to_be_hidden()
        await page.click("#pushto-stop")
        await expect(figures).to_have_text("—")


async def test_store_a_name_from_the_page_and_clear_it(
    browser: Browser, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    async with panel(tmp_path, monkeypatch) as p, open_page(browser, p.served) as page:
        await expect(page.locator("#skycommander-memory")).to_be_visible(timeout=TIMEOUT_MS)
        # No motors: no pad, and the push-to view comes first, in big figures per axis.
        await expect(page.locator("body")).to_have_attribute("data-motors", "false")
        await expect(page.locator("#pad")).to_be_hidden()
        await page.fill("#pushto-name", "Vega")
        await page.click("#pushto-form button[type=submit]")
        await expect(page.locator("#pushto-view")).to_be_visible(timeout=TIMEOUT_MS)
        await expect(page.locator("#pushto-vertical")).to_have_text(re.compile(r"^(up|down) \d"))
        await expect(page.locator("#pushto-horizontal")).to_have_text(
            re.compile(r"^(left|right) \d")
        )
        await screenshot(page, "panel-05-skycommander-pushto")
        await page.fill("#slot-name", "M 57")
        await page.fill("#slot-number", "7")
        await page.click("#slot-form button[type=submit]")
        row = page.locator("#slots tbody tr")
        await expect(row).to_have_count(1, timeout=TIMEOUT_MS)
        await expect(row.first).to_contain_text("07")
        await expect(row.first).to_contain_text("M 57")
        assert p.emulator.commander.store.get(7) == StoredObject(18.893, 33.029)
        await row.first.locator("button").click()
        await expect(row).to_have_count(0, timeout=TIMEOUT_MS)
        assert p.emulator.commander.store.get(7) == StoredObject(0.0, 90.0)
