"""Opening the dashboard's live connection costs the server a hello (the mount, the state, the
sky: ~15 kB): a client opening and closing it back to back took the mount's poller from 42 to 5
polls/s. Under a policy, opens are bounded per address and per server; beyond, 429 with
Retry-After, and the pages already open keep their updates."""

from __future__ import annotations

import asyncio
import json
from pathlib import Path

import aiohttp

from scopelink.servers.access import DEFAULT_POLICY
from scopelink.web import Dashboard
from scopelink.web.live_opens import (
    LIVE_OPEN_BURST,
    LIVE_OPENS_PER_S,
    LIVE_SERVER_OPEN_BURST,
    LIVE_SERVER_OPENS_PER_S,
)
from tests.support.alpaca import sim_mount


async def test_live_connections_opened_back_to_back_are_bounded() -> None:
    mount = sim_mount()
    await mount.connect()
    try:
        async with (
            Dashboard(mount, port=0, trace=False, access=DEFAULT_POLICY) as dashboard,
            aiohttp.ClientSession(base_url=dashboard.url) as http,
            http.ws_connect("/ws") as kept,
        ):
            assert json.loads((await kept.receive()).data)["type"] == "hello"
            refused = []
            for _ in range(LIVE_OPEN_BURST + 4):
                try:
                    async with http.ws_connect("/ws") as page:
                        await page.receive()
                except aiohttp.WSServerHandshakeError as error:
                    refused.append(error)
            assert len(refused) >= 4
            assert {error.status for error in refused} == {429}
            assert all(error.headers and "Retry-After" in error.headers for error in refused)
            # The page that was open still gets its updates.
            async with asyncio.timeout(5):
                assert json.loads((await kept.receive()).data)["type"] == "update"
    finally:
        await mount.disconnect()


def test_the_documented_bounds_are_the_codes() -> None:
    docs = " ".join((Path(__file__).parents[2] / "docs" / "dashboard.md").read_text().split())
    for name, value in (
        ("LIVE_OPENS_PER_S", LIVE_OPENS_PER_S),
        ("LIVE_OPEN_BURST", LIVE_OPEN_BURST),
        ("LIVE_SERVER_OPENS_PER_S", LIVE_SERVER_OPENS_PER_S),
        ("LIVE_SERVER_OPEN_BURST", LIVE_SERVER_OPEN_BURST),
    ):
        assert f"`{name}` = {value:g}" in docs, name
