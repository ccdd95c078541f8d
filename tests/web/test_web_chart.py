"""The sky chart in headless Chromium (Debian's, driven by Playwright), on a desktop and a phone:
it draws constellations, deep-sky objects, the Milky Way and stars (the page's debug hook,
``Chart.debug.report()``, says what the last drawing showed); zoom by wheel, keys and pinch and
pan by drag change the field; labels never overlap; a click selects an object; the slew path
shows while slewing; the eyepiece frame appears at full zoom; the page loads nothing from
another host. Each run prints the chart's drawing time (not asserted) and writes screenshots of
the chart to ``test-artifacts/web/``."""

from __future__ import annotations

import re
from typing import Any

import pytest
from playwright.async_api import Browser, Page, expect

from tests.support.browser import ARTIFACTS, TIMEOUT_MS, open_page
from tests.support.web import HIGH_UP, served, sim_mount

pytestmark = pytest.mark.asyncio(loop_scope="module")

DRAWN = (
    "() => { const r = Chart.debug.report();"
    " return r.constellations > 0 && r.milkyway > 0 && r.deepsky > 0 && r.stars > 0; }"
)


async def report(page: Page) -> dict[str, Any]:
    value = await page.evaluate("Chart.debug.report()")
    assert isinstance(value, dict)
    return value


async def fov(page: Page) -> float:
    return float(await page.evaluate("Chart.debug.report().fov"))


async def shot(page: Page, name: str) -> None:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"chart-{name}.png"
    await page.locator("#chart-panel").screenshot(path=str(path))
    print(f"screenshot: {path}")


def assert_labels_apart(labels: list[dict[str, Any]]) -> None:
    assert len(labels) >= 5
    boxes = [label["box"] for label in labels]
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            apart = a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1]
            assert apart, (a, b)


async def wait_for_change(page: Page, before: float) -> float:
    await page.wait_for_function(
        "(before) => Chart.debug.report().fov !== before", arg=before, timeout=TIMEOUT_MS
    )
    return await fov(page)


async def assert_only_own_host(page: Page, origin: str) -> None:
    urls = await page.evaluate(
        "performance.getEntriesByType('resource').map((e) => e.name).concat([location.href])"
    )
    foreign = [url for url in urls if not url.startswith(origin)]
    assert foreign == []
    assert any("/static/vendor/d3-geo.min.js" in url for url in urls)


