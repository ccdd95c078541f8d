"""The Sky Tracker's custom-rate loop is a rate motion the horizon guard stops (issue #16): timed
presses heading down are stopped above the configured horizon, and refused at it, through the
real emulator."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from scopelink.drivers.skytracker import SkyTrackerMount
from scopelink.mount import LimitError, Limits, TrackingMode
from tests.support.rates import lowest_altitude
from tests.support.skytracker_driver import eventually, rig

HORIZON_DEG = 30.0


def _running(mount: SkyTrackerMount) -> bool:
    return mount.custom_rates_running


async def test_custom_rates_towards_the_horizon_are_stopped_by_the_guard(tmp_path: Path) -> None:
    limits = Limits(horizon_deg=HORIZON_DEG)
    async with rig(tmp_path, "tcp", clock_rate=10.0, limits=limits) as r:
        r.point(30.45, 180.0)
        await r.driver.set_tracking(TrackingMode.ALT_AZ)
        await eventually(lambda: all(axis.rate != 0.0 for axis in r.sim.axes))
        async with r.driver.watching():
            await r.driver.set_tracking_rates(0.0, -100.0)  # south, on the meridian: down
            assert _running(r.driver)
            lowest = await lowest_altitude(
                lambda: _running(r.driver), lambda: r.sim.observed_at(r.sim.elapsed())[0]
            )
            assert r.emulator.tracker.remote_pressed == 0
            # At the horizon, rates heading further down are refused before anything is pressed.
            r.point(30.1, 100.0)  # east, rising: tracking may go on here
            await asyncio.sleep(0.3)  # the jump there reads as a fall: the guard stops tracking
            await r.driver.set_tracking(TrackingMode.ALT_AZ)
            await r.driver.refresh()
            with pytest.raises(LimitError, match="configured horizon"):
                await r.driver.set_tracking_rates(0.0, -100.0)
            assert not _running(r.driver)
            assert r.emulator.tracker.remote_pressed == 0
        assert lowest >= HORIZON_DEG - 0.05, f"went down to {lowest:.3f}°"
        assert lowest < 30.4, f"stopped at {lowest:.3f}°: did it move at all?"
        assert not r.driver.guard.rate_motions
        print(f"Sky Tracker custom rate towards the horizon: lowest {lowest:.3f}°")
