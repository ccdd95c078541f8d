"""The SynScan driver benchmark still runs and prints its tables (so the benchmark cannot rot)."""

from __future__ import annotations

import pytest
from bench.provenance import UVLOOP_PIN

from tests.support.quick_bench import assert_provenance, run_quick_bench


@pytest.mark.timeout(90)
def test_quick_driver_benchmark_prints_its_tables() -> None:
    result = run_quick_bench("bench.drivers_synscan", timeout_s=90)
    assert_provenance(result.stdout)
    lines = result.stdout.splitlines()
    assert lines[2] == "peer nexstar 0.0.5 (pin 0.0.5)", result.stdout
    assert lines[3] == f"serve's event loop: uvloop {UVLOOP_PIN} (pin {UVLOOP_PIN})"
    assert any(line.startswith("  driver, asyncio's default loop") for line in lines)
    refresh = next(line for line in lines if line.startswith("refresh cycles"))
    assert refresh.endswith("%"), refresh
    assert any(line.startswith("e polls ") for line in lines), result.stdout
    assert any(line.startswith("e polls, bare link") for line in lines), result.stdout
    assert any(line.startswith("driver e polls / bare-link") for line in lines), result.stdout
    assert any(line.startswith("scopelink SynScanMount.wire") for line in lines), result.stdout
    assert any(line.startswith("nexstar 0.0.5 getPosition") for line in lines), result.stdout
    assert any(line.startswith("pyserial write/read") for line in lines), result.stdout
    assert any(line.startswith("asyncio floor (bare Protocol)") for line in lines), result.stdout
    assert any(line.startswith("scopelink refresh() per command") for line in lines)
    assert any(line.startswith("our driver above the asyncio floor: ") for line in lines)
    assert lines[-2].startswith("the goal judges 'scopelink SynScanMount.wire'"), result.stdout
    goal = lines[-1]
    assert goal.startswith("goal CPU per e <= nexstar's: "), result.stdout
    assert goal.split(": ")[1].split(";")[0] in {"PASS", "MISS"}, goal
