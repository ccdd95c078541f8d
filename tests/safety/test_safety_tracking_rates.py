"""Custom tracking rates are rate motions the horizon guard stops (issue #16): the SynScan
driver's PC loop heading down is stopped above the configured horizon, through the real emulator."""

from __future__ import annotations

from scopelink.astro import observed_to_j2000
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import Limits
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
