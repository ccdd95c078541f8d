"""``scopelink serve`` run as a user runs it, in a subprocess with a fresh home."""

from __future__ import annotations

import asyncio
import os
import re
import signal
import subprocess
import sys
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

START_TIMEOUT_S = 30

ALL_OFF = (
    "--alpaca-port=-1",
    "--discovery-port=-1",
    "--lx200-port=-1",
    "--skyfi-port=-1",
    "--stellarium-port=-1",
    "--synscan-port=-1",
    "--dashboard-port=-1",
)

ALL_FREE = tuple(option.replace("=-1", "=0") for option in ALL_OFF)


def environment(home: Path, **more: str) -> dict[str, str]:
    """No user config and a scratch state dir: the test sees what a fresh install does (the
    event loop too: ``SCOPELINK_EVENT_LOOP`` unset, unless ``more`` sets it)."""
    inherited = {k: v for k, v in os.environ.items() if k != "SCOPELINK_EVENT_LOOP"}
    return {
        **inherited,
        "PYTHONUNBUFFERED": "1",
        "SCOPELINK_CONFIG": str(home / "absent.toml"),
        "XDG_STATE_HOME": str(home / "state"),
        **more,
    }


@asynccontextmanager
async def serving(
    home: Path, *options: str, env: dict[str, str] | None = None
) -> AsyncIterator[str]:
    """Run ``scopelink serve`` (with the environment variables ``env`` besides a fresh
    install's) until the test is done; yields what it printed up to the 'Ctrl-C stops.' line;
    checks it stops cleanly on SIGTERM."""
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "scopelink",
        "serve",
        *options,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
        env=environment(home, **(env or {})),
    )
    assert process.stdout is not None
    assert process.stderr is not None
    lines: list[str] = []
    try:
        async with asyncio.timeout(START_TIMEOUT_S):
            while not lines or lines[-1] != "Ctrl-C stops.":
                line = (await process.stdout.readline()).decode()
                if not line:
                    errors = (await process.stderr.read()).decode()
                    raise AssertionError(f"serve exited early: {lines} {errors}")
                lines.append(line.rstrip("\n"))
        yield "\n".join(lines)
    finally:
        if process.returncode is None:
            process.send_signal(signal.SIGTERM)
        async with asyncio.timeout(15):
            status = await process.wait()
    assert status == 0, (await process.stderr.read()).decode()


def listening(printed: str, label: str) -> int:
    found = re.search(label + r"\s+(?:tcp |udp |http://)?127\.0\.0\.1:(\d+)", printed)
    assert found, f"no {label} in {printed}"
    return int(found.group(1))


def run_serve(
    home: Path, *options: str, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "scopelink", "serve", *options],
        capture_output=True,
        text=True,
        timeout=30,
        check=False,
        env=environment(home, **(env or {})),
    )
