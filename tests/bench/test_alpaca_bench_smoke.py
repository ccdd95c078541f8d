"""The Alpaca wrk benchmark still runs and prints its table (so the benchmark cannot rot)."""

from __future__ import annotations

import pytest
from bench.alpaca_wrk import parse_wrk

from tests.support.programs import require_executable
from tests.support.quick_bench import run_quick_bench

WRK_REPORT = """Running 3s test @ http://127.0.0.1:1/api/v1/telescope/0/rightascension
  2 threads and 8 connections
  Thread Stats   Avg      Stdev     Max   +/- Stdev
    Latency     1.69ms    1.53ms  12.28ms   86.45%
  Latency Distribution
     50%  850.00us
     75%    1.72ms
     90%    3.89ms
     99%    1.20s
  23237 requests in 4.02s, 5.92MB read
  Socket errors: connect 0, read 2, write 0, timeout 1
  Non-2xx or 3xx responses: 4
Requests/sec:   5781.48
"""


def test_wrk_reports_are_read_with_their_units() -> None:
    result = parse_wrk(WRK_REPORT)
    assert result.requests == 23237
    assert result.requests_per_s == 5781.48
    assert result.p50_ms == pytest.approx(0.85)
    assert result.p99_ms == pytest.approx(1200.0)
    assert result.errors == 7


@pytest.mark.timeout(60)
def test_quick_benchmark_prints_its_table() -> None:
    require_executable("wrk")
    result = run_quick_bench("bench.alpaca_wrk", timeout_s=60)
    ours = next(
        line for line in result.stdout.splitlines() if line.startswith("scopelink Alpaca + sim")
    )
    requests_per_s = float(ours.split()[5].replace(",", ""))
    assert requests_per_s > 100.0, result.stdout
    assert ours.split()[8] == "0", f"wrk saw errors: {result.stdout}"
