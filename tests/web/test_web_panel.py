"""The panel's server side (issue #17 parts 2-6) over real HTTP and a real WebSocket on a simulated
mount: the pad's directions and the hand control's speeds, the clock and twilight, an object's
almanac and when it reaches the mount's limits, slew progress and how a slew ended, health in
words, push-to figures on the updates, and the first-run check saving the settings file."""

from __future__ import annotations

import asyncio
import dataclasses
import json
import re
from collections.abc import Callable
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

import aiohttp
import pytest

from scopelink.astro import SIDEREAL_RATE_DEG_S, PierSide, Site
from scopelink.astro.catalog import rise_transit_set
from scopelink.cli.config import load_config
from scopelink.cli.site_store import SettingsSiteStore
from scopelink.mount import Limits, MountAxis
from scopelink.sim import (
    AZ_GTI,
    SKY_TRACKER,
    SYNSCAN_FIXED_RATE_MULTIPLES,
    SimClock,
    SimulatedMount,
)
from scopelink.web.almanac import TWILIGHT_BOUNDARIES_DEG, clock_json, twilight_phase
from scopelink.web.busy import OBJECT_INFO_AT_ONCE, REST_PER_BUSY
from scopelink.web.health import WINDOW_S
from scopelink.web.objectinfo import LIMIT_STEP_MIN
from scopelink.web.pad import DEFAULT_SYNSCAN_RATE, GENERIC_MULTIPLES, pad_json, rates_json
from scopelink.web.progress import ARRIVED_DEG, ENDED_SHOWN_S
from tests.support.web import HIGH_UP, SITE, START, served, sim_mount


def plain_pad_json(*args: Any) -> Any:
    """``pad_json`` as the page gets it (through JSON)."""
    return json.loads(json.dumps(pad_json(*args)))


def plain_rates_json(*args: Any) -> Any:
    return json.loads(json.dumps(rates_json(*args)))


async def next_state(
    ws: aiohttp.ClientWebSocketResponse,
    until: Callable[[dict[str, Any]], bool],
    timeout_s: float = 10.0,
) -> dict[str, Any]:
    """The first update's state for which ``until`` holds."""
    for _ in range(int(timeout_s / 0.05)):
        message = json.loads((await ws.receive(timeout=timeout_s)).data)
        state: dict[str, Any] = {**message["state"], **message["panel"]}  # as the page reads it
        if until(state):
            return state
    raise AssertionError("no such state came")


async def test_pad_directions_follow_the_sky_and_speeds_the_hand_control() -> None:
    eq6 = sim_mount()
    await eq6.connect()
    try:
        state = eq6.state
        east_side = dataclasses.replace(state, pier_side=PierSide.EAST)
        pad = plain_pad_json(eq6, east_side)
        assert [pad[d]["label"] for d in ("up", "down", "left", "right")] == ["N", "S", "E", "W"]
        # North: declination up, on the normal (east) side the secondary axis forwards; east:
        # the primary backwards (forwards turns west in the north).
        assert (pad["up"]["axis"], pad["up"]["sign"]) == ("secondary", 1)
        assert (pad["left"]["axis"], pad["left"]["sign"]) == ("primary", -1)
        flipped = plain_pad_json(eq6, dataclasses.replace(state, pier_side=PierSide.WEST))
        assert flipped["up"]["sign"] == -1  # a meridian flip turns the buttons with the tube
        unknown = plain_pad_json(eq6, dataclasses.replace(state, pier_side=PierSide.UNKNOWN))
        assert unknown["up"]["label"] == "Dec +"  # never a guess at north
        rates = plain_rates_json(eq6)
        assert rates["hand_control"] == "synscan"
        assert [c["key"] for c in rates["choices"]] == [str(n) for n in range(1, 10)]
        assert rates["choices"][1]["rate_deg_s"] == 8 * SIDEREAL_RATE_DEG_S
        assert rates["choices"][8]["label"] == "rate 9 · 800× (3.3°/s)"
    finally:
        await eq6.disconnect()
    south = SimulatedMount(AZ_GTI, site=Site(-33.9, 18.4), clock=SimClock(start=START))
    pad = plain_pad_json(south, south.state)
    assert [pad[d]["label"] for d in ("up", "down", "left", "right")] == [
        "Up",
        "Down",
        "Left",
        "Right",
    ]
    assert (pad["right"]["axis"], pad["right"]["sign"]) == ("primary", 1)  # azimuth up
    tracker = SimulatedMount(SKY_TRACKER, site=SITE, clock=SimClock(start=START))
    speeds = plain_rates_json(tracker)["choices"]
    assert [c["label"] for c in speeds] == ["guide 2′/s", "track 8′/s", "utility 4°/s"]


