"""The dashboard's live side over a real WebSocket: the hello, the updates while a page is open
(and polling only then), and the byte traffic decoded as it flows between the real SynScan
driver and the real emulator."""

from __future__ import annotations

import asyncio
import json
import logging
from typing import Any

import aiohttp
import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.astro import SIDEREAL_RATE_DEG_S
from scopelink.decode import Direction, Protocol
from scopelink.drivers.synscan import SynScanMount
from scopelink.links.trace import format_transfer, trace_logger, trace_transfer
from scopelink.mount import Mount
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import SimClock, SimulatedMount
from scopelink.web import Dashboard
from scopelink.web.almanac import TWILIGHT_BOUNDARIES_DEG
from scopelink.web.traffic import TrafficMonitor, parse_trace_line, protocol_by_port
from tests.support.web import HIGH_UP, SITE, START, served, sim_mount


def polling(mount: Mount) -> bool:
    """Whether the state poller runs (a call, so that type narrowing does not stick)."""
    return mount.poller.running


async def receive(ws: aiohttp.ClientWebSocketResponse, timeout_s: float = 5.0) -> dict[str, Any]:
    message = await ws.receive(timeout=timeout_s)
    assert message.type is aiohttp.WSMsgType.TEXT, message
    decoded: dict[str, Any] = json.loads(message.data)
    return decoded


async def test_hello_describes_the_mount_the_sky_and_the_state() -> None:
    async with served() as s, s.http.ws_connect("/ws") as ws:
        hello = await receive(ws)
        assert hello["type"] == "hello"
        assert hello["mount"]["identity"]["model"] == "EQ6"
        assert hello["mount"]["limits"]["horizon_deg"] == 0.0
        assert len(hello["mount"]["limits"]["horizon"]) == 180
        assert "sidereal" in hello["mount"]["capabilities"]["tracking_modes"]
        assert hello["mount"]["sidereal_rate_deg_s"] == SIDEREAL_RATE_DEG_S  # app.js's unit
        sky = {obj["name"]: obj for obj in hello["sky"]}
        assert {"Moon", "Jupiter", "Vega", "Sirius", HIGH_UP} <= set(sky)
        assert sky[HIGH_UP]["alt"] > 45  # high in the west at START
        assert 250 < sky[HIGH_UP]["az"] < 330
        assert hello["state"]["connected"] is True
        assert hello["traffic_enabled"] is True
        # The chart's twilight boundaries are the almanac's (the page holds no copy).
        assert hello["twilight_deg"] == {p: b for b, p in TWILIGHT_BOUNDARIES_DEG}


async def test_updates_flow_while_a_page_is_open_and_polling_stops_after() -> None:
    async with served(interval_s=0.1) as s:
        assert not polling(s.mount)
        async with s.http.ws_connect("/ws") as ws:
            await receive(ws)
            updates = [await receive(ws) for _ in range(6)]
            assert all(u["type"] == "update" for u in updates)
            assert any("sky" in u for u in updates)  # the chart's objects every other update
            assert polling(s.mount)
            reads = [u["state"]["read_at"] for u in updates]
            assert reads == sorted(reads)
            assert len(set(reads)) > 1  # fresh readings, not the same cached one
        for _ in range(50):
            if not polling(s.mount):
                break
            await asyncio.sleep(0.05)
        assert not polling(s.mount)
        assert s.dashboard.hub.clients == 0


async def test_a_goto_shows_in_the_live_state_until_arrival() -> None:
    # x3: this slew lasts a few simulated seconds, so that updates 10 times a second show it
    # whatever the machine's load (at x30 it can end between two updates).
    async with served(sim_mount(rate=3.0), interval_s=0.1) as s, s.http.ws_connect("/ws") as ws:
        await receive(ws)
        status, _ = await s.post("/api/goto", {"name": HIGH_UP})
        assert status == 200
        seen_slewing = False
        async with asyncio.timeout(60):
            while True:
                state = (await receive(ws))["state"]
                seen_slewing |= state["slewing"]
                if seen_slewing and not state["slewing"]:
                    break
        assert state["target"]["name"] == HIGH_UP
        assert state["alt_deg"] == pytest.approx(state["target_altaz"]["alt"], abs=0.1)
        assert state["az_deg"] == pytest.approx(state["target_altaz"]["az"], abs=0.2)


async def test_two_pages_share_one_poller_and_a_page_from_another_site_is_refused() -> None:
    async with served() as s:
        async with s.http.ws_connect("/ws") as one, s.http.ws_connect("/ws") as two:
            await receive(one)
            await receive(two)
            assert s.dashboard.hub.clients == 2
            assert s.mount.poller.watchers == 1
            await receive(one)
            await receive(two)
        with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
            async with s.http.ws_connect("/ws", origin="http://evil.example"):
                pass
        assert refused.value.status == 403


async def test_stopping_the_dashboard_closes_pages_and_stops_polling() -> None:
    async with served() as s:
        ws = await s.http.ws_connect("/ws")
        await receive(ws)
        await s.dashboard.stop()
        message = await ws.receive(timeout=5)
        assert message.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED)
        assert not polling(s.mount)
        await ws.close()


