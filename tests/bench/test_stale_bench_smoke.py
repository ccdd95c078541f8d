"""The reconnect benchmark still runs and prints its table (so the benchmark code cannot rot)."""

from __future__ import annotations

from tests.support.quick_bench import assert_provenance, run_quick_bench


def test_quick_reconnect_benchmark_prints_its_table() -> None:
    result = run_quick_bench("bench.reconnect", timeout_s=120)
    assert_provenance(result.stdout)
    lines = result.stdout.splitlines()[2:]
    assert lines[1].split() == ["driver", "fault", "refused", "down", "back"]
    rows = [["synscan", "close"], ["synscan", "stall"], ["skytracker", "close"]]
    rows.append(["skytracker", "stall"])
    assert [line.split()[:2] for line in lines[2:6]] == rows
    # One verdict per row on the reconnect promise, checked on every trial.
    assert [line.split(":")[0].split()[1:3] for line in lines[6:]] == rows, result.stdout
    assert all(line.startswith("goal ") for line in lines[6:]), result.stdout
    assert all(": PASS (" in line or ": MISS (" in line for line in lines[6:]), result.stdout