def test_twilight_phases_and_the_clock() -> None:
    phases = [twilight_phase(alt) for alt in (10.0, -0.5, -3.0, -9.0, -15.0, -20.0)]
    assert phases == [
        "day",
        "day",
        "civil twilight",
        "nautical twilight",
        "astronomical twilight",
        "night",
    ]
    night = clock_json(START, SITE)  # 21:00 UTC on 1 March at 45° N
    assert night["twilight"] == "night"
    assert isinstance(night["sun_alt"], float)
    assert night["sun_alt"] < -18
    assert night["lst_hours"] == pytest.approx(8.11, abs=0.02)
    noon = clock_json(START.replace(hour=11, minute=30), SITE)
    assert noon["twilight"] == "day"


async def test_object_almanac_and_the_time_it_reaches_the_mounts_horizon() -> None:
    # A raised horizon of 30°: M 31 (16° up in the north-west) is below it and rises above it
    # when the almanac with a 30° horizon says so, to the 5-minute sampling.
    async with served(sim_mount(limits=Limits(horizon_deg=30.0))) as s:
        status, info = await s.get("/api/object", name="m31")
        assert status == 200
        assert info["name"] == "M 31"
        assert info["type"] == "Galaxy"
        assert info["constellation"] == "And"
        assert info["size_arcmin"][0] > 100  # OpenNGC: 177.8' x 69.7'
        assert info["limit"]["event"] == "rises"
        expected = rise_transit_set("M 31", s.mount.site, s.mount.now(), horizon_deg=30.0).rise
        assert expected is not None
        assert abs(_parse(info["limit"]["at"]) - expected) <= timedelta(minutes=5, seconds=30)
        assert info["meridian_limit"] is not None  # an EQ6: a German mount
        assert _parse(info["transit"]) < _parse(info["meridian_limit"])
        status, error = await s.get("/api/object", name="M 3l")
        assert status == 404
        assert error["suggestions"]
        status, error = await s.get("/api/object", name="")
        assert status == 400
        # A flood of these (~0.1 s of CPU each) is bounded: one computed at a time, a few wait,
        # the rest are told to come back (they took the poller's CPU: docs/dashboard.md).
        answers = await asyncio.gather(*(s.get("/api/object", name="Moon") for _ in range(24)))
        statuses = sorted(status for status, _ in answers)
        assert set(statuses) == {200, 429}, statuses
        assert statuses.count(200) >= OBJECT_INFO_AT_ONCE
        busy = next(body for status, body in answers if status == 429)
        assert busy["kind"] == "Busy"


def _parse(text: str) -> datetime:
    return datetime.fromisoformat(text)


