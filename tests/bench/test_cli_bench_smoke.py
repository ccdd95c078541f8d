"""The CLI latency benchmark still runs and prints its table (so the benchmark code cannot rot)."""

from __future__ import annotations

import pytest

from tests.support.quick_bench import assert_provenance, run_quick_bench


@pytest.mark.timeout(120)
def test_quick_cli_benchmark_prints_its_table() -> None:
    result = run_quick_bench("bench.cli_latency", timeout_s=120)
    assert_provenance(result.stdout)
    lines = result.stdout.splitlines()
    assert lines[2] == "best and median of 1 run(s), wall clock; ratios of the best", result.stdout
    assert any(line.startswith("python -c pass (peer)") for line in lines), result.stdout
    emulator = [line for line in lines if line.startswith("scopelink status, SynScan emulator")]
    assert emulator, result.stdout
    assert "wire floor" in emulator[0]
    assert "bytes)" in emulator[0]
