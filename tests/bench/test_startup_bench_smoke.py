"""The start-up benchmark still runs and prints its table (so the benchmark code cannot rot)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.timeout(120)
def test_quick_startup_benchmark_prints_every_row_and_a_verdict() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "bench.startup", "--quick"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith("date "), result.stdout
    assert lines[1].startswith("commit "), result.stdout
    for label in ("python -c pass (peer)", "scopelink --help", "scopelink --version"):
        assert any(line.startswith(label + " ") for line in lines), (label, result.stdout)
    assert any(line.startswith("scopelink status --help ") for line in lines), result.stdout
    assert lines[-1].startswith(("goal: PASS, slowest", "goal: MISS, slowest")), result.stdout
