"""The panel in headless Chromium (issue #17 parts 2-6), on the real simulated mount behind a real
dashboard: the tracking menu's truth, health in words, keyboard shortcuts (and none while typing),
a gamepad (a fake ``navigator.getGamepads`` driven from the test: the stick moves the mount,
centring it stops, losing the pad stops, a button stops), slew progress and arrival, feedback on
Set and Park, the suggestion list closing after Go; on a phone, the first-run check saving the
settings file and STOP in view after scrolling. Every motion is checked on the mount itself,
through ``GET /api/state``."""

from __future__ import annotations

import asyncio
import re
from collections.abc import Awaitable, Callable
from pathlib import Path

import pytest
from playwright.async_api import Browser, Page, Request, expect

from scopelink.cli.config import load_config
from scopelink.cli.site_store import SettingsSiteStore
from tests.support.browser import TIMEOUT_MS, open_page, screenshot
from tests.support.web import HIGH_UP, Served, served, sim_mount

pytestmark = pytest.mark.asyncio(loop_scope="module")

FAKE_GAMEPAD = """
window.fakePad = {
  id: "fake pad", index: 0, connected: true, mapping: "standard", timestamp: 0,
  axes: [0, 0, 0, 0],
  buttons: Array.from({ length: 17 }, () => ({ pressed: false, touched: false, value: 0 })),
};
window.fakePadPlugged = false;
Object.defineProperty(Navigator.prototype, "getGamepads", {
  configurable: true,
  value: () => {
    window.fakePadReads = (window.fakePadReads || 0) + 1;  // the page's polls, counted
    return [window.fakePadPlugged ? window.fakePad : null, null, null, null];
  },
});
"""

HIDE = """Object.defineProperty(document, "hidden", { configurable: true, get: () => true });
document.dispatchEvent(new Event("visibilitychange"))"""
SHOW = """Object.defineProperty(document, "hidden", { configurable: true, get: () => false });
document.dispatchEvent(new Event("visibilitychange"))"""


async def pad_polled(page: Page) -> None:
    """Return once the page has read the pad twice more (it polls every 50 ms): what the test
    changed has been seen, however slowly the browser runs."""
    reads = await page.evaluate("window.fakePadReads || 0")

    async def read_twice() -> bool:
        return bool(await page.evaluate(f"(window.fakePadReads || 0) >= {reads + 2}"))

    await until(read_twice, "the page reads the pad")


async def until(check: Callable[[], Awaitable[bool]], what: str, timeout_s: float = 8.0) -> None:
    for _ in range(int(timeout_s / 0.05)):
        if await check():
            return
        await asyncio.sleep(0.05)
    raise AssertionError(f"timed out waiting for: {what}")


async def slewing(s: Served) -> bool:
    """Whether the mount moves, as the API reports it (the sim's real state)."""
    status, body = await s.get("/api/state")
    assert status == 200
    return bool(body["state"]["slewing"])


async def moves_then_stops(
    s: Served, start: Callable[[], Awaitable[object]], stop: Callable[[], Awaitable[object]]
) -> None:
    await start()
    await until(lambda: slewing(s), "the mount moves")
    await stop()
    await until(lambda: _not(slewing(s)), "the mount stops")


def _keep_rate(request: Request, rates: list[float]) -> None:
    """The rates the page's moves ask for, in order."""
    if request.url.endswith("/api/move"):
        body = request.post_data_json
        assert isinstance(body, dict)
        rates.append(float(body["rate_deg_s"]))


async def _not(value: Awaitable[bool]) -> bool:
    return not await value


async def pad(page: Page, script: str) -> None:
    await page.evaluate(script)


