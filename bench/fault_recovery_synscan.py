"""What each injected fault costs the SynScan driver at the spec's 5 s timeout.

For every fault the emulator injects, one driver on its own emulated hand control (9600-baud paced
memory link, reopened through the driver's factory after a ``close``) polls the position (``e``,
an 18-byte reply) with the fault armed on ``e``. A hang (stall, halt) is cleared as soon as the
poll has failed. Reported per fault: how the poll ended, how long it took, the same as a multiple
of the timeout (the reference: a driver must wait that long before it may call a reply lost), and
how long the first poll after the fault took. Every position read is checked against the
simulator (a reply attributed to the wrong command would show as a wrong position: the run then
fails).

The second table is the safety figure: an axis turning at 1°/s, its stop lost on a hung link
(stall or halt on ``P``) while the state poller runs (as under ``scopelink serve``); measured is
the time from the device answering again to the axis standing still, with no user command.

Every figure is the worst of ``--trials`` trials (3): a recovery time's best would flatter.

    .venv/bin/python -m bench.fault_recovery_synscan            # the spec's 5 s timeout, ~45 s
    .venv/bin/python -m bench.fault_recovery_synscan --quick    # 0.5 s timeout, ~2 s

See ``docs/reliability-faults-synscan.md``.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import time
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from dataclasses import dataclass
from datetime import UTC, datetime

from bench.provenance import print_provenance
from scopelink.astro import Site, angular_separation_deg
from scopelink.drivers.synscan import SynScanMount
from scopelink.links import Link
from scopelink.mount import DeviceError, MountAxis, MountState
from scopelink.servers.faults import Fault, FaultInjector, FaultKind
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(40.4, -3.7, elevation_m=650.0)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)
E_REPLY_BYTES = 18
PRECISE_UNIT_DEG = 360.0 / 2**24


@dataclass(frozen=True, slots=True)
class Case:
    name: str
    fault: Callable[[float], Fault | None]
    """The fault for a timeout of the given seconds (None: the baseline)."""


def _slow(total: float) -> Callable[[float], Fault]:
    return lambda t: Fault(FaultKind.SLOW, "e", seconds=total * t / (E_REPLY_BYTES - 1))


CASES = [
    Case("no fault", lambda _t: None),
    Case("drop", lambda _t: Fault(FaultKind.DROP, "e")),
    Case("short", lambda _t: Fault(FaultKind.SHORT, "e")),
    Case("malformed", lambda _t: Fault(FaultKind.MALFORMED, "e")),
    Case("delay 0.9 x timeout", lambda t: Fault(FaultKind.DELAY, "e", seconds=0.9 * t)),
    Case("delay 1.2 x timeout", lambda t: Fault(FaultKind.DELAY, "e", seconds=1.2 * t)),
    Case("delay 2.5 x timeout", lambda t: Fault(FaultKind.DELAY, "e", seconds=2.5 * t)),
    Case("slow, 0.9 x timeout", _slow(0.9)),
    Case("slow, 1.2 x timeout", _slow(1.2)),
    Case("stall", lambda _t: Fault(FaultKind.STALL, "e")),
    Case("halt", lambda _t: Fault(FaultKind.HALT, "e")),
    Case("close and reopen", lambda _t: Fault(FaultKind.CLOSE, "e")),
]


Rig = tuple[SynScanMount, SimulatedMount, FaultInjector]


@dataclass(frozen=True, slots=True)
class Result:
    case: str
    outcome: str
    poll_s: float
    next_poll_s: float


@asynccontextmanager
async def driver(timeout_s: float) -> AsyncIterator[Rig]:
    sim = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped(START))
    faults = FaultInjector()
    async with SynScanEmulator(sim, faults=faults) as emulator:

        async def open_memory() -> Link:
            return await emulator.on_memory()

        mount = SynScanMount(open_memory, site=SITE, clock=sim.now, timeout_s=timeout_s)
        await mount.connect()
        try:
            yield mount, sim, faults
        finally:
            await mount.disconnect()


def check_position(state: MountState, sim: SimulatedMount) -> None:
    truth = sim.snapshot()
    assert state.ra_j2000_hours is not None
    assert state.dec_j2000_deg is not None
    assert truth.ra_j2000_hours is not None
    assert truth.dec_j2000_deg is not None
    error = angular_separation_deg(
        state.ra_j2000_hours * 15,
        state.dec_j2000_deg,
        truth.ra_j2000_hours * 15,
        truth.dec_j2000_deg,
    )
    if error > 2 * PRECISE_UNIT_DEG:
        raise SystemExit(f"a position {error:.6f}° from the truth was read: wrong attribution")


async def run_case(case: Case, timeout_s: float) -> Result:
    async with driver(timeout_s) as (mount, sim, faults):
        fault = case.fault(timeout_s)
        if fault is not None:
            faults.add(fault)
        started = time.perf_counter()
        try:
            check_position(await mount.refresh(), sim)
            failures = mount.wire.statistics.failures
            outcome = "recovered" if failures else "answered"
        except DeviceError:
            outcome = "error"
        poll_s = time.perf_counter() - started
        faults.resume()
        started = time.perf_counter()
        state = await mount.refresh()
        next_poll_s = time.perf_counter() - started
        check_position(state, sim)
        return Result(case.name, outcome, poll_s, next_poll_s)


async def lost_stop(kind: FaultKind, timeout_s: float) -> float:
    """Seconds from the device answering again to the axis standing still (poller only)."""
    async with driver(timeout_s) as (mount, sim, faults), mount.watching():
        await mount.move_axis(MountAxis.PRIMARY, 1.0)
        faults.add(Fault(kind, "P"))
        try:
            await mount.move_axis(MountAxis.PRIMARY, 0.0)
        except DeviceError:
            pass
        else:
            raise SystemExit("the stop on a hung link did not fail")
        faults.resume()
        started = time.perf_counter()
        await mount.wait_for(lambda state: not state.slewing, timeout_s=10 * timeout_s)
        elapsed = time.perf_counter() - started
        motor = sim.axes[MountAxis.PRIMARY.value]
        later = sim.elapsed() + 60.0
        if not motor.is_following_at(later) and motor.rate_at(later) != 0.0:
            raise SystemExit(f"{kind}: the axis still turns after the link came back")
        return elapsed


HANGS = (FaultKind.STALL, FaultKind.HALT)


def worst(trials: list[Result]) -> Result:
    """The worst of a case's trials: the longest times, and "mixed" if the outcomes differ."""
    outcomes = {trial.outcome for trial in trials}
    return Result(
        trials[0].case,
        outcomes.pop() if len(outcomes) == 1 else "mixed",
        max(trial.poll_s for trial in trials),
        max(trial.next_poll_s for trial in trials),
    )


