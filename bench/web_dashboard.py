"""Dashboard benchmarks: the cost of one live update, fan-out to many pages, traffic decoding.

Run ``.venv/bin/python -m bench.web_dashboard`` (about a minute and a half: 3 rounds, each row
the best) or with ``--quick`` (a few
seconds, what the smoke test runs). Figures are ratios against a budget measured in the same run:
an update's CPU time against the update interval, updates delivered per page against the rate
asked for, and traffic decoded per second against what a 9600-baud line can carry.
See ``docs/benchmarks.md``.
"""

from __future__ import annotations

import argparse
import asyncio
import math
import time
from datetime import UTC, datetime

import aiohttp

from bench.provenance import print_provenance
from scopelink.astro import Site
from scopelink.decode import Protocol
from scopelink.links.trace import trace_transfer
from scopelink.sim import EQ6, SimClock, SimulatedMount
from scopelink.web import Dashboard
from scopelink.web.traffic import TrafficMonitor

SITE = Site(45.0, 7.0)
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
INTERVAL_S = 0.25
WIRE_BYTES_PER_S = 9600 / 10  # 8N1: ten bits a byte
ROUNDS = 3
GOAL_CORE_PER_PAGE = 0.05
"""Issue #17: the server's CPU per open page."""


def sim() -> SimulatedMount:
    return SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=1.0))


async def update_cost(iterations: int, rounds: int) -> None:
    """CPU of one update, the best of ``rounds`` rounds of ``iterations`` each."""
    mount = sim()
    await mount.connect()
    dashboard = Dashboard(mount, port=0, update_interval_s=INTERVAL_S, trace=False)
    await dashboard.hub.build_update(with_sky=True)  # load the catalogue first
    print(f"{'update':<28}{'ms each':>10}{'share of interval':>20}")
    for with_sky in (False, True):
        each = math.inf
        for _ in range(rounds):
            started = time.process_time()
            for _ in range(iterations):
                await dashboard.hub.build_update(with_sky=with_sky)
            each = min(each, (time.process_time() - started) / iterations)
        label = "state + chart objects" if with_sky else "state only"
        print(f"{label:<28}{each * 1000:>10.2f}{each / INTERVAL_S:>19.1%}")
    await mount.disconnect()


async def fan_out_rounds(pages: int, seconds: float, rounds: int) -> float:
    """:func:`fan_out` ``rounds`` times; prints the round whose worst page got the most and
    returns its CPU per open page (a share of one core)."""
    runs = [await fan_out(pages, seconds) for _ in range(rounds)]
    _, row, cpu_share = max(runs)
    print(row)
    return cpu_share / pages


async def fan_out(pages: int, seconds: float) -> tuple[float, str, float]:
    """(the worst page's share of the updates asked for, the row, the process's CPU as a share
    of one core)."""
    mount = sim()
    await mount.connect()
    async with (
        Dashboard(mount, port=0, update_interval_s=INTERVAL_S, trace=False) as dashboard,
        aiohttp.ClientSession(base_url=dashboard.url) as http,
    ):
        sockets = [await http.ws_connect("/ws") for _ in range(pages)]
        for ws in sockets:
            await ws.receive()  # the hello
        counts = [0] * pages

        async def count(index: int, ws: aiohttp.ClientWebSocketResponse) -> None:
            while True:
                message = await ws.receive()
                if message.type is not aiohttp.WSMsgType.TEXT:
                    return
                counts[index] += 1

        readers = [asyncio.create_task(count(i, ws)) for i, ws in enumerate(sockets)]
        await asyncio.sleep(INTERVAL_S)  # drain what queued while the pages connected
        baseline = list(counts)
        cpu, wall = time.process_time(), time.perf_counter()
        await asyncio.sleep(seconds)
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        received = [now - before for now, before in zip(counts, baseline, strict=True)]
        for task in readers:
            task.cancel()
        for ws in sockets:
            await ws.close()
    await mount.disconnect()
    asked = wall / INTERVAL_S
    worst = min(received) / asked
    row = (
        f"{pages:>5} pages{'':<8}{sum(received) / pages / wall:>10.2f}/s"
        f"{worst:>14.0%}{cpu / wall:>14.1%}"
    )
    return worst, row, cpu / wall


def traffic_throughput(polls: int, rounds: int) -> None:
    """Bytes decoded per second, the best of ``rounds``."""
    per_s = max(traffic_rate(polls) for _ in range(rounds))
    print(
        f"{'traffic decoding':<28}{per_s:>10.0f} B/s"
        f"{per_s / WIRE_BYTES_PER_S:>12.0f}x a 9600-baud line"
    )


def traffic_rate(polls: int) -> float:
    """The driver's position poll (``e`` and its 18-byte reply) through the monitor."""
    monitor = TrafficMonitor(Protocol.SYNSCAN, capacity=200)
    link = "tcp 127.0.0.1:11880"
    reply = b"34AB0500,12CE0500#"
    with monitor.attached():
        started = time.process_time()
        for _ in range(polls):
            trace_transfer("-->", link, b"e")
            trace_transfer("<--", link, reply[:9])
            trace_transfer("<--", link, reply[9:])
        elapsed = time.process_time() - started
    decoded = monitor.since(0)
    assert decoded[-1].meanings, "the last reply was not decoded"
    return polls * (1 + len(reply)) / elapsed


async def main(quick: bool) -> None:
    rounds = 1 if quick else ROUNDS
    print_provenance()
    print(f"scopelink dashboard benchmark, each row the best of {rounds} round(s)")
    print()
    await update_cost(5 if quick else 40, rounds)
    print()
    print(f"{'fan-out':<18}{'updates/page':>12}{'worst vs 4/s':>14}{'CPU of 1 core':>14}")
    per_page = {
        pages: await fan_out_rounds(pages, 1.0 if quick else 5.0, rounds)
        for pages in ((1, 10) if quick else (1, 10, 50))
    }
    print()
    traffic_throughput(200 if quick else 5000, rounds)
    print()
    worst_pages, worst = max(per_page.items(), key=lambda item: item[1])
    verdict = "PASS" if all(share <= GOAL_CORE_PER_PAGE for share in per_page.values()) else "MISS"
    print(
        f"goal: server CPU per open page <= {GOAL_CORE_PER_PAGE:g} core, every row: {verdict} "
        f"(worst {worst:.3f} core per page, with {worst_pages} page(s); the process's CPU with its "
        "poller and this benchmark's own clients, divided by the pages)"
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="a few seconds: the smoke test")
    asyncio.run(main(parser.parse_args().quick))
