"""A stop while following must stop (issue #16, docs/tracking.md "Tried to break it"): an
abort from any front end (the dashboard's stop, LX200 ``:Q#``, Alpaca ``AbortSlew``) ends the
SynScan driver's rate loop; the follower used to start it again at its next update, so the
mount moved on after the observer had pressed stop. The SynScan emulator over TCP, 20x clock."""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime

from scopelink.astro.targets import solar_system_target
from scopelink.mount.follow import ABORTED, TargetFollower
from scopelink.sim import SimClock
from tests.support.synscan_driver import MADRID, rig


async def test_an_abort_while_following_ends_following_and_nothing_restarts() -> None:
    moon = solar_system_target("Moon", MADRID)
    start = datetime(2026, 3, 1, 23, 0, tzinfo=UTC)
    async with rig("tcp", clock=SimClock.accelerated(20.0, start)) as r:
        follower = TargetFollower(r.mount, moon, interval_s=2.0)
        task = asyncio.create_task(follower.run(duration_s=3600.0))
        await r.mount.wait_for(lambda _: r.mount.custom_rates_running, timeout_s=30.0)
        await r.mount.abort()  # what every front end's stop does
        result = await asyncio.wait_for(task, 10.0)
        assert result.reason.startswith(ABORTED), result.reason
        assert r.mount.tracking_rates.zero
        for _ in range(20):  # 20 s of the mount's clock: ten of the follower's intervals
            assert not r.mount.custom_rates_running, "the rate loop started again after a stop"
            await asyncio.sleep(0.05)
