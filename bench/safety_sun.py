"""How far outside the Sun avoidance zone the guard stops a rate motion, and what the checks cost.

The SynScan driver (zone 15°) talks over TCP to the SynScan emulator (replies paced at 9600 baud),
whose simulated AZ-GTi has no Sun avoidance of its own; the clock starts at 2026-06-21 12:00 UTC at
51.5° N 0° E (the Sun at altitude 62.0°, azimuth 179.1°). Each run turns the azimuth axis towards
the Sun along its altitude and records the true distance to the Sun every 2 ms until the mount
rests: the clearance is the least distance minus the radius (positive = never inside).

Then the CPU cost of the checks a goto runs (the zone at the current time, the target, the slew
path) and of one guard judgement.

    .venv/bin/python -m bench.safety_sun            # rates 0.5 .. 3.34 °/s, then the costs
    .venv/bin/python -m bench.safety_sun --quick    # one rate (the smoke test)
    .venv/bin/python -m bench.safety_sun --noisy    # full speed, 5/15/30 % of replies spoiled
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime

from bench.provenance import print_provenance
from scopelink.astro import PierSide, Site
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import Limits, MountAxis, MountError
from scopelink.mount.sun import SunZone
from scopelink.mount.types import AlignmentMode
from scopelink.servers.faults import Fault, FaultInjector, FaultKind
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import AZ_GTI, SimClock, SimulatedMount

SITE = Site(latitude_deg=51.5, longitude_deg=0.0, pressure_hpa=0.0)
NOON = datetime(2026, 6, 21, 12, 0, tzinfo=UTC)
RADIUS_DEG = 15.0
SUN_ALT_DEG = 62.0
RATES_DEG_S = (0.5, 1.0, 2.0, 3.34)


@dataclass(frozen=True, slots=True)
class Result:
    rate_deg_s: float
    start_distance_deg: float
    closest_deg: float
    stops: int

    @property
    def clearance_deg(self) -> float:
        return self.closest_deg - RADIUS_DEG


def _azimuth_at_distance(distance_deg: float) -> float:
    """The azimuth east of the Sun, at its altitude, that is ``distance_deg`` from it."""
    zone = SunZone(RADIUS_DEG, SITE, NOON, AlignmentMode.ALT_AZ)
    low, high = zone.az_deg - 179.0, zone.az_deg
    for _ in range(50):
        middle = 0.5 * (low + high)
        if zone.distance_deg(zone.alt_deg, middle) > distance_deg:
            low = middle
        else:
            high = middle
    return low % 360.0


async def run_once(
    rate_deg_s: float, lead_deg: float = 3.0, noise: tuple[FaultKind, float, int] | None = None
) -> Result:
    """One run at ``rate_deg_s``; ``noise`` (fault kind, probability, seed) garbles or drops
    that share of the device's replies once the driver is connected (the spec's 5 s timeout)."""
    start_distance = RADIUS_DEG + lead_deg + rate_deg_s * 1.5
    clock = SimClock.accelerated(500.0, NOON)
    sim = SimulatedMount(
        AZ_GTI, site=SITE, clock=clock, limits=Limits(horizon_deg=-10.0, sun_avoidance_deg=0.0)
    )
    await sim.connect()
    await sim.goto_horizontal(SUN_ALT_DEG, _azimuth_at_distance(start_distance))
    await sim.wait_for_slew(timeout_s=30.0)
    await sim.abort()
    clock.set_rate(1.0)
    closest = math.inf
    faults = FaultInjector(seed=noise[2] if noise else 0)
    async with SynScanEmulator(sim, SynScanConfig(model=165), faults=faults) as device:
        host, port = await device.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(
            f"tcp://{host}:{port}",
            site=SITE,
            clock=sim.now,
            limits=Limits(horizon_deg=0.0, sun_avoidance_deg=RADIUS_DEG),
        )
        await mount.connect()
        if noise is not None:
            faults.add(Fault(noise[0], times=None, probability=noise[1]))
        try:
            with contextlib.suppress(MountError):  # a failed start is owed a stop: still guarded
                await mount.move_axis(MountAxis.PRIMARY, rate_deg_s)
            last_az, still = math.nan, 0
            deadline = time.monotonic() + 60.0
            while still < 10 and time.monotonic() < deadline:
                await asyncio.sleep(0.002)
                alt, az = sim.observed_at(sim.elapsed())
                zone = SunZone(RADIUS_DEG, SITE, sim.now(), AlignmentMode.ALT_AZ)
                closest = min(closest, zone.distance_deg(alt, az))
                still = still + 1 if abs(az - last_az) < 1e-4 else 0
                last_az = az
            stops = mount.guard.stops
        finally:
            faults.clear()
            with contextlib.suppress(Exception):
                await mount.abort()
            await mount.disconnect()
    return Result(rate_deg_s, start_distance, closest, stops)


COST_ROUNDS = 5


def check_costs(repeats: int = 200, rounds: int = COST_ROUNDS) -> dict[str, float]:
    """Milliseconds of a goto's Sun checks and of one guard judgement: the mean over
    ``repeats``, the best of ``rounds`` such means."""
    zone = SunZone(RADIUS_DEG, SITE, NOON, AlignmentMode.GERMAN_POLAR)

    def judgement() -> None:
        zone.distance_deg(40.0, 120.0)
        zone.distance_deg(40.1, 120.1, later_s=0.3)

    work: dict[str, Callable[[], object]] = {
        "zone now (Sun's observed position, cached ephemeris)": lambda: SunZone(
            RADIUS_DEG, SITE, NOON, AlignmentMode.GERMAN_POLAR
        ),
        "slew path, 210° of azimuth on an EQ6 (a meridian flip)": lambda: zone.check_slew(
            (30.0, 90.0), PierSide.WEST, (30.0, 300.0)
        ),
        "one guard judgement (two distances)": judgement,
    }
    costs: dict[str, float] = {}
    for what, call in work.items():
        means = []
        for _ in range(rounds):
            started = time.perf_counter()
            for _ in range(repeats):
                call()
            means.append((time.perf_counter() - started) / repeats)
        costs[what] = 1000.0 * min(means)
    return costs


def zone_goal(clearances: list[float]) -> str:
    """The goal line: outside the zone in every run the table shows."""
    worst = min(clearances)
    inside = sum(c < 0.0 for c in clearances)
    return (
        f"goal: outside the Sun's zone (clearance >= 0) in every run: "
        f"{'PASS' if inside == 0 else 'MISS'} ({inside} of {len(clearances)} inside, worst "
        f"{worst:+.2f}°)"
    )


async def _main(rates: tuple[float, ...]) -> list[Result]:
    return [await run_once(rate) for rate in rates]


NOISE_LEVELS = (0.05, 0.15, 0.30)


async def noisy(trials: int) -> None:
    """Full speed towards the Sun with a share of the replies garbled or lost: the worst and
    median clearance per level over ``trials`` seeds."""
    print("| replies | share | worst clearance° | median clearance° | inside |")
    print("| --- | ---: | ---: | ---: | ---: |")
    every: list[float] = []
    for kind in (FaultKind.MALFORMED, FaultKind.DROP):
        for share in NOISE_LEVELS:
            runs = [await run_once(3.34, noise=(kind, share, seed)) for seed in range(trials)]
            clearances = sorted(r.clearance_deg for r in runs)
            every += clearances
            inside = sum(1 for c in clearances if c < 0.0)
            print(
                f"| {kind.value} | {share:.0%} | {clearances[0]:+.2f} | "
                f"{statistics.median(clearances):+.2f} | {inside} |"
            )
    print()
    print(zone_goal(every))


def main(argv: list[str] | None = None) -> list[Result]:
    parser = argparse.ArgumentParser(prog="python -m bench.safety_sun", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="one rate (2°/s), no cost figures")
    parser.add_argument("--noisy", action="store_true", help="full speed on a noisy link")
    parser.add_argument("--trials", type=int, default=5, help="seeds per noise level (--noisy)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    logging.getLogger("scopelink").setLevel(logging.CRITICAL)
    print_provenance()
    if args.noisy:
        asyncio.run(noisy(args.trials))
        return []
    rates = (2.0,) if args.quick else RATES_DEG_S
    results = asyncio.run(_main(rates))
    print("| rate °/s | start distance° | closest° | clearance° | guard stops |")
    print("| ---: | ---: | ---: | ---: | ---: |")
    for r in results:
        print(
            f"| {r.rate_deg_s:.2f} | {r.start_distance_deg:.2f} | {r.closest_deg:.2f} | "
            f"{r.clearance_deg:+.2f} | {r.stops} |"
        )
    print()
    print(zone_goal([r.clearance_deg for r in results]))
    if not args.quick:
        print()
        print(f"costs, the best of {COST_ROUNDS} rounds:")
        for what, ms in check_costs().items():
            print(f"{what}: {ms:.3f} ms")
    return results


if __name__ == "__main__":
    main()
