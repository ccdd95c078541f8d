"""Issue #14 part 1: demand-driven polling, both drivers, against real emulators on TCP.

With nobody reading, a watched mount is polled at the slow idle rate; an instant device (the
SynScan emulator unpaced, the Sky Tracker emulator unpaced) is never polled faster than the
configured maximum line rate; a reader, a slew, a rate motion raise the rate at once; an idle mount
is never reported stale.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

from tests.support.polling import LINE_BYTES_PER_S, skytracker_driver, synscan_driver


async def test_an_unread_synscan_is_polled_at_the_idle_rate() -> None:
    async with synscan_driver() as driver, driver.watching():
        await asyncio.sleep(0.3)  # the first polls after connect
        stats = driver.wire.statistics
        exchanges, polls = stats.exchanges, driver.poller.polls
        await asyncio.sleep(2.0)
        made = stats.exchanges - exchanges
        # Idle: one poll a second (2 exchanges, 4 on a full read); today thousands.
        assert driver.poller.polls - polls <= 3, driver.poller.polls - polls
        assert made <= 10, made
        assert not driver.state.slewing


async def test_an_unread_sky_tracker_is_polled_at_the_idle_rate(tmp_path: Path) -> None:
    async with skytracker_driver(tmp_path) as driver, driver.watching():
        await asyncio.sleep(0.3)
        polls = driver.poller.polls
        await asyncio.sleep(2.0)
        assert driver.poller.polls - polls <= 3, driver.poller.polls - polls


async def test_a_reader_never_drives_an_instant_device_past_the_line_rate() -> None:
    async with synscan_driver() as driver, driver.watching():
        stats = driver.wire.statistics
        loop = asyncio.get_running_loop()
        driver.fresh_state()  # a reader: full rate from now on
        await asyncio.sleep(0.2)
        received, started = stats.bytes_received, loop.time()
        ends = started + 1.0
        while loop.time() < ends:
            driver.fresh_state()
            await asyncio.sleep(0.05)
        rate = (stats.bytes_received - received) / (loop.time() - started)
        assert rate <= LINE_BYTES_PER_S * 1.05, rate
        assert rate >= LINE_BYTES_PER_S * 0.5, f"not at full rate while read: {rate:.0f} B/s"
