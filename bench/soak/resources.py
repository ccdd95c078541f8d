"""What the serve process holds, read from ``/proc``: its RSS, its fds and what they are."""

from __future__ import annotations

import asyncio
import contextlib
import os
import re
from collections import Counter
from pathlib import Path

from bench.soak.night import Night


def rss_kib_and_fds(pid: int) -> tuple[int, int]:
    status = Path(f"/proc/{pid}/status").read_text()
    found = re.search(r"^VmRSS:\s+(\d+) kB", status, re.MULTILINE)
    return (int(found.group(1)) if found else 0), len(os.listdir(f"/proc/{pid}/fd"))


_TCP_STATES = {"01": "established", "06": "time-wait", "08": "close-wait", "0A": "listen"}


def open_files(pid: int) -> Counter[str]:
    """What the process holds open, by kind: TCP sockets (listening, a client's, the device
    link's), pipes, event fds, files."""
    rows: list[tuple[int, int, str, str]] = []  # local port, remote port, state, inode
    for table in ("tcp", "tcp6"):
        with contextlib.suppress(OSError):
            for line in Path(f"/proc/{pid}/net/{table}").read_text().splitlines()[1:]:
                fields = line.split()
                local, remote = int(fields[1].split(":")[1], 16), int(fields[2].split(":")[1], 16)
                rows.append((local, remote, _TCP_STATES.get(fields[3], fields[3]), fields[9]))
    listening = {local for local, _, state, _ in rows if state == "listen"}
    sockets: dict[str, str] = {}
    for local, remote, state, inode in rows:
        if state == "listen":
            sockets[inode] = f"listening on :{local}"
        elif local in listening:
            sockets[inode] = f"{state} client of :{local}"
        else:
            sockets[inode] = f"{state} to :{remote}"  # the device link
    kinds: Counter[str] = Counter()
    for fd in os.listdir(f"/proc/{pid}/fd"):
        with contextlib.suppress(OSError):
            target = os.readlink(f"/proc/{pid}/fd/{fd}")
            if target.startswith("socket:["):
                target = "socket " + sockets.get(target[8:-1], "(not tcp)")
            elif target.startswith("pipe:["):
                target = "pipe"
            kinds[target] += 1
    return kinds


async def sample_memory(pid: int, night: Night) -> None:
    while True:
        rss, fds = rss_kib_and_fds(pid)
        night.memory.append((night.now(), rss, fds))
        await asyncio.sleep(1.0)
