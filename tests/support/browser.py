"""Helpers for the dashboard tests in headless Chromium (the browser itself is the ``browser``
fixture of tests/web/conftest.py)."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from playwright.async_api import Browser, Page, expect

from tests.support.web import Served

ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts" / "web"

TIMEOUT_MS = 10_000


async def screenshot(page: Page, name: str, *, full_page: bool = True) -> None:
    """``full_page=False``: what the viewport shows now (e.g. after scrolling)."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    await page.screenshot(path=str(path), full_page=full_page)
    print(f"screenshot: {path}")


@asynccontextmanager
async def open_page(
    browser: Browser,
    s: Served,
    width: int = 1300,
    height: int = 1000,
    *,
    init_script: str | None = None,
) -> AsyncIterator[Page]:
    """A fresh browser context on the dashboard, live; no script error may happen meanwhile.
    ``init_script`` runs in the page before its own scripts (e.g. a fake gamepad)."""
    context = await browser.new_context(viewport={"width": width, "height": height})
    if init_script is not None:
        await context.add_init_script(init_script)
    try:
        page = await context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        await page.goto(s.dashboard.url)
        await expect(page.locator("#link-status")).to_have_text("live", timeout=TIMEOUT_MS)
        await expect(page.locator("#hl-connected")).to_have_text("yes", timeout=TIMEOUT_MS)
        yield page
        assert errors == []
    finally:
        await context.close()
