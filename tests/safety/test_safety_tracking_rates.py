"""Custom tracking rates are rate motions the horizon guard stops (issue #16): the SynScan
driver's PC loop heading down is stopped above the configured horizon, through the real emulator."""

from __future__ import annotations

import asyncio

import pytest

from scopelink.astro import observed_to_j2000
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import LimitError, Limits
from scopelink.mount.rates import TrackingRates
from scopelink.sim import SimClock
from tests.support.rates import lowest_altitude
from tests.support.synscan_driver import START, rig

HORIZON_DEG = 30.0


def _running(mount: SynScanMount) -> bool:
    return mount.custom_rates_running


async def test_a_custom_rate_towards_the_horizon_is_stopped_by_the_guard() -> None:
    async with rig("tcp", clock=SimClock.accelerated(10.0, START)) as r:
        r.mount.limits = Limits(horizon_deg=HORIZON_DEG)
        ra, dec = observed_to_j2000(34.0, 180.0, r.mount.now(), r.mount.site)
        await r.mount.goto_equatorial(ra, dec)
        await r.mount.wait_for_slew(timeout_s=15.0)
        async with r.mount.watching():
            await r.mount.set_tracking_rates(0.0, -600.0)  # south, on the meridian: down
            assert _running(r.mount)
            lowest = await lowest_altitude(
                lambda: _running(r.mount), lambda: r.sim.observed_at(r.sim.elapsed())[0]
            )
        assert lowest >= HORIZON_DEG - 0.05, f"went down to {lowest:.3f}°"
        assert lowest < HORIZON_DEG + 2.0, f"stopped at {lowest:.3f}°: did it move at all?"
        assert not r.mount.guard.rate_motions
        print(f"custom rate towards the horizon: lowest {lowest:.3f}° (horizon {HORIZON_DEG}°)")


async def test_a_rate_update_heading_down_at_the_horizon_is_refused_and_changes_nothing() -> None:
    """The running loop takes new rates without a restart (issue #16), but they pass the guard's
    check first: at the horizon, rates heading down are refused and the loop goes on as it was."""
    async with rig("tcp", clock=SimClock.accelerated(10.0, START)) as r:
        r.mount.limits = Limits(horizon_deg=HORIZON_DEG)
        ra, dec = observed_to_j2000(HORIZON_DEG + 0.1, 165.0, r.mount.now(), r.mount.site)
        await r.mount.goto_equatorial(ra, dec)
        await r.mount.wait_for_slew(timeout_s=15.0)
        async with r.mount.watching():
            await r.mount.set_tracking_rates(0.0, 2.0)  # south-east, rising: slowly up
            assert _running(r.mount)
            before = r.sim.observed_at(r.sim.elapsed())[0]
            with pytest.raises(LimitError, match="horizon"):
                await r.mount.set_tracking_rates(0.0, -600.0)
            assert _running(r.mount), "the refusal ended the loop"
            assert r.mount.tracking_rates == TrackingRates(0.0, 2.0)
            assert r.mount.rate_updates == 0
            await asyncio.sleep(1.0)  # 10 s of the mount's: -600″/s would be 1.7° down
            after = r.sim.observed_at(r.sim.elapsed())[0]
        assert after >= before - 0.01, f"went down from {before:.3f}° to {after:.3f}°"
        print(f"rate update towards the horizon refused at {before:.3f}°, then {after:.3f}°")
