"""The safety benchmark runs (one rate) and the guard keeps the mount above the horizon."""

from __future__ import annotations

import pytest
from bench.safety_guard import HORIZON_DEG, horizon_goal, main


async def test_the_guard_benchmark_runs_and_stops_above_the_horizon(
    capsys: pytest.CaptureFixture[str],
) -> None:
    (result,) = await main((2.0,), lead_deg=0.5)
    assert result.stops == 1
    assert result.lowest_alt_deg > HORIZON_DEG - 0.5
    assert result.lowest_alt_deg < result.start_alt_deg - 1.0  # it did move down
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].endswith("each rate the worst of 1 run(s)"), lines
    assert lines[-1].startswith("goal: above the horizon (clearance >= 0) in every run: "), lines


def test_the_goal_line_checks_every_run() -> None:
    """One run below the horizon among many is a miss, whatever the others did."""
    assert horizon_goal([1.0, 2.5, 0.0]).split(": ")[-1] == "PASS (0 of 3 below, worst +0.00°)"
    assert horizon_goal([1.0, -0.01, 3.0]).split(": ")[-1] == "MISS (1 of 3 below, worst -0.01°)"
