"""The LX200/Stellarium server benchmark still runs and prints its tables."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.timeout(60)
def test_quick_planetarium_benchmark_prints_its_tables() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "bench.planetarium_servers", "--quick"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert any(line.startswith("LX200 over TCP, unpaced") for line in lines), result.stdout
    paced = next(line for line in lines if line.startswith("LX200 9600 paced"))
    # pacing holds the poll rate at (not above) the serial line's limit
    assert 0.5 < float(paced.split()[4]) <= 1.02, paced
    stellarium = [line.split() for line in lines if line.strip()[:1].isdigit()]
    assert [row[0] for row in stellarium] == ["1", "5"], result.stdout