async def test_the_chart_on_a_desktop(browser: Browser) -> None:
    async with served(sim_mount(rate=1.0)) as s, open_page(browser, s) as page:
        await page.wait_for_function(DRAWN, timeout=TIMEOUT_MS)
        drawn = await report(page)
        assert drawn["fov"] == 200
        assert drawn["twilight"] == "night"  # 21 h UTC in March
        # The sky hides stars by the server's twilight boundaries (web/almanac.py, the hello).
        limits = await page.evaluate("[0, -0.8, -0.9, -6, -12, -18, -40].map(Chart.debug.skyLimit)")
        assert limits[:2] == [-99, -99]  # day: upper limb above -0.833°
        assert limits[2:6] == pytest.approx([2.0233, 3.8058, 5.9029, 8.0], abs=1e-3)
        assert limits[6] == 8.0
        assert drawn["mount"] is not None  # the crosshair is on the chart
        assert_labels_apart(drawn["labels"])
        # The J2000 layers sit where the server puts the same stars (its frame, its refraction).
        for name, ra, dec in (("Capella", 79.1723, 45.998), ("Sirius", 101.2872, -16.7161)):
            server = await page.evaluate("(name) => Chart.debug.find(name)", name)
            chart = await page.evaluate("([ra, dec]) => Chart.debug.toSky(ra, dec)", [ra, dec])
            assert abs(chart["alt"] - server["alt"]) < 0.03, name
            assert abs((chart["az"] - server["az"] + 180) % 360 - 180) < 0.05, name
        print(f"desktop chart: {await page.evaluate('Chart.debug.benchmark(5)'):.1f} ms a drawing")
        await assert_only_own_host(page, s.dashboard.url.rstrip("/"))
        await shot(page, "desktop")

        # The mouse wheel zooms in at the pointer.
        box = await page.locator("#sky").bounding_box()
        assert box is not None
        await page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        await page.mouse.wheel(0, -400)
        wheel = await wait_for_change(page, 200)
        assert wheel < 200

        # Keys on the focused chart zoom and pan it; the arrows do not reach the pad.
        await page.locator("#sky").focus()
        await page.keyboard.press("+")
        keyed = await wait_for_change(page, wheel)
        assert keyed < wheel
        az = await page.evaluate("Chart.debug.view.az")
        await page.keyboard.down("ArrowLeft")
        await page.wait_for_function(
            "(az) => Chart.debug.view.az !== az", arg=az, timeout=TIMEOUT_MS
        )
        await expect(page.locator(".pad-left")).not_to_have_class(re.compile("held"))
        await page.keyboard.up("ArrowLeft")
        await page.keyboard.press("0")  # the whole sky again
        await wait_for_change(page, keyed)
        assert_labels_apart((await report(page))["labels"])
        # Outside the sky's disc nothing is left of the zoomed drawings.
        assert await page.evaluate("Chart.debug.ctx.getImageData(3, 3, 1, 1).data[3]") == 0

        # A click on a Messier object selects it by name.
        await page.wait_for_function(DRAWN, timeout=TIMEOUT_MS)
        messier = next(o for o in (await report(page))["clickable"] if o["name"].startswith("M "))
        await page.mouse.click(box["x"] + messier["x"], box["y"] + messier["y"])
        await expect(page.locator("#selection-name")).to_have_text(messier["name"])

        # While the mount slews, its planned path is drawn, and the track GET /api/track gives
        # (an endpoint of another branch, answered here by the browser: without it, a 404, the
        # chart draws no track) with its error beside the target.
        assert (await report(page))["track"] is False
        await page.route("**/api/track", lambda route: route.fulfill(json=TRACK))
        status, _ = await s.post("/api/goto", {"name": HIGH_UP})
        assert status == 200
        await page.wait_for_function(
            "() => { const r = Chart.debug.report();"
            " return r.path && r.track && r.error === '12″'; }",
            timeout=TIMEOUT_MS,
        )
        await shot(page, "slewing")
        await s.post("/api/abort")
        # The real endpoint (web/track.py): following the Moon replaces the stub's track with the
        # server's (its path at once, its error once the mount follows), and stopping clears it.
        await page.unroute("**/api/track")
        status, _ = await s.post("/api/track", {"target": "moon"})
        assert status == 200
        await page.wait_for_function(
            "() => { const r = Chart.debug.report(); return r.track && r.error !== '12″'; }",
            timeout=TIMEOUT_MS,
        )
        status, _ = await s.post("/api/track", {"target": None})
        assert status == 200
        await page.wait_for_function("() => !Chart.debug.report().track", timeout=TIMEOUT_MS)
        await s.post("/api/abort")

        # Centred on the mount and zoomed in all the way: a 1° field with the eyepiece frame.
        await page.get_by_role("button", name="Centre on the mount and follow it (M)").click()
        await page.locator("#sky").focus()
        for _ in range(14):
            await page.keyboard.press("+")
        await page.wait_for_function(
            "() => Chart.debug.report().fov === 1 && Chart.debug.report().frame === true",
            timeout=TIMEOUT_MS,
        )
        assert await page.evaluate("Chart.debug.view.follow") is True
        await shot(page, "zoomed-frame")
        await page.keyboard.press("ArrowUp")  # any pan ends the following
        assert await page.evaluate("Chart.debug.view.follow") is False

        await page.click("#night-toggle")
        await page.locator("#sky").press("0")
        await page.wait_for_function("() => Chart.debug.report().fov === 200", timeout=TIMEOUT_MS)
        await shot(page, "night")


TRACK = {
    "target": HIGH_UP,
    "kind": "star",
    "error_arcsec": 12.3,
    "path": [[79.17, 45.99], [79.5, 46.2], [80.0, 46.4], "junk", [80.5]],
}

POINTER = """([type, id, x, y]) => {
    const rect = document.getElementById("sky").getBoundingClientRect();
    document.getElementById("sky").dispatchEvent(new PointerEvent(type, {
        pointerId: id, pointerType: "touch", isPrimary: id === 1, bubbles: true,
        clientX: rect.left + x, clientY: rect.top + y }));
}"""


async def test_the_chart_on_a_phone_with_touch(browser: Browser) -> None:
    async with served(sim_mount(rate=1.0)) as s, open_page(browser, s, 390, 844) as page:
        await page.wait_for_function(DRAWN, timeout=TIMEOUT_MS)
        assert_labels_apart((await report(page))["labels"])
        print(f"phone chart: {await page.evaluate('Chart.debug.benchmark(5)'):.1f} ms a drawing")
        await shot(page, "phone")
        # Two fingers spread apart: zoom in.
        await page.evaluate(POINTER, ["pointerdown", 1, 150, 180])
        await page.evaluate(POINTER, ["pointerdown", 2, 200, 180])
        await page.evaluate(POINTER, ["pointermove", 2, 300, 180])
        await page.evaluate(POINTER, ["pointerup", 2, 300, 180])
        await page.evaluate(POINTER, ["pointerup", 1, 150, 180])
        pinched = await wait_for_change(page, 200)
        assert pinched == pytest.approx(200 / 3, rel=0.01)
        # One finger dragged: the view pans, and it is no tap (nothing selected).
        view = await page.evaluate("({...Chart.debug.view})")
        await page.evaluate(POINTER, ["pointerdown", 1, 100, 100])
        await page.evaluate(POINTER, ["pointermove", 1, 160, 150])
        await page.evaluate(POINTER, ["pointerup", 1, 160, 150])
        await page.wait_for_function(
            "(v) => Chart.debug.view.az !== v.az || Chart.debug.view.alt !== v.alt", arg=view
        )
        assert await page.locator("#selection").is_hidden()
        await page.wait_for_function(DRAWN, timeout=TIMEOUT_MS)
        assert_labels_apart((await report(page))["labels"])