async def main(timeout_s: float, trials: int = 1) -> None:
    """Both tables, each figure the worst of ``trials`` (a recovery time's best would flatter)."""
    runs = [
        await asyncio.gather(
            asyncio.gather(*(run_case(case, timeout_s) for case in CASES)),
            asyncio.gather(*(lost_stop(kind, timeout_s) for kind in HANGS)),
        )
        for _ in range(trials)
    ]
    results = [worst(list(case_trials)) for case_trials in zip(*(r[0] for r in runs), strict=True)]
    stops = [max(kind_trials) for kind_trials in zip(*(r[1] for r in runs), strict=True)]
    print(
        f"SynScan driver fault recovery, timeout {timeout_s:g} s (fault on 'e', 18-byte reply), "
        f"worst of {trials} trial(s)"
    )
    print(f"{'fault':22} {'outcome':10} {'poll s':>8} {'x timeout':>10} {'next poll s':>12}")
    for result in results:
        print(
            f"{result.case:22} {result.outcome:10} {result.poll_s:8.2f} "
            f"{result.poll_s / timeout_s:10.2f} {result.next_poll_s:12.3f}"
        )
    print()
    print("stop lost on a hung link, poller running: link back -> axis still")
    for kind, seconds in zip(HANGS, stops, strict=True):
        print(f"{kind.value:22} {seconds:8.3f} s  ({seconds / timeout_s:.2f} x timeout)")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a 0.5 s timeout: about 2 s")
    parser.add_argument("--timeout", type=float, default=5.0, help="the driver's timeout, s")
    parser.add_argument("--trials", type=int, default=3, help="trials; the worst counts")
    arguments = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)  # the driver's warnings about the faults are expected
    print_provenance()
    trials = 1 if arguments.quick else max(1, arguments.trials)
    asyncio.run(main(0.5 if arguments.quick else arguments.timeout, trials))
