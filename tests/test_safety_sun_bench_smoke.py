"""The Sun benchmark runs (one rate) and the guard keeps the mount outside the zone."""

from __future__ import annotations

import asyncio

import pytest
from bench.safety_sun import main, zone_goal

from tests.bench_support import assert_provenance


async def test_sun_benchmark_quick_run_stays_outside_the_zone(
    capsys: pytest.CaptureFixture[str],
) -> None:
    (result,) = await asyncio.to_thread(main, ["--quick"])
    assert result.stops == 1
    assert result.clearance_deg > 0.0, result
    assert result.closest_deg < result.start_distance_deg - 1.0  # it did move towards the Sun
    out = capsys.readouterr().out
    assert_provenance(out)
    assert out.splitlines()[-1].startswith(
        "goal: outside the Sun's zone (clearance >= 0) in every run: PASS"
    )


def test_the_goal_line_checks_every_run() -> None:
    """One run inside the zone among many is a miss, whatever the others did."""
    assert zone_goal([4.0, -0.2, 1.0]).split(": ")[-1] == "MISS (1 of 3 inside, worst -0.20°)"
