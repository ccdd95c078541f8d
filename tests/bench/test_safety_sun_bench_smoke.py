"""The Sun benchmark runs (one rate) and the guard keeps the mount outside the zone."""

from __future__ import annotations

from bench.safety_sun import zone_goal

from tests.support.quick_bench import assert_provenance, run_quick_bench


def test_sun_benchmark_quick_run_stays_outside_the_zone() -> None:
    printed = run_quick_bench("bench.safety_sun", timeout_s=60).stdout
    assert_provenance(printed)
    # | rate °/s | start distance° | closest° | clearance° | guard stops |: one row, the 2°/s run
    (row,) = [line for line in printed.splitlines() if line.startswith("| 2.00 |")]
    start_distance_deg, closest_deg, clearance_deg, stops = (
        float(cell) for cell in row.strip("| ").split(" | ")[1:]
    )
    assert stops == 1
    assert clearance_deg > 0.0, printed
    assert closest_deg < start_distance_deg - 1.0  # it did move towards the Sun
    assert printed.splitlines()[-1].startswith(
        "goal: outside the Sun's zone (clearance >= 0) in every run: PASS"
    )


def test_the_goal_line_checks_every_run() -> None:
    """One run inside the zone among many is a miss, whatever the others did."""
    assert zone_goal([4.0, -0.2, 1.0]).split(": ")[-1] == "MISS (1 of 3 inside, worst -0.20°)"
