"""The CLI latency benchmark still runs and prints its table (so the benchmark code cannot rot)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.timeout(120)
def test_quick_cli_benchmark_prints_its_table() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "bench.cli_latency", "--quick"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert any(line.startswith("python -c pass (peer)") for line in lines), result.stdout
    emulator = [line for line in lines if line.startswith("scopelink status, SynScan emulator")]
    assert emulator, result.stdout
    assert "wire floor" in emulator[0]
    assert "bytes)" in emulator[0]
