"""The Alpaca wrk benchmark still runs and prints its table (so the benchmark cannot rot)."""

from __future__ import annotations

import pytest
from bench.alpaca_wrk import PEER_STACK, line_use, parse_wrk, stack_label

from tests.support.programs import require_executable
from tests.support.quick_bench import assert_provenance, run_quick_bench

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


@pytest.mark.timeout(90)
def test_quick_benchmark_prints_its_table() -> None:
    require_executable("wrk")
    result = run_quick_bench("bench.alpaca_wrk", timeout_s=90)
    assert_provenance(result.stdout)
    lines = result.stdout.splitlines()
    ours = next(line for line in lines if line.startswith("scopelink Alpaca + sim"))
    requests_per_s = float(ours.split()[5].replace(",", ""))
    assert requests_per_s > 100.0, result.stdout
    assert ours.split()[8] == "0", f"wrk saw errors: {result.stdout}"
    # What serve gives out of the box: a child process, its telescope connected (every read a
    # reading, checked before wrk runs), held to its default access policy's rate.
    served = next(
        line for line in lines if line.startswith("scopelink serve (out of the box) + sim")
    )
    assert float(served.split()[8].replace(",", "")) > 10.0, result.stdout
    assert served.split()[11] == "0", f"wrk saw errors: {result.stdout}"
    assert "250/s burst 500" in served, result.stdout
    # Every row the goal speaks for has its own verdict line, and a row not run says so.
    goals = [line for line in lines if line.startswith("goal ")]
    assert [line.split(":")[0] for line in goals] == [
        "goal scopelink Alpaca + simulated mount",
        "goal scopelink Alpaca + SynScan driver @9600",
    ], result.stdout
    assert goals[0].endswith("not checked (no peer); p99 " + ours.split()[7] + " ms"), goals[0]
    assert "not checked (row not run)" in goals[1], goals[1]


def test_the_line_is_measured_not_assumed() -> None:
    """At rest a SynScan poll reads L and e (20 reply bytes), t and p only every tenth poll:
    the poll rate the line allows comes from the bytes counted, not from L e t p each time."""
    text = line_use(sent=90, received=840, seconds=1.0, polls=41)
    assert text.startswith("line 88% of 9600 8N1 (840 B/s in, 90 out)"), text
    assert "41.0 polls/s of 20.5 B from the device: 0.88 of the 46.9/s the line allows" in text


def test_the_peers_web_stack_is_named_and_a_version_off_its_pin_marked() -> None:
    versions = dict(PEER_STACK)
    assert stack_label(versions) == ", ".join(f"{n} {v}" for n, v in PEER_STACK.items())
    versions["uvicorn"] = "0.1.0"
    assert f"uvicorn 0.1.0 (pin {PEER_STACK['uvicorn']})" in stack_label(versions)
