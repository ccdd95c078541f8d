"""The dashboard end to end in headless Chromium (Debian's, driven by Playwright; no browser is
downloaded): load, goto by clicking an object on the chart, watch the mount move, abort; a goto
below the horizon shows the error; search as you type; night mode survives a reload; hostile
text stays text. Screenshots go to ``test-artifacts/web/`` (printed)."""

from __future__ import annotations

import asyncio
import re

import pytest
from playwright.async_api import Browser, Page, expect

from scopelink.astro import SIDEREAL_RATE_DEG_S, angular_separation_deg
from scopelink.astro.catalog import lookup
from tests.support.browser import TIMEOUT_MS, open_page, screenshot
from tests.support.web import HIGH_UP, NEVER_UP, Served, served, sim_mount

# One browser for the whole file (launching costs a second or two): the tests share its loop.
pytestmark = pytest.mark.asyncio(loop_scope="module")


async def click_object(page: Page, name: str) -> None:
    """Click where the chart draws ``name`` (computed by the page's own projection)."""
    await page.wait_for_function(
        "(name) => Chart.debug.report().clickable.some((o) => o.name === name)",
        arg=name,
        timeout=TIMEOUT_MS,
    )
    x, y = await page.evaluate(
        "(name) => { const o = Chart.debug.report().clickable.find((o) => o.name === name);"
        " return [o.x, o.y]; }",
        name,
    )
    box = await page.locator("#sky").bounding_box()
    assert box is not None
    scale = box["width"] / await page.evaluate("Chart.debug.size")
    await page.mouse.click(box["x"] + x * scale, box["y"] + y * scale)


async def test_goto_by_clicking_the_chart_watch_it_move_then_abort(browser: Browser) -> None:
    # x2: the slew to Capella takes ~8 s, time enough to see it move and stop it on the way.
    async with served(sim_mount(rate=2.0), interval_s=0.1) as s, open_page(browser, s) as page:
        await screenshot(page, "01-loaded")
        await click_object(page, HIGH_UP)
        await expect(page.locator("#selection-name")).to_have_text(HIGH_UP)
        await page.click("#go-selected")
        await expect(page.locator("#st-slewing")).to_have_text("yes", timeout=TIMEOUT_MS)
        await expect(page.locator("#st-target")).to_have_text(HIGH_UP)
        first = await page.locator("#st-altaz").text_content()
        await expect(page.locator("#st-altaz")).not_to_have_text(first or "", timeout=TIMEOUT_MS)
        second = await page.locator("#st-altaz").text_content()
        await expect(page.locator("#st-altaz")).not_to_have_text(second or "", timeout=TIMEOUT_MS)
        await screenshot(page, "02-slewing")
        await page.click("#abort")
        await expect(page.locator("#st-slewing")).to_have_text("no", timeout=TIMEOUT_MS)
        state = await s.mount.refresh()
        assert not state.slewing
        capella = lookup(HIGH_UP, s.mount.now(), s.mount.site)
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        distance = angular_separation_deg(
            state.ra_j2000_hours * 15, state.dec_j2000_deg, capella.ra_hours * 15, capella.dec_deg
        )
        assert distance > 1.0  # stopped on the way, not arrived
        await screenshot(page, "03-aborted")


async def test_a_goto_below_the_horizon_shows_the_error_and_moves_nothing(
    browser: Browser,
) -> None:
    async with served() as s, open_page(browser, s) as page:
        await page.fill("#goto-name", NEVER_UP)
        await page.click("#goto-button")
        message = page.locator("#message")
        await expect(message).to_be_visible(timeout=TIMEOUT_MS)
        await expect(message).to_contain_text("below the configured horizon")
        await expect(message).to_have_class("error")
        assert s.mount.target is None
        assert not (await s.mount.refresh()).slewing
        await screenshot(page, "04-below-horizon")


async def test_search_as_you_type_fills_the_goto_box(browser: Browser) -> None:
    async with served() as s, open_page(browser, s) as page:
        # Wait for the answer to the whole word: under load the typing may pause long enough for
        # a search of a shorter prefix, whose list the last answer then replaces under the click.
        async with page.expect_response(lambda reply: "q=betel&" in reply.url):
            await page.locator("#goto-name").press_sequentially("betel", delay=30)
        suggestion = page.locator("#goto-suggestions button").first
        await expect(suggestion).to_contain_text("Betelgeuse", timeout=TIMEOUT_MS)
        await suggestion.click()
        await expect(page.locator("#goto-name")).to_have_value("Betelgeuse")
        await page.click("#goto-button")
        await expect(page.locator("#st-target")).to_have_text("Betelgeuse", timeout=TIMEOUT_MS)


