"""The LX200/Stellarium server benchmark still runs and prints its tables."""

from __future__ import annotations

import pytest

from tests.support.quick_bench import assert_provenance, run_quick_bench


@pytest.mark.timeout(60)
def test_quick_planetarium_benchmark_prints_its_tables() -> None:
    result = run_quick_bench("bench.planetarium_servers", timeout_s=60)
    assert_provenance(result.stdout)
    lines = result.stdout.splitlines()
    assert lines[2].startswith("each row the best of 1 round(s)"), result.stdout
    assert any(line.startswith("LX200 over TCP, unpaced") for line in lines), result.stdout
    paced = next(line for line in lines if line.startswith("LX200 9600 paced"))
    # pacing holds the poll rate at (not above) the serial line's limit
    assert 0.5 < float(paced.split()[4]) <= 1.02, paced
    stellarium = [line.split() for line in lines if line.strip()[:1].isdigit()]
    assert [row[0] for row in stellarium] == ["1", "5"], result.stdout
