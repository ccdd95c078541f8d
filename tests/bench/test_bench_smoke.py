"""The emulator benchmark still runs and prints its table (so the benchmark code cannot rot)."""

from __future__ import annotations

import pytest

from tests.support.quick_bench import assert_provenance, run_quick_bench


@pytest.mark.timeout(60)
def test_quick_benchmark_prints_its_tables() -> None:
    result = run_quick_bench("bench.emulators", timeout_s=60)
    lines = result.stdout.splitlines()
    assert any(line.startswith("1 mount, unpaced") for line in lines), result.stdout
    assert any(line.startswith("1 mount, 9600 paced") for line in lines), result.stdout
    assert any("mounts, 9600 paced" in line for line in lines), result.stdout
    assert any(line.strip().startswith("1e+04") for line in lines), result.stdout
    assert any(line.startswith("largest factor") for line in lines), result.stdout
    assert_provenance(result.stdout)
    goals = [line for line in lines if line.startswith("goal ")]
    # Both goals of issue #14 part 3, each with its verdict.
    assert len(goals) == 2, result.stdout
    assert all(line.split(": ")[1].split()[0] in ("PASS", "MISS") for line in goals), goals


@pytest.mark.timeout(60)
def test_quick_astro_benchmark_prints_its_table() -> None:
    result = run_quick_bench("bench.astro", timeout_s=60)
    lines = [line.strip() for line in result.stdout.splitlines()]
    assert lines[0].startswith("date "), result.stdout
    assert "load average" in lines[0], result.stdout
    assert any(line.startswith("peer astropy ") and "(pin " in line for line in lines)
    assert "1. 1000 positions at one instant, best of 2" in lines
    assert any(line.startswith("scopelink j2000_to_observed (arrays)") for line in lines)
    assert any(line.startswith("astropy SkyCoord.transform_to(AltAz)") for line in lines)
    assert sum(line.startswith("scopelink, instants") for line in lines) == 2
    assert any(line.startswith("astropy transform_to, frames pre-built") for line in lines)
    goals = [line for line in lines if line.startswith("goal ")]
    # One verdict per row compared with the peer, each saying whether it met the goal.
    assert len(goals) == 3, result.stdout
    assert all(line.split(": ")[2].split()[0] in ("PASS", "MISS") for line in goals), goals
