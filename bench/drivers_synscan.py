"""SynScan driver benchmarks: polls per second against the 9600-baud wire limit, and CPU per
command side by side with PyPI ``nexstar`` and a minimal blocking pyserial client.

Run ``.venv/bin/python -m bench.drivers_synscan`` (about half a minute) or with ``--quick`` (a few
seconds, what the smoke test runs). See ``docs/benchmarks.md`` and ``docs/drivers-synscan.md``.
"""

from __future__ import annotations

import argparse
import asyncio
import functools
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime

import serial

from scopelink.astro import Site
from scopelink.drivers.synscan import SynScanMount
from scopelink.links import Link, paced
from scopelink.mount import Priority
from scopelink.protocol.synscan import GetRaDec, Position
from scopelink.servers.hosting import SERIAL_9600_8N1
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(40.4, -3.7, pressure_hpa=0.0)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)

BYTE_S = SERIAL_9600_8N1.bits_per_byte / SERIAL_9600_8N1.baudrate
"""One byte on a 9600 8N1 line: 1.04 ms."""
E_ROUND_TRIP_BYTES = 1 + 18
"""``e`` and ``XXXXXXXX,YYYYYYYY#``."""
REFRESH_BYTES = (1 + 2) + E_ROUND_TRIP_BYTES + (1 + 2) + (1 + 2)
"""One refresh of an aligned equatorial mount: ``L``, ``e``, ``t``, ``p`` with their replies."""


@dataclass(frozen=True, slots=True)
class Sizes:
    polls: int
    commands: int


FULL = Sizes(polls=300, commands=2000)
QUICK = Sizes(polls=20, commands=100)


def new_sim() -> SimulatedMount:
    return SimulatedMount(EQ6, site=SITE, clock=SimClock.accelerated(1.0, START))


# --- 1. wire utilisation -----------------------------------------------------------------------


async def wire_utilisation(sizes: Sizes) -> list[tuple[str, float, float]]:
    """Refresh cycles and bare ``e`` polls per second over a memory link paced at 9600 8N1 in both
    directions (the emulator's replies by its host, the driver's commands by ``paced``)."""
    sim = new_sim()
    async with SynScanEmulator(sim) as emulator:
        device_side = await emulator.on_memory()
        handed_out = False

        async def factory() -> Link:
            nonlocal handed_out
            if handed_out:
                raise RuntimeError("the memory link cannot be reopened")
            handed_out = True
            return paced(device_side, SERIAL_9600_8N1.baudrate, SERIAL_9600_8N1.bits_per_byte)

        mount = SynScanMount(factory, site=SITE, clock=sim.now, name="memory, 9600 paced")
        await mount.connect()
        started = time.perf_counter()
        for _ in range(sizes.polls):
            await mount.refresh()
        refresh_rate = sizes.polls / (time.perf_counter() - started)
        started = time.perf_counter()
        for _ in range(sizes.polls):
            await mount.wire.ask(GetRaDec(), Priority.POLL)
        poll_rate = sizes.polls / (time.perf_counter() - started)
        await mount.disconnect()
    return [
        ("refresh (L e t p)", refresh_rate, 1.0 / (REFRESH_BYTES * BYTE_S)),
        ("e polls", poll_rate, 1.0 / (E_ROUND_TRIP_BYTES * BYTE_S)),
    ]


# --- 2. CPU per command: three clients, each in its own thread, against one emulator ----------


@dataclass(frozen=True, slots=True)
class ClientFigures:
    name: str
    cpu_us: float
    wall_us: float


Batch = Callable[[int], None]
"""Runs a client's command ``n`` times."""


def timed_in_thread(name: str, setup: Callable[[], Batch], count: int) -> ClientFigures:
    """Run ``setup()`` (which connects and returns a batch runner) in a fresh thread; time ``count``
    commands with the thread's own CPU clock, so the emulator's CPU (another thread) is not
    counted."""
    result: list[ClientFigures] = []
    failure: list[BaseException] = []

    def run() -> None:
        try:
            batch = setup()
            batch(10)  # warm up (imports, caches)
            cpu, wall = time.thread_time(), time.perf_counter()
            batch(count)
            cpu, wall = time.thread_time() - cpu, time.perf_counter() - wall
            result.append(ClientFigures(name, cpu / count * 1e6, wall / count * 1e6))
        except BaseException as error:  # reported in the main thread
            failure.append(error)

    thread = threading.Thread(target=run, name=name)
    thread.start()
    thread.join()
    if failure:
        raise failure[0]
    return result[0]


