"""`scopelink serve` as a user runs it on a bare machine: the simulated mount behind its servers."""

from __future__ import annotations

import asyncio
import os
import re
import signal
import subprocess
import sys

from scopelink.links import Link, open_serial, open_tcp
from scopelink.protocol.synscan import (
    NEED_DATA,
    GetRaDec,
    GetVersion,
    IsAligned,
    Position,
    SynScanClientConnection,
    Version,
)
from scopelink.protocol.synscan.messages import AnyCommand, AnyReply

START_TIMEOUT_S = 20


async def start(*options: str) -> tuple[asyncio.subprocess.Process, list[str]]:
    """Start the command and read what it prints up to 'Ctrl-C stops.'."""
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "scopelink",
        "serve",
        *options,
        stdout=asyncio.subprocess.PIPE,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    assert process.stdout is not None
    lines: list[str] = []
    async with asyncio.timeout(START_TIMEOUT_S):
        while not lines or lines[-1] != "Ctrl-C stops.":
            line = (await process.stdout.readline()).decode()
            assert line, f"serve exited early after printing {lines}"
            lines.append(line.rstrip("\n"))
    return process, lines


async def stop(process: asyncio.subprocess.Process) -> int:
    process.send_signal(signal.SIGTERM)
    async with asyncio.timeout(10):
        return await process.wait()


async def ask(link: Link, client: SynScanClientConnection, command: AnyCommand) -> AnyReply:
    await link.write(client.send(command))
    async with asyncio.timeout(5):
        while (event := client.next_event()) is NEED_DATA:
            client.receive_data(await link.read())
    assert isinstance(event, AnyReply), event
    return event


async def test_serve_runs_the_simulated_mount_behind_a_synscan_server() -> None:
    process, lines = await start("--synscan-port", "0", "--synscan-pty")
    try:
        assert lines[0].startswith("scopelink serve: simulated EQ6 at +51.4779°")
        tcp = re.search(r"SynScan +tcp 127\.0\.0\.1:(\d+)", "\n".join(lines))
        pty = re.search(r"SynScan +pty (/dev/\S+)", "\n".join(lines))
        assert tcp, lines
        assert pty, lines
        async with await open_tcp("127.0.0.1", int(tcp.group(1))) as link:
            client = SynScanClientConnection()
            version = await ask(link, client, GetVersion())
            assert isinstance(version, Version)
            assert version.as_tuple()[:2] == (4, 39)
            assert await ask(link, client, IsAligned()) is not None
            position = await ask(link, client, GetRaDec(precise=True))
            assert isinstance(position, Position)
            # Power-on: the pole of date, which precession puts 0.1-0.2° from J2000's pole now.
            assert 0.05 < 90.0 - position.dec_degrees < 0.25
        async with await open_serial(pty.group(1)) as link:
            client = SynScanClientConnection()
            position = await ask(link, client, GetRaDec(precise=False))
            assert isinstance(position, Position)
    finally:
        assert await stop(process) == 0


def test_bad_options_fail_with_one_clear_line() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "scopelink", "serve", "--synscan-port", "70000"],
        capture_output=True,
        text=True,
        timeout=30,
        check=False,
    )
    assert result.returncode == 1
    assert result.stderr.strip() == "scopelink serve: --synscan-port 70000 is not a TCP port"


def test_a_port_in_use_is_reported_with_a_hint() -> None:
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = subprocess.run(
            [sys.executable, "-m", "scopelink", "serve", "--synscan-port", str(port)],
            capture_output=True,
            text=True,
            timeout=30,
            check=False,
        )
    assert result.returncode == 1
    assert "scopelink serve:" in result.stderr
    assert "Traceback" not in result.stderr
