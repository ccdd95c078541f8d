"""The Sky Tracker driver benchmark still runs and prints its tables (so the code cannot rot)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.timeout(90)
def test_quick_benchmark_prints_its_tables() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "bench.drivers_skytracker", "--quick"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=90,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    wire = [line for line in lines if line.startswith("position poll") and line.endswith("%")]
    assert len(wire) == 1, result.stdout
    driver, bare, limit = (float(field) for field in wire[0].split()[-5:-2])
    assert 0 < driver <= limit * 1.02  # the emulated line never beats the wire
    assert 0 < bare <= limit * 1.02
    assert any(line.startswith("status (R)") and line.endswith("x") for line in lines)