async def test_night_mode_is_remembered_and_the_page_fits_a_phone(browser: Browser) -> None:
    async with served() as s, open_page(browser, s, width=390, height=844) as page:
        await page.click("#night-toggle")
        await expect(page.locator("body")).to_have_class(re.compile("night"))
        await page.reload()
        await expect(page.locator("body")).to_have_class(re.compile("night"), timeout=TIMEOUT_MS)
        overflow = await page.evaluate(
            "document.documentElement.scrollWidth - document.documentElement.clientWidth"
        )
        assert overflow <= 0  # nothing wider than the phone
        stop = await page.locator("#abort").bounding_box()
        assert stop is not None
        assert stop["height"] >= 44  # a finger-sized STOP
        await screenshot(page, "05-phone-night")


async def test_hostile_text_is_shown_as_text(browser: Browser) -> None:
    async with served() as s, open_page(browser, s) as page:
        hostile = '<img src=x onerror="window.pwned=1">'
        await page.fill("#goto-name", hostile)
        await page.click("#goto-button")
        await expect(page.locator("#message")).to_contain_text(hostile, timeout=TIMEOUT_MS)
        assert await page.locator("#message img").count() == 0
        assert await page.evaluate("window.pwned === undefined")


async def axis_speeds(s: Served, seconds: float = 0.3) -> tuple[float, float]:
    """How fast the RA and Dec readings change now (degrees per simulated second)."""
    first = await s.mount.refresh()
    before = s.mount.elapsed()
    await asyncio.sleep(seconds)
    second = await s.mount.refresh()
    elapsed = s.mount.elapsed() - before
    assert first.ra_j2000_hours is not None
    assert second.ra_j2000_hours is not None
    assert first.dec_j2000_deg is not None
    assert second.dec_j2000_deg is not None
    ra = abs(second.ra_j2000_hours - first.ra_j2000_hours) * 15 / elapsed
    dec = abs(second.dec_j2000_deg - first.dec_j2000_deg) / elapsed
    return ra, dec


async def test_the_pads_sidereal_multiples_use_the_servers_sidereal_rate(browser: Browser) -> None:
    """app.js writes no sidereal rate of its own: 8x is 8 x the package's one constant."""
    async with served(sim_mount(rate=2.0)) as s, open_page(browser, s) as page:
        await page.select_option("#rate", "2")  # SynScan rate 2: 8x
        async with page.expect_request(
            lambda request: request.url.endswith("/api/move") and request.method == "POST"
        ) as sent:
            await page.locator(".pad-up").dispatch_event("pointerdown")
        body = (await sent.value).post_data_json
        await page.locator(".pad-up").dispatch_event("pointerup")
        assert isinstance(body, dict)
        assert body["axis"] == "secondary"
        assert body["rate_deg_s"] == pytest.approx(8 * SIDEREAL_RATE_DEG_S, rel=1e-12)


async def test_the_pad_moves_while_held_by_pointer_or_key(browser: Browser) -> None:
    async with served(sim_mount(rate=2.0)) as s, open_page(browser, s) as page:
        await page.select_option("#rate", "7")  # SynScan rate 7: 400x
        await page.locator(".pad-down").hover()
        await page.mouse.down()
        await expect(page.locator(".pad-down")).to_have_class(re.compile("held"))
        await asyncio.sleep(0.5)  # past the acceleration ramp
        _, dec_speed = await axis_speeds(s)
        assert dec_speed > 0.5  # 400x sidereal is 1.67°/s
        await page.mouse.up()
        await expect(page.locator(".pad-down")).not_to_have_class(re.compile("held"))
        await asyncio.sleep(1.0)  # the deceleration ramp
        assert (await axis_speeds(s))[1] < 0.01

        # Not on the chart: there the arrows pan the chart (tests/web/test_web_chart.py).
        await page.locator("#st-altaz").click()
        await page.keyboard.down("ArrowRight")
        await asyncio.sleep(0.6)
        ra_speed, _ = await axis_speeds(s)
        assert ra_speed > 0.5
        await page.keyboard.up("ArrowRight")
        await asyncio.sleep(1.0)
        assert (await axis_speeds(s))[0] < 0.01