async def test_progress_arrival_stop_health_and_push_to_ride_on_the_updates() -> None:
    async with served(sim_mount(rate=10.0), interval_s=0.05) as s, s.http.ws_connect("/ws") as ws:
        assert (await s.post("/api/goto", {"name": HIGH_UP}))[0] == 200
        going = await next_state(ws, lambda st: bool(st["slew"] and st["slew"].get("eta_s")))
        assert going["slew"]["kind"] == "goto"
        assert going["slew"]["target"] == HIGH_UP
        assert going["slew"]["distance_deg"] > 1.0
        arrived = await next_state(ws, lambda st: bool(st["slew"] and not st["slew"]["active"]))
        assert arrived["slew"]["arrived"] is True
        assert arrived["slew"]["distance_deg"] <= ARRIVED_DEG
        words = arrived["health_words"]
        assert words["level"] == "ok"
        assert words["text"].startswith("link OK, ")
        assert words["readings_per_s"] > 1

        assert (await s.post("/api/goto", {"name": "Arcturus"}))[0] == 200
        await next_state(ws, lambda st: bool(st["slew"] and st["slew"].get("target") == "Arcturus"))
        assert (await s.post("/api/abort"))[0] == 200
        stopped = await next_state(ws, lambda st: bool(st["slew"] and not st["slew"]["active"]))
        assert stopped["slew"]["arrived"] is False
        assert stopped["slew"]["distance_deg"] > 1.0  # "stopped 40.2° short of Arcturus"
        # A rate motion after the goto is not the goto: no target is claimed.
        assert (await s.post("/api/move", {"axis": "primary", "rate_deg_s": 1.0}))[0] == 200
        moving = await next_state(ws, lambda st: bool(st["slew"] and st["slew"]["active"]))
        assert moving["slew"] == {"active": True, "kind": "moving", "target": None}
        assert (await s.post("/api/move", {"axis": "primary", "rate_deg_s": 0.0}))[0] == 200

        status, _ = await s.post("/api/pushto", {"name": "vega"})
        assert status == 200
        figures = (await next_state(ws, lambda st: st["pushto"] is not None))["pushto"]
        assert figures["target"] == "Vega"
        assert "° away" in figures["text"]
        assert (await s.post("/api/pushto", {"name": "Vegaa"}))[0] == 404
        assert (await s.post("/api/pushto", {}))[0] == 200
        await next_state(ws, lambda st: st["pushto"] is None)

        await s.mount.disconnect()
        down = await next_state(ws, lambda st: st["health_words"]["level"] == "bad")
        assert down["health_words"]["text"].startswith("link down")
        assert down["slew"] is None  # nothing is claimed about motion while the link is down


