"""The dashboard benchmark still runs and prints its figures (so the benchmark code cannot rot)."""

from __future__ import annotations

import pytest

from tests.support.quick_bench import assert_provenance, run_quick_bench


@pytest.mark.timeout(60)
def test_quick_dashboard_benchmark_prints_its_figures() -> None:
    result = run_quick_bench("bench.web_dashboard", timeout_s=60)
    assert_provenance(result.stdout)
    lines = result.stdout.splitlines()
    assert "each row the best of 1 round(s)" in lines[2], result.stdout
    assert any(line.startswith("state + chart objects") for line in lines), result.stdout
    assert any(line.strip().startswith("10 pages") for line in lines), result.stdout
    assert any("x a 9600-baud line" in line for line in lines), result.stdout
    goal = lines[-1]
    assert goal.startswith("goal: server CPU per open page <= 0.05 core, every row: "), goal
    assert ("PASS" in goal) != ("MISS" in goal), goal


@pytest.mark.timeout(60)
def test_quick_object_flood_benchmark_prints_its_goal() -> None:
    result = run_quick_bench("bench.web_object_flood", timeout_s=60)
    assert_provenance(result.stdout)
    lines = result.stdout.splitlines()
    assert any(line.startswith("poller unloaded ") for line in lines), result.stdout
    for kind in ("object", "live"):
        assert any(line.startswith(f"flood {kind}") for line in lines), result.stdout
    (goal,) = (line for line in lines if line.startswith("goal "))
    assert goal.split(": ")[1].split()[0] in ("PASS", "MISS"), goal
