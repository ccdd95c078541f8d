"""Issue #14 part 1: what raises the poll rate, what keeps it capped, and the settings.

Real drivers against real emulators on TCP with no wire pacing (instant devices), as in
``test_polling_demand.py``.
"""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

import aiohttp
import pytest

from scopelink.astro import Site
from scopelink.cli.config import ConfigError, parse_config
from scopelink.cli.config_command import EXAMPLE_CONFIG, show
from scopelink.cli.mount_session import DeviceCommand, open_device
from scopelink.drivers.open import parse_device
from scopelink.mount import InvalidValueError, MountAxis
from scopelink.mount.polling import (
    DEFAULT_DEMAND_HOLD_S,
    DEFAULT_IDLE_POLL_S,
    DEFAULT_MAX_POLL_BAUD,
    PollPolicy,
)
from scopelink.sim import EQ6, SimulatedMount
from scopelink.web import Dashboard
from tests.support.polling import LINE_BYTES_PER_S, skytracker_driver, synscan_driver

DOCS = Path(__file__).resolve().parents[2] / "docs"
SITE = Site(latitude_deg=48.0, longitude_deg=11.0)


async def polls_in(driver: object, seconds: float) -> int:
    poller = driver.poller  # type: ignore[attr-defined]
    before = poller.polls
    await asyncio.sleep(seconds)
    return int(poller.polls - before)


async def polls_come(driver: object, count: int, within_s: float) -> None:
    """Return once ``count`` more polls have been made; fail if that takes ``within_s``. Full
    rate makes them in a fraction of it (an instant device: ~40 a second); the idle rate
    (one a second) cannot. Waiting for them, not counting them in a fixed window, keeps a
    loaded machine's stall from failing the test."""
    poller = driver.poller  # type: ignore[attr-defined]
    target = poller.polls + count
    loop = asyncio.get_running_loop()
    ends = loop.time() + within_s
    while poller.polls < target and loop.time() < ends:  # noqa: ASYNC110 (looked at: a wait
        await asyncio.sleep(0.01)  # on the state would add demand of its own)
    if poller.polls >= target:
        return
    raise AssertionError(f"{count} polls not made within {within_s} s")


