"""The emulator benchmark still runs and prints its table (so the benchmark code cannot rot)."""

from __future__ import annotations

import pytest

from tests.bench_support import run_quick_bench


@pytest.mark.timeout(60)
def test_quick_benchmark_prints_its_tables() -> None:
    result = run_quick_bench("bench.emulators", timeout_s=60)
    lines = result.stdout.splitlines()
    assert any(line.startswith("1 mount, unpaced") for line in lines), result.stdout
    assert any(line.startswith("1 mount, 9600 paced") for line in lines), result.stdout
    assert any("mounts, 9600 paced" in line for line in lines), result.stdout
    assert any(line.strip().startswith("1e+04") for line in lines), result.stdout
    assert any(line.startswith("largest factor") for line in lines), result.stdout


@pytest.mark.timeout(60)
def test_quick_astro_benchmark_prints_its_table() -> None:
    result = run_quick_bench("bench.astro", timeout_s=60)
    lines = result.stdout.splitlines()
    assert lines[0].startswith("J2000 -> observed Alt/Az, 1000 positions")
    assert any(line.startswith("scopelink j2000_to_observed (vector)") for line in lines)
    assert any(line.startswith("astropy SkyCoord.transform_to(AltAz)") for line in lines)
    assert lines[-1].startswith("astropy / scopelink:")
