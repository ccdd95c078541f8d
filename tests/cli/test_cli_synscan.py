"""The device commands against the SynScan emulator, over TCP, through the SynScan driver.

The emulator runs as ``scopelink emulate synscan`` in its own process, so what one command leaves
the mount doing (still slewing, or stopped) can be read back by the next.
"""

from __future__ import annotations

import asyncio
import json
import signal
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.cli import (
    read_line_matching,
    scopelink,
    separation_deg,
    start_scopelink,
    state_of,
    synscan_emulator,
)


@pytest.fixture(scope="module")
def device() -> Iterator[str]:
    """A real-time emulated EQ6 (real-time so a slew lasts long enough to interrupt)."""
    with synscan_emulator("--no-pacing") as spec:
        yield spec


def test_info_names_the_firmware_and_model(config: Path, device: str) -> None:
    result = scopelink(config, "info", device, "--json")
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["protocol"] == "synscan"
    assert report["model"] == "EQ6 GOTO"
    assert report["firmware"] == "04.39.05"
    assert report["details"]["motor_versions"] == [[3, 39], [3, 39]]


def test_info_without_a_kind_detects_synscan(config: Path, device: str) -> None:
    bare = device.removeprefix("synscan:")
    result = scopelink(config, "info", bare)
    assert result.returncode == 0, result.stderr
    assert "synscan" in result.stdout
    assert "04.39.05" in result.stdout
    lines = [" ".join(line.split()) for line in result.stdout.splitlines()]
    assert "motor controllers 3.39, 3.39" in lines  # for people: not [[3, 39], [3, 39]]
    assert not any(line.startswith("version major") for line in lines)  # the firmware line says it


def test_verbose_shows_the_byte_trace(config: Path, device: str) -> None:
    result = scopelink(config, "status", "--json", "-v", "--device", device)
    assert result.returncode == 0, result.stderr
    assert "scopelink.links.trace" in result.stderr
    assert '--> 1 bytes: 56 | "V"' in result.stderr  # the version query at connect
    json.loads(result.stdout)  # the trace went to stderr only


def test_ctrl_c_during_goto_stops_the_mount(config: Path, device: str) -> None:
    async def interrupt() -> tuple[int, str]:
        process = await start_scopelink(config, "goto", "--altaz", "20", "200", "--device", device)
        await read_line_matching(process.stderr, "° to go")  # the slew is under way
        process.send_signal(signal.SIGINT)
        async with asyncio.timeout(20):
            out, _ = await process.communicate()
        return await process.wait(), out.decode()

    status, out = asyncio.run(interrupt())
    assert status == 130, out
    assert "slew aborted; the mount stopped at" in out
    # The emulated mount (another process) really stopped short of the target, and stays put.
    first = state_of(config, device)
    time.sleep(0.5)
    second = state_of(config, device)
    assert first["slewing"] is False
    assert second["slewing"] is False
    assert separation_deg(first["alt_deg"], first["az_deg"], 20.0, 200.0) > 5.0
    moved = separation_deg(first["alt_deg"], first["az_deg"], second["alt_deg"], second["az_deg"])
    assert moved < 0.05


def test_status_watch_streams_until_ctrl_c(config: Path, device: str) -> None:
    async def watch() -> tuple[int, list[str]]:
        process = await start_scopelink(
            config, "status", "--watch", "--json", "--interval", "0.2", "--device", device
        )
        lines = [await read_line_matching(process.stdout, "read_at") for _ in range(3)]
        process.send_signal(signal.SIGINT)
        async with asyncio.timeout(20):
            await process.communicate()
        return await process.wait(), lines

    status, lines = asyncio.run(watch())
    assert status == 0
    stamps = [json.loads(line)["read_at"] for line in lines]
    assert stamps == sorted(stamps)
    assert len(set(stamps)) == 3  # fresh readings, not the same one again
