"""Lost and stalled devices: how soon a reading stops being served, and how soon the drivers are
back once the device returns (issue #11 parts 5 and 6).

Each driver polls (a watcher holds its poller) over TCP to its real emulator: the SynScan driver to
the SynScan emulator (replies paced at 9600 baud), the Sky Tracker driver to the Sky Tracker
emulator. Two faults: ``close`` (the emulator's TCP port closes and reopens on the same port after
``--down`` seconds, a network bridge restarting) and ``stall`` (the device reads and answers
nothing, then answers again). Reported per driver and fault, over the trials:

* ``refused``: from the fault until the position is refused (``fresh_state`` raises); at most
  ``stale_after_s`` plus one poll for a stall, at once for a closed port once a poll notices;
* ``down``: from the fault until the state reads ``connected = false``;
* ``back``: from the device's return until a fresh, connected reading (the reconnect promise is
  5 s).

    .venv/bin/python -m bench.reconnect            # 5 trials of each
    .venv/bin/python -m bench.reconnect --quick    # 1 trial of each (the smoke test)
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import statistics
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from bench.provenance import print_provenance
from scopelink.astro import Site
from scopelink.drivers.skytracker import SkyTrackerMount
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import DEFAULT_STALE_AFTER_S, Mount, MountError
from scopelink.servers.faults import ANY, Fault, FaultInjector, FaultKind
from scopelink.servers.hosting import HostedDevice
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SKY_TRACKER, SimClock, SimulatedMount

SITE = Site(latitude_deg=48.0, longitude_deg=11.0)
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
DRIVERS = ("synscan", "skytracker")
FAULTS = ("close", "stall")


@dataclass(frozen=True, slots=True)
class Trial:
    refused_s: float
    down_s: float
    back_s: float


async def _until(check: Callable[[], bool], mount: Mount, limit_s: float = 60.0) -> float:
    loop = asyncio.get_running_loop()
    start = loop.time()
    while not check():
        if loop.time() - start > limit_s:
            raise TimeoutError(f"not within {limit_s} s: {mount.state}")
        await asyncio.sleep(0.01)
    return loop.time() - start


def _refused(mount: Mount) -> bool:
    try:
        mount.fresh_state()
    except MountError:
        return True
    return False


async def _trial(
    mount: Mount,
    emulator: HostedDevice,
    faults: FaultInjector,
    *,
    port: int,
    fault: str,
    down_s: float,
) -> Trial:
    await _until(lambda: mount.state.connected and not _refused(mount), mount)
    loop = asyncio.get_running_loop()
    started = loop.time()
    if fault == "close":
        await emulator.close()
    else:
        faults.add(Fault(FaultKind.STALL, ANY))
    refused_s = await _until(lambda: _refused(mount), mount)
    await _until(lambda: not mount.state.connected, mount)
    down = loop.time() - started
    await asyncio.sleep(max(0.0, down_s - (loop.time() - started)))
    returned = loop.time()
    if fault == "close":
        await emulator.on_tcp("127.0.0.1", port)
    else:
        faults.clear()
    await _until(lambda: mount.state.connected and not _refused(mount), mount)
    return Trial(refused_s, down, loop.time() - returned)


async def run(driver: str, fault: str, trials: int, down_s: float) -> list[Trial]:
    if driver == "synscan":
        sim = SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START))
        await sim.connect()
        emulator: HostedDevice = SynScanEmulator(sim)
    else:
        sim = SimulatedMount(SKY_TRACKER, site=SITE, clock=SimClock(start=START))
        emulator = SkyTrackerEmulator(sim, Path(tempfile.mkdtemp(prefix="scopelink-bench-")))
    results: list[Trial] = []
    async with emulator:
        faults = emulator.faults  # type: ignore[attr-defined]
        _, port = await emulator.on_tcp("127.0.0.1", 0)
        spec = f"tcp://127.0.0.1:{port}"
        mount: Mount = (
            SynScanMount(spec, site=SITE)
            if driver == "synscan"
            else SkyTrackerMount(spec, site=SITE)
        )
        await mount.connect()
        async with mount.watching():
            for number in range(trials):
                trial = await _trial(mount, emulator, faults, port=port, fault=fault, down_s=down_s)
                logging.getLogger("bench").info("%s %s #%d: %s", driver, fault, number, trial)
                results.append(trial)
        await mount.disconnect()
    return results


def _row(values: list[float]) -> str:
    return f"{min(values):6.2f} {statistics.median(values):6.2f} {max(values):6.2f}"


async def main(trials: int, down_s: float) -> list[tuple[str, str, list[Trial]]]:
    table: list[tuple[str, str, list[Trial]]] = []
    for driver in DRIVERS:
        for fault in FAULTS:
            table.append((driver, fault, await run(driver, fault, trials, down_s)))
    return table


RECONNECT_PROMISE_S = 5.0
"""docs/reliability-safety.md: a device that comes back is read again within 5 s."""


def report(table: list[tuple[str, str, list[Trial]]]) -> str:
    lines = [
        f"stale_after_s {DEFAULT_STALE_AFTER_S:g} s (default); seconds as min / median / max",
        f"{'driver':<11}{'fault':<7}{'refused':>21}{'down':>21}{'back':>21}",
    ]
    for driver, fault, trials in table:
        lines.append(
            f"{driver:<11}{fault:<7}"
            f"{_row([t.refused_s for t in trials]):>21}"
            f"{_row([t.down_s for t in trials]):>21}"
            f"{_row([t.back_s for t in trials]):>21}"
        )
    for driver, fault, trials in table:
        back = max(t.back_s for t in trials)
        verdict = "PASS" if back <= RECONNECT_PROMISE_S else "MISS"
        lines.append(
            f"goal {driver} {fault}: back within {RECONNECT_PROMISE_S:g} s in every trial: "
            f"{verdict} (worst {back:.2f} s of {len(trials)})"
        )
    return "\n".join(lines)


def cli(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="one trial of each (smoke test)")
    parser.add_argument("--trials", type=int, default=5)
    parser.add_argument("--down", type=float, default=8.0, help="seconds the device stays away")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    logging.getLogger("bench").setLevel(logging.INFO)
    trials = 1 if args.quick else args.trials
    down_s = 3.0 if args.quick else args.down
    print_provenance()
    print(report(asyncio.run(main(trials, down_s))))


if __name__ == "__main__":
    cli()
