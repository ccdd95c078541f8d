"""Helpers for the custom tracking-rate tests: where a driver's rate loop started, Alpaca in
front of a driver, how low a motion the guard stopped went."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from datetime import datetime
from pathlib import Path

from alpaca.telescope import Telescope

from scopelink.mount import Mount
from scopelink.mount.rates import RateLoopStatistics
from scopelink.servers.alpaca import AlpacaServer
from tests.support.alpaca import blocking


def loop_anchor(
    statistics: RateLoopStatistics | None, epoch: datetime
) -> tuple[RateLoopStatistics, float, float, float]:
    """The loop's statistics and its start: seconds after ``epoch`` (the simulator's clock) and
    the J2000 RA (h) and Dec (°) it read there, from which its target is integrated."""
    assert statistics is not None
    assert statistics.started_at is not None
    assert statistics.anchor is not None
    ra0, dec0 = statistics.anchor
    return statistics, (statistics.started_at - epoch).total_seconds(), ra0, dec0


@asynccontextmanager
async def alpaca_telescope(mount: Mount, state_dir: Path) -> AsyncIterator[Telescope]:
    """An Alpaca server on a free port of 127.0.0.1 in front of ``mount`` (watched meanwhile),
    and alpyca's Telescope on it, connected."""
    server = AlpacaServer(mount, host="127.0.0.1", port=0, discovery_port=None, state_dir=state_dir)
    async with server, mount.watching():
        telescope = Telescope(f"127.0.0.1:{server.port}", 0)
        await blocking(lambda: setattr(telescope, "Connected", True))
        yield telescope


async def lowest_altitude(
    running: Callable[[], bool], altitude: Callable[[], float], timeout_s: float = 10.0
) -> float:
    """The lowest ``altitude()`` while ``running()`` (at most ``timeout_s``), and for a second
    (real) after: a motion the guard stopped stays stopped. Fails if it still runs."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout_s
    lowest = 90.0
    while running() and loop.time() < deadline:
        await asyncio.sleep(0.05)
        lowest = min(lowest, altitude())
    assert not running(), "the guard did not stop it"
    for _ in range(20):
        await asyncio.sleep(0.05)
        lowest = min(lowest, altitude())
    return lowest
