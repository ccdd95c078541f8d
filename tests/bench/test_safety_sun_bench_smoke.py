"""The Sun benchmark runs (one rate) and the guard keeps the mount outside the zone."""

from __future__ import annotations

import asyncio

from bench.safety_sun import main


async def test_sun_benchmark_quick_run_stays_outside_the_zone() -> None:
    (result,) = await asyncio.to_thread(main, ["--quick"])
    assert result.stops == 1
    assert result.clearance_deg > 0.0, result
    assert result.closest_deg < result.start_distance_deg - 1.0  # it did move towards the Sun
