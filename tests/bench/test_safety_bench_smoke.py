"""The safety benchmark runs (one rate) and the guard keeps the mount above the horizon."""

from __future__ import annotations

from bench.safety_guard import HORIZON_DEG, main


async def test_the_guard_benchmark_runs_and_stops_above_the_horizon() -> None:
    (result,) = await main((2.0,), lead_deg=0.5)
    assert result.stops == 1
    assert result.lowest_alt_deg > HORIZON_DEG - 0.5
    assert result.lowest_alt_deg < result.start_alt_deg - 1.0  # it did move down
