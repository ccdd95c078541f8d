"""The reconnect benchmark still runs and prints its table (so the benchmark code cannot rot)."""

from __future__ import annotations

from tests.support.quick_bench import run_quick_bench


def test_quick_reconnect_benchmark_prints_its_table() -> None:
    result = run_quick_bench("bench.reconnect", timeout_s=120)
    lines = result.stdout.splitlines()
    assert lines[1].split() == ["driver", "fault", "refused", "down", "back"]
    assert [line.split()[:2] for line in lines[2:]] == [
        ["synscan", "close"],
        ["synscan", "stall"],
        ["skytracker", "close"],
        ["skytracker", "stall"],
    ]
