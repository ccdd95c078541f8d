"""Run a benchmark module as a user would (so the benchmark code cannot rot)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def run_bench(module: str, *args: str, timeout_s: float = 60) -> subprocess.CompletedProcess[str]:
    """``python -m MODULE ARGS...`` from the repository root; fails the test on a non-zero exit."""
    result = subprocess.run(
        [sys.executable, "-m", module, *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=timeout_s,
        check=False,
    )
    # A failed check is printed on stdout (its "check ...: FAILED" line), a crash on stderr.
    failed = [line for line in result.stdout.splitlines() if "FAIL" in line or "MISS" in line]
    assert result.returncode == 0, "\n".join([*failed, result.stderr[-4000:]])
    return result


def assert_provenance(stdout: str) -> None:
    """The report begins with where its figures come from (bench/provenance.py): the date and
    load average, then the commit."""
    lines = stdout.splitlines()
    assert len(lines) >= 2, stdout
    assert lines[0].startswith("date "), stdout
    assert " UTC, load average " in lines[0], stdout
    assert lines[1].startswith("commit "), stdout


def run_quick_bench(module: str, *, timeout_s: float = 60) -> subprocess.CompletedProcess[str]:
    """``python -m MODULE --quick`` from the repository root; fails the test on a non-zero exit."""
    return run_bench(module, "--quick", timeout_s=timeout_s)
