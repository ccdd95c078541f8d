"""`scopelink emulate synscan` as a user runs it: prints where to connect, serves, stops."""

from __future__ import annotations

import asyncio
import os
import re
import signal
import sys

import pytest

from scopelink.links import open_serial, open_tcp


async def start(*options: str) -> tuple[asyncio.subprocess.Process, str]:
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "scopelink",
        "emulate",
        "synscan",
        *options,
        stdout=asyncio.subprocess.PIPE,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    assert process.stdout is not None
    async with asyncio.timeout(15):
        line = (await process.stdout.readline()).decode()
    return process, line


async def stop(process: asyncio.subprocess.Process) -> int:
    process.send_signal(signal.SIGTERM)
    async with asyncio.timeout(10):
        return await process.wait()


async def test_tcp_prints_the_bound_address_and_answers() -> None:
    process, line = await start("--tcp", "127.0.0.1:0", "--no-pacing", "--fault", "V:drop")
    try:
        match = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
        assert match, line
        async with await open_tcp("127.0.0.1", int(match.group(1))) as link:
            await link.write(b"V")
            await link.write(b"Kx")
            async with asyncio.timeout(3):
                assert await link.read_exactly(2) == b"x#"  # V was dropped by the fault
    finally:
        assert await stop(process) == 0


async def test_pty_prints_the_device_path() -> None:
    process, line = await start("--pty", "--unaligned")
    try:
        match = re.search(r"on (/dev/\S+)", line)
        assert match, line
        async with await open_serial(match.group(1)) as link:
            await link.write(b"J")
            async with asyncio.timeout(3):
                assert await link.read_exactly(2) == b"\x00#"
    finally:
        assert await stop(process) == 0


@pytest.mark.parametrize("fault", ["e", "e:explode"])
async def test_bad_fault_is_one_clear_line(fault: str) -> None:
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "scopelink",
        "emulate",
        "synscan",
        "--fault",
        fault,
        stderr=asyncio.subprocess.PIPE,
    )
    _, stderr = await process.communicate()
    assert process.returncode == 1
    assert stderr.decode().startswith("scopelink emulate: fault")
