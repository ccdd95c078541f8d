"""LX200 and Stellarium server benchmarks: poll throughput and position-stream fidelity.

Run ``.venv/bin/python -m bench.planetarium_servers`` (about 40 s) or with ``--quick`` (a few
seconds, what the smoke test runs). Figures are ratios against the wire limit or the configured
rate, so they travel between machines. See ``docs/benchmarks.md``.

1. LX200: a client polls ``:GR#`` then ``:GD#``, each after the previous reply (what INDI does,
   minus its sleep) over TCP, unpaced, and over an in-memory link paced at 9600 baud 8N1. The wire
   limit is 9600 / (27 bytes x 10 bits) = 35.6 pairs/s.
2. Stellarium: N clients connected at once, positions every 0.1 s; each client's message rate
   against the configured 10/s, and the process CPU per message.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime

from bench.provenance import print_provenance
from scopelink.astro import Site
from scopelink.links import Link, open_tcp, paced, precise_event_loop
from scopelink.protocol.stellarium import NEED_DATA, CurrentPosition, StellariumClientConnection
from scopelink.servers.hosting import SERIAL_9600_8N1
from scopelink.servers.lx200 import LX200Server
from scopelink.servers.stellarium import StellariumServer
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(40.4, -3.7)
POLL = b":GR#:GD#"
PAIR_BYTES = len(POLL) + len(b"HH:MM:SS#") + len(b"sDD*MM:SS#")
WIRE_LIMIT_PAIRS = SERIAL_9600_8N1.baudrate / (PAIR_BYTES * SERIAL_9600_8N1.bits_per_byte)
STELLARIUM_INTERVAL_S = 0.1


@dataclass(frozen=True)
class Sizes:
    poll_s: float
    stream_s: float
    client_counts: tuple[int, ...]
    rounds: int


FULL = Sizes(poll_s=8.0, stream_s=6.0, client_counts=(1, 10, 50), rounds=3)
QUICK = Sizes(poll_s=1.0, stream_s=1.0, client_counts=(1, 5), rounds=1)


@dataclass(frozen=True)
class Run:
    """One run of a row: its count (pairs, messages), wall and CPU seconds, and its key: the
    larger, the less disturbed (pairs/s; the worst client's share of the asked rate)."""

    text: str
    key: float


def new_mount() -> SimulatedMount:
    return SimulatedMount(EQ6, site=SITE, clock=SimClock(start=datetime.now(UTC)))


async def _read_until_hashes(link: Link, count: int) -> None:
    seen = 0
    while seen < count:
        seen += (await link.read()).count(b"#")


async def poll_link(link: Link, seconds: float) -> tuple[int, float, float]:
    """Poll pairs for ``seconds``; (pairs, wall seconds, CPU seconds)."""
    pairs = 0
    cpu0, wall0 = time.process_time(), time.perf_counter()
    while time.perf_counter() - wall0 < seconds:
        for command in (b":GR#", b":GD#"):  # one at a time, as INDI does
            await link.write(command)
            await _read_until_hashes(link, 1)
        pairs += 1
    return pairs, time.perf_counter() - wall0, time.process_time() - cpu0


async def lx200_rows(seconds: float) -> list[Run]:
    rows = []
    async with LX200Server(new_mount()) as server:
        host, port = await server.on_tcp(port=0)
        tcp = await open_tcp(host, port)
        pairs, wall, cpu = await poll_link(tcp, seconds)
        await tcp.close()
        rows.append(_lx200_row("LX200 over TCP, unpaced", pairs, wall, cpu))
    async with LX200Server(new_mount(), wire=SERIAL_9600_8N1) as server:
        client = await server.on_memory()
        link = paced(client, SERIAL_9600_8N1.baudrate, SERIAL_9600_8N1.bits_per_byte)
        pairs, wall, cpu = await poll_link(link, seconds)
        rows.append(_lx200_row("LX200 9600 paced", pairs, wall, cpu))
    return rows


def _lx200_row(name: str, pairs: int, wall: float, cpu: float) -> Run:
    rate = pairs / wall
    text = (
        f"{name:<26}{rate:>10.1f}{rate / WIRE_LIMIT_PAIRS:>10.3f}"
        f"{cpu / wall:>9.3f}{1e6 * cpu / max(pairs, 1):>10.0f}"
    )
    return Run(text, rate)


async def _count_positions(
    reader: asyncio.StreamReader, stop: asyncio.Event, counts: list[int], index: int
) -> None:
    codec = StellariumClientConnection()
    while not stop.is_set():
        data = await reader.read(4096)
        if not data:
            return
        codec.receive_data(data)
        while (event := codec.next_event()) is not NEED_DATA:
            if isinstance(event, CurrentPosition):
                counts[index] += 1


async def stellarium_row(clients: int, seconds: float) -> Run:
    async with StellariumServer(new_mount(), port=0, interval_s=STELLARIUM_INTERVAL_S) as server:
        streams = [await asyncio.open_connection("127.0.0.1", server.port) for _ in range(clients)]
        counts = [0] * clients
        stop = asyncio.Event()
        tasks = [
            asyncio.create_task(_count_positions(reader, stop, counts, i))
            for i, (reader, _) in enumerate(streams)
        ]
        await asyncio.sleep(0.5)  # every client connected and served
        before = list(counts)
        cpu0, wall0 = time.process_time(), time.perf_counter()
        await asyncio.sleep(seconds)
        wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
        counts = [after - earlier for after, earlier in zip(counts, before, strict=True)]
        stop.set()
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        for _, writer in streams:
            writer.close()
    nominal = wall / STELLARIUM_INTERVAL_S
    worst = min(counts) / nominal
    total = sum(counts)
    text = (
        f"{clients:>7d}{total / wall:>12.1f}{worst:>10.3f}"
        f"{cpu / wall:>9.3f}{1e6 * cpu / max(total, 1):>10.0f}"
    )
    return Run(text, worst)


def best(runs: Sequence[Run]) -> str:
    return max(runs, key=lambda run: run.key).text


async def main(sizes: Sizes) -> None:
    print_provenance()
    print(f"each row the best of {sizes.rounds} round(s): the most pairs/s, the best worst client")
    lx200 = [await lx200_rows(sizes.poll_s) for _ in range(sizes.rounds)]
    print(f"LX200 :GR#+:GD# polling; wire limit {WIRE_LIMIT_PAIRS:.1f} pairs/s at 9600 8N1")
    print(f"{'run':<26}{'pairs/s':>10}{'/wire':>10}{'cpu/s':>9}{'us/pair':>10}")
    for runs in zip(*lx200, strict=True):
        print(best(runs))
    print()
    print(f"Stellarium positions every {STELLARIUM_INTERVAL_S} s to every client")
    print(f"{'clients':>7}{'msgs/s':>12}{'min/set':>10}{'cpu/s':>9}{'us/msg':>10}")
    for clients in sizes.client_counts:
        print(best([await stellarium_row(clients, sizes.stream_s) for _ in range(sizes.rounds)]))
    sys.stdout.flush()


def run() -> None:
    parser = argparse.ArgumentParser(
        prog="python -m bench.planetarium_servers", description=__doc__
    )
    parser.add_argument("--quick", action="store_true", help="a few seconds, smaller counts")
    args = parser.parse_args()
    with asyncio.Runner(loop_factory=precise_event_loop) as runner:
        runner.run(main(QUICK if args.quick else FULL))


if __name__ == "__main__":
    run()
