"""Where a benchmark's figures come from: date, load average, cores and commit, printed with every
report so that each figure in docs/benchmarks.md can be traced to the code that produced it."""

from __future__ import annotations

import os
import platform
import subprocess
from datetime import UTC, datetime


def git(*args: str) -> str:
    """``git args...``'s output, or "unknown" outside a checkout."""
    try:
        done = subprocess.run(["git", *args], capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return done.stdout.strip()


def provenance() -> list[str]:
    """Two lines: when and under what load, and which commit (marked if src/ or bench/ have
    uncommitted changes) with which Python."""
    dirty = "+uncommitted changes" if git("status", "--porcelain", "--", "src", "bench") else ""
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    return [
        f"date {datetime.now(UTC):%Y-%m-%d %H:%M} UTC, "
        f"load average {load} on {os.cpu_count()} cores",
        f"commit {git('rev-parse', '--short', 'HEAD')}{dirty}, Python {platform.python_version()}",
    ]
