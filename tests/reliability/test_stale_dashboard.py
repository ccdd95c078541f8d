"""Issue #11 parts 5 and 6 on the dashboard, in headless Chromium: the reading's age is shown, a
stale position is marked as such, and while the link is down no motion state is claimed; all of
it clears by itself when the device answers again (the SynScan driver on TCP to the emulator)."""

from __future__ import annotations

import re
from datetime import UTC, datetime

from playwright.async_api import async_playwright, expect

from scopelink.astro import Site
from scopelink.drivers.synscan import SynScanMount
from scopelink.servers.faults import ANY, Fault, FaultKind
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from scopelink.web import Dashboard
from tests.support.programs import require_executable

SITE = Site(latitude_deg=48.0, longitude_deg=11.0)
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
TIMEOUT_MS = 10_000


async def test_the_dashboard_shows_the_age_and_claims_no_motion_while_the_link_is_down() -> None:
    executable = require_executable("chromium")
    sim = SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=1.0))
    await sim.connect()
    async with SynScanEmulator(sim, wire=None) as device:
        _, port = await device.on_tcp("127.0.0.1", 0)
        driver = SynScanMount(f"tcp://127.0.0.1:{port}", site=SITE, timeout_s=1.0)
        driver.stale_after_s = 1.0
        await driver.connect()
        try:
            async with (
                Dashboard(driver, port=0, update_interval_s=0.1) as dashboard,
                async_playwright() as playwright,
            ):
                browser = await playwright.chromium.launch(executable_path=executable)
                try:
                    page = await browser.new_page()
                    errors: list[str] = []
                    page.on("pageerror", lambda error: errors.append(str(error)))
                    await page.goto(dashboard.url)
                    age = page.locator("#hl-age")
                    await expect(page.locator("#hl-connected")).to_have_text("yes")
                    await expect(age).to_have_text(re.compile(r"^\d+\.\d s$"), timeout=TIMEOUT_MS)

                    device.faults.add(Fault(FaultKind.STALL, ANY))
                    await expect(age).to_contain_text("stale", timeout=TIMEOUT_MS)
                    await expect(page.locator("#st-altaz")).to_have_class(re.compile(r"\bstale\b"))
                    await expect(page.locator("#hl-connected")).to_have_text(
                        "no", timeout=TIMEOUT_MS
                    )
                    await expect(page.locator("#st-slewing")).to_have_text("unknown (link down)")

                    device.faults.clear()
                    await expect(page.locator("#hl-connected")).to_have_text(
                        "yes", timeout=TIMEOUT_MS
                    )
                    await expect(age).not_to_contain_text("stale", timeout=TIMEOUT_MS)
                    await expect(page.locator("#st-slewing")).to_have_text("no")
                    assert errors == []
                finally:
                    await browser.close()
        finally:
            await driver.disconnect()