async def test_a_10_hz_reader_gets_readings_no_older_than_its_period() -> None:
    async with synscan_driver() as driver, driver.watching():
        await asyncio.sleep(0.3)
        ages = []
        for _ in range(20):
            ages.append(driver.fresh_state().position_age_s())
            await asyncio.sleep(0.1)
        # The first read may find an idle-rate reading (within stale_after_s); it wakes the poller.
        assert ages[0] <= driver.stale_after_s
        # At full rate a reading is ~10 ms old when read (20 ms at most); at the idle rate (the
        # defect) ages climb towards 1 s between polls. The median holds the promise of one
        # poll period; the worst leaves room for a stall of a loaded machine.
        later = sorted(ages[1:])
        assert later[len(later) // 2] <= 0.1, ages
        assert later[-1] <= 0.5, ages
        # The reader stops: back to the idle rate once demand_hold_s has passed.
        await asyncio.sleep(DEFAULT_DEMAND_HOLD_S + 0.2)
        assert await polls_in(driver, 1.0) <= 2


async def test_an_idle_mount_is_never_stale_even_with_a_short_stale_after() -> None:
    async with synscan_driver() as driver, driver.watching():
        driver.stale_after_s = 0.4  # the idle period becomes 0.2 s
        loop = asyncio.get_running_loop()
        ends = loop.time() + 1.5
        worst = 0.0
        while loop.time() < ends:  # looks at the cache without reading (no demand)
            worst = max(worst, driver.state.position_age_s())
            await asyncio.sleep(0.02)
        # The idle period is half of stale_after_s (0.2 s): the worst age ~0.2-0.3 s, never
        # the default period's 1 s. (0.7, not 0.4: a stall of a loaded machine adds to it.)
        assert 0.1 < worst <= 0.7, worst


async def test_a_goto_is_polled_at_full_rate_with_nobody_reading() -> None:
    async with synscan_driver() as driver, driver.watching():
        await asyncio.sleep(0.3)
        await driver.goto_horizontal(60.0, 120.0)
        await polls_come(driver, 10, within_s=3.0)  # idle: 3 at most
        assert driver.state.slewing
        await driver.abort()


async def test_a_states_consumer_holds_the_full_rate() -> None:
    async with synscan_driver() as driver:
        await asyncio.sleep(0.3)
        readings = 0
        loop = asyncio.get_running_loop()
        ends = loop.time() + 3.0  # ten readings at the idle rate would take 10 s
        async for state in driver.states():  # what the horizon guard does near a limit
            readings += 1
            if readings >= 10 or loop.time() > ends or not state.connected:
                break
        assert readings >= 10, readings


async def test_a_rate_motion_started_while_idle_is_seen_at_once_and_polled_at_full_rate() -> None:
    async with synscan_driver() as driver, driver.watching():
        await asyncio.sleep(0.3)
        await driver.move_axis(MountAxis.PRIMARY, 1.0)
        # Two polls well within the idle period (1 s): it was not waited out.
        await polls_come(driver, 2, within_s=0.7)
        await polls_come(driver, 10, within_s=3.0)
        await driver.move_axis(MountAxis.PRIMARY, 0.0)


async def test_a_sky_tracker_reader_stays_within_the_line_cap(tmp_path: Path) -> None:
    async with skytracker_driver(tmp_path) as driver, driver.watching():
        link = driver._line.link if driver._line else None
        assert link is not None
        loop = asyncio.get_running_loop()
        driver.fresh_state()
        await asyncio.sleep(0.2)
        received, sent, started = link.bytes_read, link.bytes_written, loop.time()
        ends = started + 1.0
        polls = driver.poller.polls
        while loop.time() < ends:
            driver.fresh_state()
            await asyncio.sleep(0.05)
        elapsed = loop.time() - started
        busier = max(link.bytes_read - received, link.bytes_written - sent) / elapsed
        assert busier <= LINE_BYTES_PER_S * 1.05, busier
        assert driver.poller.polls - polls >= 10, "not at full rate while read"


async def test_a_lower_cap_slows_full_rate_polls() -> None:
    async with synscan_driver() as driver, driver.watching():
        driver.poll_policy = PollPolicy(max_poll_baud=2400)  # 240 B/s: ~12 L-e polls a second
        driver.fresh_state()
        await asyncio.sleep(0.3)
        received = driver.wire.statistics.bytes_received
        loop = asyncio.get_running_loop()
        started = loop.time()
        while loop.time() < started + 1.0:
            driver.fresh_state()
            await asyncio.sleep(0.05)
        rate = (driver.wire.statistics.bytes_received - received) / (loop.time() - started)
        assert 120 <= rate <= 240 * 1.05, rate


def test_the_policy_refuses_values_outside_its_ranges() -> None:
    for bad in (
        {"idle_poll_s": 0.0},
        {"idle_poll_s": 3.0},
        {"idle_poll_s": float("nan")},
        {"demand_hold_s": -1.0},
        {"max_poll_baud": 0},
        {"max_poll_baud": 9600.5},
        {"max_poll_baud": True},
    ):
        with pytest.raises(ValueError, match=next(iter(bad))):
            PollPolicy(**bad)
    mount = SimulatedMount(EQ6, site=SITE)
    with pytest.raises(InvalidValueError):
        mount.poll_policy = "fast"  # type: ignore[assignment]
    assert PollPolicy().idle_period_s(0.4) == 0.2


def test_the_file_sets_the_policy_and_refuses_bad_values(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    assert parse_config("", path).poll_policy == PollPolicy()
    text = "[readings]\nidle_poll_s = 0.5\ndemand_hold_s = 10\nmax_poll_baud = 19200\n"
    config = parse_config(text, path)
    assert config.poll_policy == PollPolicy(0.5, 10.0, 19200)
    shown = show(config)
    assert "idle_poll_s = 0.5" in shown
    assert "max_poll_baud = 19200" in shown
    for key, value in (
        ("idle_poll_s", "5"),
        ("idle_poll_s", '"1"'),
        ("demand_hold_s", "0"),
        ("max_poll_baud", "9600.5"),
        ("max_poll_baud", "1200"),
    ):
        with pytest.raises(ConfigError, match=rf"readings\.{key}"):
            parse_config(f"[readings]\n{key} = {value}\n", path)


async def test_device_commands_apply_the_policy(tmp_path: Path) -> None:
    config = parse_config("[readings]\nidle_poll_s = 0.25\n", tmp_path / "config.toml")
    mount = await open_device(DeviceCommand(parse_device("sim"), SITE, config, 1.0, None))
    try:
        assert mount.poll_policy.idle_poll_s == 0.25
    finally:
        await mount.disconnect()


def test_the_docs_and_the_example_state_the_defaults_the_code_has() -> None:
    api = (DOCS / "mount-api.md").read_text(encoding="utf-8")
    assert f"| `readings.idle_poll_s` | **{DEFAULT_IDLE_POLL_S:g} s** |" in api
    assert f"| `readings.demand_hold_s` | **{DEFAULT_DEMAND_HOLD_S:g} s** |" in api
    assert f"| `readings.max_poll_baud` | **{DEFAULT_MAX_POLL_BAUD}** |" in api
    cli = (DOCS / "cli.md").read_text(encoding="utf-8")
    assert f"`readings.idle_poll_s` (default **{DEFAULT_IDLE_POLL_S:g} s**)" in cli
    assert f"`readings.demand_hold_s` (default **{DEFAULT_DEMAND_HOLD_S:g} s**)" in cli
    assert f"`readings.max_poll_baud` (default **{DEFAULT_MAX_POLL_BAUD}**)" in cli
    for key, value in (
        ("idle_poll_s", DEFAULT_IDLE_POLL_S),
        ("demand_hold_s", DEFAULT_DEMAND_HOLD_S),
        ("max_poll_baud", DEFAULT_MAX_POLL_BAUD),
    ):
        assert re.search(rf"^{key} = {value}\b", cli, re.MULTILINE), key
        assert re.search(rf"# {key} = {value}\b", EXAMPLE_CONFIG), key


async def test_an_open_dashboard_page_raises_the_rate_and_its_departure_lowers_it() -> None:
    async with synscan_driver() as driver, Dashboard(driver, port=0) as dashboard:
        async with aiohttp.ClientSession() as http, http.ws_connect(f"{dashboard.url}ws") as ws:
            await ws.receive()  # the hello: the page's updates start
            await polls_come(driver, 10, within_s=3.0)
        await asyncio.sleep(DEFAULT_DEMAND_HOLD_S + 0.3)  # the page has gone
        assert driver.poller.watchers == 0 or await polls_in(driver, 1.0) <= 2


async def test_stopping_the_poller_passes_a_cancellation_of_the_caller_on() -> None:
    """A poll still finishing its exchange when ``stop`` waits for it: cancelling the task that
    called ``stop`` must cancel it, not be swallowed (a shutdown hung 120 s on this)."""
    from datetime import UTC, datetime

    from scopelink.mount import MountState
    from scopelink.mount.polling import StateBroadcast, StatePoller

    started = asyncio.Event()

    async def refresh() -> MountState:
        started.set()
        try:
            await asyncio.sleep(10.0)
        except asyncio.CancelledError:
            await asyncio.sleep(0.3)  # the exchange in flight completes first, as a driver's does
            raise
        raise AssertionError("not reached")

    state = MountState(read_at=datetime(2026, 1, 1, tzinfo=UTC))
    poller = StatePoller(
        refresh, lambda: True, lambda _: None, StateBroadcast(state), interval_s=0.1, retry_s=0.1
    )
    async with poller.watching():
        await started.wait()
        stopping = asyncio.create_task(poller.stop())
        await asyncio.sleep(0.05)
        stopping.cancel()
        with pytest.raises(asyncio.CancelledError):
            await stopping
        assert stopping.cancelled()