async def test_desktop_controls_keys_gamepad_progress_and_feedback(browser: Browser) -> None:
    async with (
        served(sim_mount(rate=10.0)) as s,
        open_page(browser, s, 1280, 800, init_script=FAKE_GAMEPAD) as page,
    ):
        # The tracking menu shows the mount's real mode at start (the simulator starts off).
        assert s.mount.state.tracking.value == "off"
        await expect(page.locator("#tracking-mode")).to_have_value("off")
        await expect(page.locator("#hl-words")).to_have_text(
            re.compile(r"^link OK, \d+ readings/s$"), timeout=TIMEOUT_MS
        )
        await expect(page.locator("#hl-polls")).to_be_hidden()  # developer counters folded
        await expect(page.locator("#traffic-nowire")).to_be_visible()
        await expect(page.locator("#traffic-panel")).to_be_hidden()
        await expect(page.locator(".pad-up .dir")).to_have_text("N")
        await expect(page.locator(".pad-left .dir")).to_have_text("E")
        await expect(page.locator("#rate option")).to_have_count(9)
        await expect(page.locator("#rate")).to_have_value("7")  # 400x

        # Keys: "?" lists them; typed letters in a field move nothing; WASD and arrows do.
        await page.keyboard.press("?")
        await expect(page.locator("#keys-help")).to_be_visible()
        await page.keyboard.press("Escape")
        await expect(page.locator("#keys-help")).to_be_hidden()
        moves: list[str] = []
        page.on("request", lambda r: moves.append(r.url) if r.url.endswith("/api/move") else None)
        await page.locator("#goto-name").press_sequentially("wasd")
        await page.locator("#goto-name").fill("")
        await asyncio.sleep(0.3)
        assert moves == []
        assert not await slewing(s)
        await page.locator("#status").click()  # out of the field
        await moves_then_stops(s, lambda: page.keyboard.down("d"), lambda: page.keyboard.up("d"))
        await moves_then_stops(
            s, lambda: page.keyboard.down("ArrowUp"), lambda: page.keyboard.press("Space")
        )
        await page.keyboard.up("ArrowUp")
        await expect(page.locator("#message")).to_have_text("stopped")

        # The gamepad: the stick moves, centring stops, losing the pad stops, A stops.
        await pad(page, "fakePadPlugged = true; dispatchEvent(new Event('gamepadconnected'))")
        await expect(page.locator("#gamepad-status")).to_contain_text("fake pad")
        async with page.expect_request(lambda r: r.url.endswith("/api/move")) as sent:
            await pad(page, "fakePad.axes[1] = -1")  # stick up: north
        body = (await sent.value).post_data_json
        assert isinstance(body, dict)
        assert body["axis"] == "secondary"
        await until(lambda: slewing(s), "the stick moves the mount")
        await pad(page, "fakePad.axes[1] = 0.1")  # inside the dead zone
        await until(lambda: _not(slewing(s)), "centring the stick stops it")
        await moves_then_stops(
            s,
            lambda: pad(page, "fakePad.axes[0] = 1"),
            lambda: pad(page, "fakePadPlugged = false"),  # unplugged mid-move
        )
        await expect(page.locator("#message")).to_contain_text("gamepad lost: stopped")
        await pad(page, "fakePadPlugged = true; dispatchEvent(new Event('gamepadconnected'))")
        await until(lambda: slewing(s), "the held stick moves it again")
        await pad(page, "fakePad.buttons[0].pressed = true")
        await until(lambda: _not(slewing(s)), "button A stops it")
        await asyncio.sleep(0.4)
        assert not await slewing(s)  # the stick is still held: nothing until it centres
        await pad(page, "fakePad.buttons[0].pressed = false; fakePad.axes[0] = 0")
        await pad_polled(page)  # the centred stick is seen: the latch lets go

        # The page hidden (a phone's screen locked, with no blur) stops the stick and the keys;
        # the held stick does not start again while hidden, nor on return until it centres.
        rates: list[float] = []
        page.on("request", lambda r: _keep_rate(r, rates))

        async def asked_to_stop() -> bool:
            return bool(rates) and rates[-1] == 0

        holds: list[tuple[Callable[[], Awaitable[object]], Callable[[], Awaitable[object]]]] = [
            (lambda: pad(page, "fakePad.axes[0] = 1"), lambda: pad(page, "fakePad.axes[0] = 0")),
            (lambda: page.keyboard.down("a"), lambda: page.keyboard.up("a")),
        ]
        for start, end in holds:
            await start()
            await until(lambda: slewing(s), "the mount moves")
            await pad(page, HIDE)
            await until(asked_to_stop, "hiding the page stops it")
            await asyncio.sleep(0.4)  # several of the gamepad's polls
            await pad(page, SHOW)
            await asyncio.sleep(0.4)
            assert rates[-1] == 0, rates
            await end()
            await until(lambda: _not(slewing(s)), "the mount stops")
            await pad_polled(page)  # the centred stick is seen

        # Go by name: the list closes, progress shows, then the arrival; the almanac follows.
        await page.locator("#goto-name").press_sequentially("Capel", delay=20)
        await expect(page.locator("#goto-suggestions li").first).to_be_visible(timeout=TIMEOUT_MS)
        await page.locator("#goto-name").fill(HIGH_UP)
        await page.click("#goto-button")
        await expect(page.locator("#slew-status")).to_contain_text(
            f"slewing to {HIGH_UP}", timeout=TIMEOUT_MS
        )
        await expect(page.locator("#slew-status")).to_contain_text("° to go")
        await expect(page.locator("#goto-suggestions li")).to_have_count(0)
        await screenshot(page, "panel-01-slewing")
        await expect(page.locator("#slew-status")).to_have_text(
            f"arrived at {HIGH_UP}", timeout=TIMEOUT_MS
        )
        await expect(page.locator("#goto-suggestions li")).to_have_count(0)  # still closed
        await expect(page.locator("#message")).to_be_hidden()  # no "slewing to" left over
        await expect(page.locator("#oi-title")).to_have_text(HIGH_UP)
        await expect(page.locator("#oi-rts")).to_contain_text("transit")
        await expect(page.locator("#ck-twilight")).to_have_text("night")
        await expect(page.locator("#tracking-mode")).to_have_value(s.mount.state.tracking.value)
        await screenshot(page, "panel-02-arrived")

        # Feedback on Set and Park, with the mount's own answer.
        await page.select_option("#tracking-mode", "lunar")
        await page.click("#tracking-apply")
        await expect(page.locator("#message")).to_have_text("tracking set: lunar")
        assert s.mount.state.tracking.value == "lunar"
        await page.click("#park")
        await expect(page.locator("#message")).to_contain_text("parking")
        await expect(page.locator("#slew-status")).to_have_text("parked", timeout=TIMEOUT_MS)
        assert s.mount.state.parked


