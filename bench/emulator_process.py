"""An emulated device in a process of its own, on a CPU of its own, for the driver benches.

A real hand control or Sky Tracker is another machine: its CPU time overlaps the driver's instead
of adding to it. The driver benches (``bench.drivers_synscan``, ``bench.drivers_skytracker``) run
their emulators through :func:`emulator_process` (a spawned process serving TCP on 127.0.0.1,
free ports) and time each client in a thread of its own with the thread's CPU clock, the client
threads placed on one CPU and the emulator on another (:data:`CLIENT_CPU`, :data:`EMULATOR_CPU`).
"""

from __future__ import annotations

import asyncio
import multiprocessing
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing.connection import Connection

PLACED = hasattr(os, "sched_setaffinity") and len(os.sched_getaffinity(0)) >= 2
"""Whether the emulator and the clients are placed on CPUs of their own (Linux, two or more)."""
CLIENT_CPU, EMULATOR_CPU = sorted(os.sched_getaffinity(0))[:2] if PLACED else (0, 0)
"""Every client thread runs on the first allowed CPU, the emulator process on the second: the
same placement for each client (a reply always wakes a thread on the other core). Unplaced, the
scheduler's choices moved the figures by 20-30 % from run to run."""


def place_client_thread() -> None:
    """Pin the calling thread (only it) to :data:`CLIENT_CPU`, where placement is possible."""
    if PLACED:
        os.sched_setaffinity(0, {CLIENT_CPU})


@dataclass(frozen=True, slots=True)
class Served:
    """What the emulator process announced: its own process id and where it listens."""

    pid: int
    urls: tuple[str, ...]


async def announce_and_serve(pipe: Connection, *addresses: tuple[str, int]) -> None:
    """Child side: send the parent this process's id and the ``tcp://`` URL of each listening
    ``(host, port)``, then keep serving until the parent says stop."""
    pipe.send((os.getpid(), tuple(f"tcp://{host}:{port}" for host, port in addresses)))
    await asyncio.get_running_loop().run_in_executor(None, pipe.recv)


@contextmanager
def emulator_process(target: Callable[..., None], *args: object) -> Iterator[Served]:
    """Spawn ``target(pipe, *args)`` (a module-level function that ends in
    :func:`announce_and_serve`) pinned to :data:`EMULATOR_CPU`; yields what it announced and
    stops it on leaving."""
    context = multiprocessing.get_context("spawn")
    parent, child = context.Pipe()
    process = context.Process(target=target, args=(child, *args))
    process.start()
    if PLACED and process.pid is not None:
        os.sched_setaffinity(process.pid, {EMULATOR_CPU})
    try:
        if not parent.poll(60.0):
            raise RuntimeError("the emulator process did not start")
        pid, urls = parent.recv()
        yield Served(int(pid), tuple(str(url) for url in urls))
    finally:
        parent.send("stop")
        process.join(10.0)
        if process.is_alive():
            process.kill()
