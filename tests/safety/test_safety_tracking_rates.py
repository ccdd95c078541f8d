"""Custom tracking rates are rate motions the horizon guard stops (issue #16): the SynScan
driver's PC loop heading down (equatorial or alt-az) is stopped above the configured horizon, and a
rate update heading down at it is refused, through the real emulator."""

from __future__ import annotations

import asyncio

import pytest

from scopelink.astro import observed_to_j2000
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import LimitError, Limits, TrackingMode
from scopelink.mount.rates import TrackingRates
from scopelink.servers.synscan import SynScanConfig
from scopelink.sim import AZ_GTI, SimClock
from tests.support.rates import lowest_altitude
from tests.support.synscan_driver import START, Rig, rig

HORIZON_DEG = 30.0


def _running(mount: SynScanMount) -> bool:
    return mount.custom_rates_running


async def _lowest_under_a_rate_heading_down(r: Rig, alt_deg: float, az_deg: float) -> float:
    """From ``alt_deg``/``az_deg``, custom rates of -600″/s of Dec (down there): the lowest
    altitude the simulator reached before the guard stopped the loop, and after."""
    r.mount.limits = Limits(horizon_deg=HORIZON_DEG)
    ra, dec = observed_to_j2000(alt_deg, az_deg, r.mount.now(), r.mount.site)
    await r.mount.goto_equatorial(ra, dec)
    await r.mount.wait_for_slew(timeout_s=15.0)
    async with r.mount.watching():
        await r.mount.set_tracking_rates(0.0, -600.0)
        assert _running(r.mount)
        lowest = await lowest_altitude(
            lambda: _running(r.mount), lambda: r.sim.observed_at(r.sim.elapsed())[0]
        )
    assert lowest >= HORIZON_DEG - 0.05, f"went down to {lowest:.3f}°"
    assert lowest < HORIZON_DEG + 1.0, f"stopped at {lowest:.3f}°: did it move at all?"
    assert not r.mount.guard.rate_motions
    return lowest


async def test_a_custom_rate_towards_the_horizon_is_stopped_by_the_guard() -> None:
    async with rig("tcp", clock=SimClock.accelerated(10.0, START)) as r:
        lowest = await _lowest_under_a_rate_heading_down(r, 34.0, 180.0)  # south, the meridian
        print(f"custom rate towards the horizon: lowest {lowest:.3f}° (horizon {HORIZON_DEG}°)")


async def test_a_rate_update_heading_down_at_the_horizon_is_refused_and_changes_nothing() -> None:
    """The running loop takes new rates without a restart (issue #16), but they pass the guard's
    check first: at the horizon, rates heading down are refused and the loop goes on as it was."""
    async with rig("tcp", clock=SimClock.accelerated(10.0, START)) as r:
        r.mount.limits = Limits(horizon_deg=HORIZON_DEG)
        ra, dec = observed_to_j2000(HORIZON_DEG + 1.0, 165.0, r.mount.now(), r.mount.site)
        await r.mount.goto_equatorial(ra, dec)
        await r.mount.wait_for_slew(timeout_s=15.0)
        async with r.mount.watching():
            await r.mount.set_tracking_rates(0.0, 2.0)  # south-east, rising: slowly up
            assert _running(r.mount)
            # The horizon brought up to just below the tube (landed and settled: no goto's
            # last readings for the guard to judge), so the mount is at the limit now.
            state = await r.mount.refresh()
            assert state.alt_deg is not None
            r.mount.limits = Limits(horizon_deg=state.alt_deg - 0.1)
            before = r.sim.observed_at(r.sim.elapsed())[0]
            with pytest.raises(LimitError, match="horizon"):
                await r.mount.set_tracking_rates(0.0, -600.0)
            assert _running(r.mount), "the refusal ended the loop"
            assert r.mount.tracking_rates == TrackingRates(0.0, 2.0)
            assert r.mount.rate_updates == 0
            await asyncio.sleep(1.0)  # 10 s of the mount's: -600″/s would be 1.7° down
            after = r.sim.observed_at(r.sim.elapsed())[0]
        assert after >= before - 0.01, f"went down from {before:.3f}° to {after:.3f}°"
        print(
            f"rate update towards the horizon ({r.mount.limits.horizon_deg:.3f}°) refused at "
            f"{before:.3f}°, then {after:.3f}°"
        )


async def test_the_altaz_loop_heading_down_is_stopped_by_the_guard() -> None:
    """An alt-az SynScan mount's loop drives the altitude axis itself: custom rates taking the
    tube down are a rate motion the guard stops above the horizon, and tracking is handed back."""
    async with rig(
        "tcp",
        model=AZ_GTI,
        config=SynScanConfig(model=165),
        clock=SimClock.accelerated(10.0, START),
    ) as r:
        lowest = await _lowest_under_a_rate_heading_down(r, 32.0, 90.0)  # east: Dec falling
        assert r.sim.tracking is TrackingMode.ALT_AZ  # handed back to the hand control
        print(f"alt-az loop towards the horizon: lowest {lowest:.3f}° (horizon {HORIZON_DEG}°)")