async def test_phone_first_run_saves_the_site_and_stop_stays_in_view(
    browser: Browser, tmp_path: Path
) -> None:
    path = tmp_path / "config.toml"
    store = SettingsSiteStore(path, saved=False)
    async with (
        served(sim_mount(rate=10.0), site_store=store) as s,
        open_page(browser, s, 390, 844) as page,
    ):
        await expect(page.locator("#firstrun")).to_be_visible(timeout=TIMEOUT_MS)
        await expect(page.locator("#fr-where")).to_have_text(str(path))
        await expect(page.locator("#fr-clock")).to_contain_text("the mount:")
        await expect(page.locator("#fr-lat")).to_have_value("45")  # the mount's site to start
        await page.fill("#fr-lat", "-31.27")
        await page.fill("#fr-lon", "149.06")
        await page.fill("#fr-elev", "1165")
        await screenshot(page, "panel-03-first-run-phone")
        await page.click("#fr-save")
        await expect(page.locator("#message")).to_contain_text(f"site saved to {path}")
        await expect(page.locator("#firstrun")).to_be_hidden()
        config = load_config(path)
        assert (config.site.latitude_deg, config.site.longitude_deg) == (-31.27, 149.06)
        assert s.mount.site.elevation_m == 1165

        await page.click("#site-form >> xpath=ancestor::details/summary")
        field = await page.locator("#site-lon").bounding_box()
        form = await page.locator("#site-form").bounding_box()
        assert field is not None
        assert form is not None
        assert field["x"] + field["width"] <= form["x"] + form["width"] + 0.5  # fits its panel

        # The first run set the mount's clock from the browser's (now): a named star may be
        # down at this hour (Canopus was, at 03:00 UTC). At latitude -31° the Sun never stands
        # in the south above the horizon, so a slew up the southern meridian is allowed at
        # any hour.
        answer = await s.post("/api/goto", {"alt_deg": 60.0, "az_deg": 180.0})
        assert answer[0] == 200, answer
        await page.evaluate("window.scrollTo(0, document.body.scrollHeight)")
        assert await page.evaluate("window.scrollY") > 500
        box = await page.locator("#abort").bounding_box()
        assert box is not None
        assert box["y"] >= 0
        assert box["y"] + box["height"] <= 844
        assert box["height"] >= 44
        on_top = await page.evaluate(
            "([x, y]) => document.elementFromPoint(x, y).id", [box["x"] + 5, box["y"] + 5]
        )
        assert on_top == "abort"  # nothing covers it
        await screenshot(page, "panel-04-phone-scrolled", full_page=False)
        await page.click("#abort")
        await expect(page.locator("#message")).to_have_text("stopped")
        await until(lambda: _not(slewing(s)), "STOP stops the goto")
