"""``scopelink`` as a child process of a benchmark: the command line as users run it, with its own
settings (none) and state directory under ``home`` so that no user file is read or written; and
what the benchmarks measure such children with (their CPU, the bytes on their device link)."""

from __future__ import annotations

import asyncio
import contextlib
import os
import re
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path

CLK_TCK = os.sysconf("SC_CLK_TCK")


def environment(home: Path) -> dict[str, str]:
    """This process's environment with no settings file and a private state directory."""
    return {
        **os.environ,
        "PYTHONUNBUFFERED": "1",
        "SCOPELINK_CONFIG": str(home / "absent.toml"),
        "XDG_STATE_HOME": str(home / "state"),
    }


async def start_scopelink(
    home: Path, *args: str, stderr: int = asyncio.subprocess.PIPE
) -> asyncio.subprocess.Process:
    """``python -m scopelink args...``, its standard output piped (and its errors, unless
    ``stderr`` says otherwise: a long run that never reads them should pass DEVNULL)."""
    return await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "scopelink",
        *args,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=stderr,
        env=environment(home),
    )


async def quiet_scopelink(home: Path, *args: str) -> asyncio.subprocess.Process:
    """:func:`start_scopelink` whose errors go nowhere (a benchmark never reads them: a full
    pipe would stall the child)."""
    return await start_scopelink(home, *args, stderr=asyncio.subprocess.DEVNULL)


async def read_until(process: asyncio.subprocess.Process, pattern: str) -> str:
    """What ``process`` printed up to and including the first line matching ``pattern``."""
    assert process.stdout is not None
    lines: list[str] = []
    async with asyncio.timeout(30):
        while not lines or not re.search(pattern, lines[-1]):
            line = (await process.stdout.readline()).decode()
            if not line:
                raise RuntimeError(f"scopelink exited early: {lines}")
            lines.append(line.rstrip("\n"))
    return "\n".join(lines)


async def stop(process: asyncio.subprocess.Process) -> int:
    """SIGTERM, then SIGKILL after 15 s; the exit status."""
    if process.returncode is None:
        process.send_signal(signal.SIGTERM)
    try:
        async with asyncio.timeout(15):
            return await process.wait()
    except TimeoutError:
        process.kill()
        return await process.wait()


def cpu_seconds(pid: int | None = None) -> float:
    """User + system CPU seconds of process ``pid`` so far (this process when None)."""
    if pid is None:
        return time.process_time()
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK


async def emulate(home: Path, driver: str, *extra: str) -> tuple[asyncio.subprocess.Process, int]:
    """``scopelink emulate DRIVER --tcp 127.0.0.1:0 EXTRA...``; returns it and its port."""
    process = await quiet_scopelink(home, "emulate", driver, "--tcp", "127.0.0.1:0", *extra)
    try:
        printed = await read_until(process, r"listening on")
    except BaseException:
        await stop(process)
        raise
    found = re.search(r"127\.0\.0\.1:(\d+)", printed)
    assert found is not None, printed
    return process, int(found.group(1))


async def serve_alpaca(
    home: Path, device: str, *options: str, dashboard: bool = False
) -> tuple[asyncio.subprocess.Process, str]:
    """``scopelink serve`` in front of ``device`` with Alpaca (and the dashboard) on free ports,
    every other server off, and serve's defaults for everything else (its access policy
    included); returns the process and what it printed until it was ready."""
    serve = await quiet_scopelink(
        home,
        "serve",
        "--device",
        device,
        *options,
        "--alpaca-port=0",
        "--discovery-port=-1",
        "--lx200-port=-1",
        "--skyfi-port=-1",
        "--stellarium-port=-1",
        "--synscan-port=-1",
        f"--dashboard-port={0 if dashboard else -1}",
    )
    try:
        return serve, await read_until(serve, r"^Ctrl-C stops\.$")
    except BaseException:
        await stop(serve)
        raise


def alpaca_port(printed: str) -> int:
    """The Alpaca port in what ``scopelink serve`` printed at start."""
    found = re.search(r"Alpaca\s+http://127\.0\.0\.1:(\d+)", printed)
    assert found is not None, printed
    return int(found.group(1))


class Relay:
    """A TCP relay to a device on 127.0.0.1, counting the bytes each way."""

    def __init__(self, device_port: int) -> None:
        self.device_port = device_port
        self.to_device = 0
        self.from_device = 0
        self._server: asyncio.Server | None = None

    async def start(self) -> int:
        """Listen on a free port of 127.0.0.1; returns it."""
        self._server = await asyncio.start_server(self._connection, "127.0.0.1", 0)
        return int(self._server.sockets[0].getsockname()[1])

    async def close(self) -> None:
        if self._server is not None:
            self._server.close()

    async def _connection(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        device_reader, device_writer = await asyncio.open_connection("127.0.0.1", self.device_port)

        async def pump(
            source: asyncio.StreamReader, sink: asyncio.StreamWriter, count: Callable[[int], None]
        ) -> None:
            with contextlib.suppress(ConnectionError):
                while data := await source.read(4096):
                    count(len(data))
                    sink.write(data)
                    await sink.drain()
            sink.close()

        def up(n: int) -> None:
            self.to_device += n

        def down(n: int) -> None:
            self.from_device += n

        await asyncio.gather(pump(reader, device_writer, up), pump(device_reader, writer, down))
