"""The dashboard and the Sun, in headless Chromium (the pattern of ``test_web_browser.py``): the
zone is drawn on the chart and a warning shows while the Sun is up; a goto to the Sun shows the
refusal; with the zone off the page says so in red.

The simulated mount's clock starts at 2026-06-21 12:00 UTC at 45° N 7° E: the Sun is up, about
67° high, in the south."""

from __future__ import annotations

import re
import statistics
from datetime import UTC, datetime

import pytest
from playwright.async_api import Browser, Page, expect

from scopelink.mount import Limits, TrackingMode
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.browser import TIMEOUT_MS, open_page, screenshot
from tests.support.web import SITE, served

pytestmark = pytest.mark.asyncio(loop_scope="module")

NOON = datetime(2026, 6, 21, 12, 0, tzinfo=UTC)


def noon_mount(radius: float = 15.0) -> SimulatedMount:
    return SimulatedMount(
        EQ6,
        site=SITE,
        clock=SimClock(start=NOON, rate=1.0),
        limits=Limits(sun_avoidance_deg=radius),
    )


async def redness(page: Page, alt: float, az: float) -> float:
    """The mean red minus blue of a 5x5 patch of the chart at (alt, az)."""
    return float(
        await page.evaluate(
            """([alt, az]) => {
                const [x, y] = Chart.debug.project(alt, az);
                const ratio = window.devicePixelRatio || 1;
                const data = Chart.debug.ctx.getImageData(
                    Math.round(x * ratio) - 2, Math.round(y * ratio) - 2, 5, 5).data;
                let sum = 0;
                for (let i = 0; i < data.length; i += 4) sum += data[i] - data[i + 2];
                return sum / (data.length / 4);
            }""",
            [alt, az],
        )
    )


async def test_zone_drawn_warning_shown_and_goto_sun_refused(browser: Browser) -> None:
    async with served(noon_mount()) as s, open_page(browser, s) as page:
        warning = page.locator("#sun-warning")
        await expect(warning).to_be_visible(timeout=TIMEOUT_MS)
        await expect(warning).to_contain_text("The Sun is up")
        await expect(warning).to_contain_text("within 15° of it are refused")
        await page.wait_for_function(
            "() => Chart.debug.report().sunZone === true", timeout=TIMEOUT_MS
        )
        sun = await page.evaluate("view.state.sun")
        assert sun["up"] is True
        assert sun["radius_deg"] == 15.0
        # Inside the zone (6° to 12° below the Sun) the chart is tinted like forbidden sky;
        # outside (22° to 31° below) it is not. The median of four patches each: a star drawn
        # on one patch (Orion's belt stands 25° below the Sun here) does not decide.
        inside = statistics.median(
            [await redness(page, sun["alt"] - d, sun["az"]) for d in (6.0, 8.0, 10.0, 12.0)]
        )
        outside = statistics.median(
            [await redness(page, sun["alt"] - d, sun["az"]) for d in (22.0, 25.0, 28.0, 31.0)]
        )
        assert inside > outside + 20.0, (inside, outside)
        await screenshot(page, "sun-01-zone")
        await page.fill("#goto-name", "Sun")
        await page.click("#goto-button")
        message = page.locator("#message")
        await expect(message).to_be_visible(timeout=TIMEOUT_MS)
        await expect(message).to_contain_text("Sun avoidance zone")
        assert s.mount.target is None
        await screenshot(page, "sun-02-refused")


async def test_zone_off_is_said_in_red(browser: Browser) -> None:
    async with served(noon_mount(radius=0.0)) as s, open_page(browser, s) as page:
        warning = page.locator("#sun-warning")
        await expect(warning).to_contain_text("Sun avoidance is OFF", timeout=TIMEOUT_MS)
        await expect(warning).to_have_class("off")
        colour = await warning.evaluate("(el) => getComputedStyle(el).color")
        red, green, blue = (int(v) for v in colour[colour.index("(") + 1 : -1].split(",")[:3])
        assert red > 200
        assert green < 120
        assert blue < 120
        await screenshot(page, "sun-03-off")


async def test_a_still_mount_in_the_suns_path_is_warned_about(browser: Browser) -> None:
    """A mount standing still 24° west of the Sun, on its path: the Sun reaches it in about 39
    minutes, and the page says so in red (nothing moves the mount by itself)."""
    clock = SimClock(start=NOON, rate=500.0)
    mount = SimulatedMount(EQ6, site=SITE, clock=clock, limits=Limits(sun_avoidance_deg=0.0))
    await mount.connect()
    await mount.goto_horizontal(55.0, 240.0)
    await mount.wait_for_slew(timeout_s=10.0)
    await mount.abort()
    await mount.set_tracking(TrackingMode.OFF)
    clock.set_rate(1.0)
    mount.limits = Limits(sun_avoidance_deg=15.0)
    async with served(mount, connect=False) as s, open_page(browser, s) as page:
        warning = page.locator("#sun-warning")
        await expect(warning).to_contain_text(
            re.compile(r"The Sun will reach where the mount points in 3\d min"), timeout=TIMEOUT_MS
        )
        await expect(warning).to_have_class("off")
        await screenshot(page, "sun-04-in-its-path")