async def test_first_run_check_saves_the_site_to_the_settings_file(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    store = SettingsSiteStore(path, saved=False)
    async with served(site_store=store) as s:
        status, setup = await s.get("/api/setup")
        assert status == 200
        assert setup["needed"] is True
        assert setup["where"] == str(path)
        status, error = await s.post("/api/setup", {"latitude_deg": 95, "longitude_deg": 7})
        assert status == 400
        assert "latitude_deg" in error["error"]
        assert not path.exists()  # a refused site is never saved
        body = {
            "latitude_deg": 40.4,
            "longitude_deg": -3.7,
            "elevation_m": 667,
            "utc": "2026-11-24T23:00:00Z",
        }
        status, saved = await s.post("/api/setup", body)
        assert status == 200, saved
        assert saved["saved_to"] == str(path)
        assert saved["time_set"] is True
        assert saved["status"]["needed"] is False
        again = {"latitude_deg": 10.0, "longitude_deg": 10.0}
        status, error = await s.post("/api/setup", again)  # first run only
        assert status == 409
        assert "config set" in error["error"]
        config = load_config(path)
        assert config.site_configured
        assert (config.site.latitude_deg, config.site.longitude_deg) == (40.4, -3.7)
        assert config.site.elevation_m == 667
        assert s.mount.site.latitude_deg == 40.4
        assert abs(s.mount.now() - _parse("2026-11-24T23:00:00+00:00")) < timedelta(minutes=5)
    async with served() as s:  # no store: the page never asks
        status, setup = await s.get("/api/setup")
        assert setup["needed"] is False
        assert setup["can_save"] is False
        status, _ = await s.post("/api/setup", {"latitude_deg": 10.0, "longitude_deg": 10.0})
        assert status == 409
        assert s.mount.site.latitude_deg != 10.0


def test_the_documented_defaults_are_the_codes() -> None:
    """docs/dashboard.md states every limit and default of the panel as the code has it."""
    root = Path(__file__).resolve().parents[2]
    docs = " ".join((root / "docs" / "dashboard.md").read_text(encoding="utf-8").split())
    static = root / "src" / "scopelink" / "web" / "static" / "panel"

    def js(name: str, constant: str) -> float:
        text = (static / name).read_text(encoding="utf-8")
        match = re.search(rf"const {constant} = ([0-9.]+);", text)
        assert match, f"{constant} in {name}"
        return float(match.group(1))

    stated = [
        f"`ARRIVED_DEG` = {ARRIVED_DEG:g}°",
        f"`ENDED_SHOWN_S` = {ENDED_SHOWN_S:g} s",
        f"`WINDOW_S` = {WINDOW_S:g} s",
        f"`LIMIT_STEP_MIN` = {LIMIT_STEP_MIN} min",
        ", ".join(f"{m:g}×" for m in SYNSCAN_FIXED_RATE_MULTIPLES) + " sidereal",
        ", ".join(f"{m:g}×" for m in GENERIC_MULTIPLES) + " sidereal",
        f"default rate {DEFAULT_SYNSCAN_RATE}, "
        f"{SYNSCAN_FIXED_RATE_MULTIPLES[DEFAULT_SYNSCAN_RATE - 1]:g}×",
        f"dead zone of {js('gamepad.js', 'DEAD_ZONE'):g}",
        f"every {js('gamepad.js', 'POLL_MS'):g} ms",
        f"more than {js('firstrun.js', 'CLOCK_WARN_S'):g} s",
        f"at most every {js('info.js', 'REFETCH_MIN_MS') / 1000:g} s",
        f"`OBJECT_INFO_AT_ONCE` = {OBJECT_INFO_AT_ONCE}",
        f"`REST_PER_BUSY` = {REST_PER_BUSY:g}",
    ]
    boundaries = [(-0.833, "day"), *TWILIGHT_BOUNDARIES_DEG[1:]]
    for (boundary, phase), (table_boundary, table_phase) in zip(
        boundaries, TWILIGHT_BOUNDARIES_DEG, strict=True
    ):
        assert phase == table_phase
        assert boundary == pytest.approx(table_boundary, abs=1e-3)
        stated.append(f"−{abs(boundary):g}°")
    for text in stated:
        assert text in docs, text


async def test_north_and_east_move_the_sim_north_and_east_on_both_sides_of_the_pier() -> None:
    """The pad's mapping against the real simulated mount: on either side of the pier (after a
    goto east of the meridian the tube is flipped), N raises the declination, E the RA."""
    mount = sim_mount(rate=100.0)
    await mount.connect()
    try:
        sides = set()
        for name in ("Capella", "Regulus"):  # west, then east of the meridian at START
            await mount.goto_object(name)
            await mount.wait_for_slew(timeout_s=10)
            state = await mount.refresh()
            sides.add(state.pier_side)
            pad = plain_pad_json(mount, state)
            for direction, coordinate in (("up", "dec_j2000_deg"), ("left", "ra_j2000_hours")):
                axis = MountAxis[pad[direction]["axis"].upper()]
                sign = pad[direction]["sign"]
                before = getattr(await mount.refresh(), coordinate)
                await mount.move_axis(axis, sign * 0.5)
                await asyncio.sleep(0.05)
                after = getattr(await mount.refresh(), coordinate)
                await mount.move_axis(axis, 0.0)
                assert after > before, (name, state.pier_side, direction)
        assert sides == {PierSide.EAST, PierSide.WEST}
    finally:
        await mount.disconnect()
