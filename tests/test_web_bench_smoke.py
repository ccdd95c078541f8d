"""The dashboard benchmark still runs and prints its figures (so the benchmark code cannot rot)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.timeout(60)
def test_quick_dashboard_benchmark_prints_its_figures() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "bench.web_dashboard", "--quick"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert any(line.startswith("state + chart objects") for line in lines), result.stdout
    assert any(line.strip().startswith("10 pages") for line in lines), result.stdout
    assert any("x a 9600-baud line" in line for line in lines), result.stdout
