"""The Sun avoidance zone on a noisy link (issue #11, parts 1 and 3): with 30 % of the device's
replies garbled or lost, a full-speed motion towards the Sun never enters the zone.

The runs are the benchmark's (``bench.safety_sun.run_once``): the SynScan driver (the spec's 5 s
timeout) on TCP (9600-baud pacing) to the SynScan emulator, whose simulated AZ-GTi has no zone of
its own; scopelink's zone is 15°; the azimuth axis at full speed towards the Sun along its
altitude. The true distance is the simulated mount's own, sampled every 2 ms. Without the blind
budget for the Sun (the guard judging only the readings it gets) the tube ran into the zone.
"""

from __future__ import annotations

import pytest
from bench.safety_sun import RADIUS_DEG, run_once

from scopelink.servers.faults import FaultKind


@pytest.mark.parametrize("kind", [FaultKind.MALFORMED, FaultKind.DROP])
async def test_a_full_speed_motion_towards_the_sun_never_enters_the_zone_on_a_noisy_link(
    kind: FaultKind,
) -> None:
    for seed in range(2):
        result = await run_once(3.34, noise=(kind, 0.30, seed))
        assert result.closest_deg >= RADIUS_DEG, (seed, result)