async def test_traffic_between_the_driver_and_the_emulator_is_decoded_live() -> None:
    sim = SimulatedMount(site=SITE, clock=SimClock(start=START, rate=1.0))
    async with SynScanEmulator(sim) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(f"tcp://{host}:{port}", site=SITE, clock=sim.now, timeout_s=5.0)
        await mount.connect()
        try:
            async with (
                Dashboard(mount, port=0, update_interval_s=0.1) as dashboard,
                aiohttp.ClientSession(base_url=dashboard.url) as http,
                http.ws_connect("/ws") as ws,
            ):
                assert dashboard.traffic is not None
                assert dashboard.traffic.protocol_for(f"tcp {host}:{port}") is Protocol.SYNSCAN
                await receive(ws)
                pc_meanings: list[str] = []
                device_meanings: list[str] = []
                async with asyncio.timeout(10):
                    while not (pc_meanings and device_meanings):
                        for line in (await receive(ws))["traffic"]:
                            if line["link"].startswith(f"tcp {host}:{port}"):
                                side = pc_meanings if line["from"] == "pc" else device_meanings
                                side.extend(m["text"] for m in line["meanings"])
                # The driver polls the position: "e" (or "E") and its decoded reply.
                assert any("RA/Dec" in text for text in pc_meanings), pc_meanings
                assert any(text.startswith("RA ") for text in device_meanings), device_meanings
                # The emulator's own end of the same TCP connection is decoded from its side.
                server_lines = [line for line in dashboard.traffic.since(0) if " on :" in line.link]
                assert server_lines
                assert {line.sender.value for line in server_lines} == {"pc", "device"}
                assert all(kind != "error" for line in server_lines for kind, _ in line.meanings)
        finally:
            await mount.disconnect()


def test_the_traffic_monitor_restores_the_trace_logger() -> None:
    level, propagate = trace_logger.level, trace_logger.propagate
    monitor = TrafficMonitor(Protocol.SYNSCAN, capacity=3)
    with monitor.attached():
        assert trace_logger.isEnabledFor(logging.DEBUG)
        assert trace_logger.propagate is False  # nobody else asked: no console flood
        for _ in range(5):
            trace_transfer("-->", "tcp 127.0.0.1:1", b"e")
    assert (trace_logger.level, trace_logger.propagate) == (level, propagate)
    assert monitor not in trace_logger.handlers
    lines = monitor.since(0)
    assert [line.seq for line in lines] == [3, 4, 5]  # only the last `capacity` kept
    trace_transfer("-->", "tcp 127.0.0.1:1", b"e")  # detached: nothing more arrives
    assert len(monitor.since(0)) == 3


def test_a_trace_someone_asked_for_still_reaches_their_handlers() -> None:
    previous = trace_logger.level
    trace_logger.setLevel(logging.DEBUG)
    try:
        with TrafficMonitor(Protocol.SYNSCAN).attached():
            assert trace_logger.propagate is True
        assert trace_logger.level == logging.DEBUG
    finally:
        trace_logger.setLevel(previous)


@given(
    link=st.text(
        alphabet=st.characters(blacklist_categories=("Cs", "Cc")), min_size=1, max_size=30
    ).filter(lambda name: name.strip() == name),
    arrow=st.sampled_from(["-->", "<--"]),
    data=st.binary(min_size=1, max_size=64),
)
def test_trace_lines_parse_back_to_their_bytes(link: str, arrow: str, data: bytes) -> None:
    assert parse_trace_line(format_transfer(arrow, link, data)) == (link, arrow, data)


@given(st.text(max_size=80))
def test_any_other_log_text_is_ignored_or_parsed_without_raising(text: str) -> None:
    parsed = parse_trace_line(text)
    assert parsed is None or isinstance(parsed[2], bytes)


async def test_a_site_change_reaches_every_open_page() -> None:
    async with served(interval_s=0.1) as s, s.http.ws_connect("/ws") as ws:
        hello = await receive(ws)
        assert hello["mount"]["site"]["latitude_deg"] == 45.0
        status, _ = await s.post("/api/site", {"latitude_deg": -31.3, "longitude_deg": 149.1})
        assert status == 200
        async with asyncio.timeout(5):
            while True:
                update = await receive(ws)
                if "mount" in update:
                    break
        assert update["mount"]["site"]["latitude_deg"] == -31.3
        sky = {obj["name"]: obj for obj in update.get("sky") or []}
        assert sky, "the chart's objects come with the same update"
        assert sky["Acrux"]["alt"] > 0  # the Southern Cross is up from Siding Spring


def test_a_chooser_decodes_each_link_as_its_own_protocol_or_not_at_all() -> None:
    def chooser(link: str) -> Protocol | None:
        return Protocol.SYNSCAN if link.endswith(":11880") else None

    monitor = TrafficMonitor(chooser)
    with monitor.attached():
        trace_transfer("-->", "tcp 127.0.0.1:11880", b"V")
        trace_transfer("-->", "tcp 127.0.0.1:4030", b"#:GR#")
    synscan, lx200 = monitor.since(0)
    assert synscan.meanings == (("command", "get hand control version"),)
    assert lx200.meanings == ()
    assert lx200.data == b"#:GR#"


def test_protocol_by_port_decodes_each_server_as_its_own() -> None:
    monitor = TrafficMonitor(protocol_by_port({11880: Protocol.SYNSCAN}, Protocol.SKYTRACKER))
    with monitor.attached():
        trace_transfer("<--", "tcp 127.0.0.1:50000 on :11880", b"V")
        trace_transfer("<--", "tcp 127.0.0.1:50001 on :4030", b"#:GR#")
        trace_transfer("-->", "/dev/ttyUSB0", b"V")
    synscan, lx200, skytracker = monitor.since(0)
    assert synscan.meanings == (("command", "get hand control version"),)
    assert synscan.sender is Direction.PC
    assert lx200.meanings == ()
    assert skytracker.meanings
    assert skytracker.meanings != synscan.meanings