def scopelink_client(url: str) -> Batch:
    """Our driver on its own event loop, asking ``e`` through its wire (timeouts, scheduler)."""
    loop = asyncio.new_event_loop()
    mount = SynScanMount(url, site=SITE)
    loop.run_until_complete(mount.connect())

    async def polls(count: int) -> None:
        for _ in range(count):
            reply = await mount.wire.ask(GetRaDec(), Priority.POLL)
            assert isinstance(reply, Position)

    return lambda count: loop.run_until_complete(polls(count))


def nexstar_client(url: str) -> Batch:
    """PyPI ``nexstar`` (Celestron NexStar protocol, which SynScan's ``e`` shares)."""
    import nexstar  # type: ignore[import-untyped]  # ships no type hints

    port = serial.serial_for_url(url.replace("tcp://", "socket://"), timeout=3.5)
    controller = nexstar.NexstarHandController(port)

    def batch(count: int) -> None:
        for _ in range(count):
            controller.getPosition(nexstar.NexstarCoordinateMode.RA_DEC, highPrecisionFlag=True)

    return batch


def pyserial_client(url: str) -> Batch:
    """The least a blocking client can do: write ``e``, read 18 bytes, parse two hex numbers."""
    port = serial.serial_for_url(url.replace("tcp://", "socket://"), timeout=3.5)

    def batch(count: int) -> None:
        for _ in range(count):
            port.write(b"e")
            reply = port.read(18)
            int(reply[0:8], 16), int(reply[9:17], 16)

    return batch


def cpu_per_command(sizes: Sizes) -> list[ClientFigures]:
    """Serve one unpaced emulator on TCP in a thread; time each client against it in turn."""
    sim = new_sim()
    loop = asyncio.new_event_loop()
    ready = threading.Event()
    stop = asyncio.Event()
    address: list[str] = []

    async def serve() -> None:
        async with SynScanEmulator(sim, wire=None) as emulator:
            host, port = await emulator.on_tcp("127.0.0.1", 0)
            address.append(f"tcp://{host}:{port}")
            ready.set()
            await stop.wait()

    server = threading.Thread(target=loop.run_until_complete, args=(serve(),), daemon=True)
    server.start()
    ready.wait(10.0)
    url = address[0]
    try:
        clients: list[tuple[str, Callable[[str], Batch]]] = [
            ("scopelink SynScanMount.wire", scopelink_client),
            ("nexstar 0.0.5 getPosition", nexstar_client),
            ("pyserial write/read", pyserial_client),
        ]
        return [
            timed_in_thread(name, functools.partial(make, url), sizes.commands)
            for name, make in clients
        ]
    finally:
        loop.call_soon_threadsafe(stop.set)
        server.join(10.0)


# --- report --------------------------------------------------------------------------------------


def main(sizes: Sizes) -> None:
    print(f"scopelink SynScan driver benchmarks ({'quick' if sizes is QUICK else 'full'} run)")
    print()
    print("1. polls over a memory link paced at 9600 8N1 both ways")
    print(f"{'poll':<20} {'per s':>8} {'wire limit':>11} {'of limit':>9}")
    for name, rate, limit in asyncio.run(wire_utilisation(sizes)):
        print(f"{name:<20} {rate:>8.2f} {limit:>11.2f} {rate / limit:>8.1%}")
    print()
    print("2. CPU per 'e' command, each client in its own thread, emulator on TCP in another")
    figures = cpu_per_command(sizes)
    baseline = figures[-1].cpu_us
    print(f"{'client':<30} {'cpu us':>8} {'wall us':>8} {'cpu vs pyserial':>16}")
    for row in figures:
        print(
            f"{row.name:<30} {row.cpu_us:>8.0f} {row.wall_us:>8.0f} {row.cpu_us / baseline:>15.2f}x"
        )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="python -m bench.drivers_synscan", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="a few seconds, smaller counts")
    main(QUICK if parser.parse_args().quick else FULL)
