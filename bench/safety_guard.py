"""How close to the horizon the guard stops a rate motion, by rate, on a paced SynScan line.

The SynScan driver talks over TCP to the SynScan emulator (replies paced at 9600 baud, like the
hand control's serial port), whose simulated EQ6 has a permissive -10° horizon; scopelink's horizon
is 10°. Each run starts the polar axis westwards low in the west (which lowers the tube) and
records the simulated mount's true altitude every 2 ms until it rests. Reported per rate: where the
guard decided to stop, the lowest true altitude (its clearance above the horizon: positive = safe)
and the poll period the guard measured.

    .venv/bin/python -m bench.safety_guard            # rates 0.25 .. 3.34 °/s
    .venv/bin/python -m bench.safety_guard --quick    # one rate (the smoke test)
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import math
from dataclasses import dataclass
from datetime import UTC, datetime

from scopelink.astro import Site
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import Limits, MountAxis
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(latitude_deg=48.0, longitude_deg=11.0, pressure_hpa=0.0)
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
HORIZON_DEG = 10.0
RATES_DEG_S = (0.25, 0.5, 1.0, 2.0, 3.34)


@dataclass(frozen=True, slots=True)
class Result:
    rate_deg_s: float
    start_alt_deg: float
    lowest_alt_deg: float
    stops: int
    polls: int
    seconds: float

    @property
    def clearance_deg(self) -> float:
        return self.lowest_alt_deg - HORIZON_DEG


async def run_once(rate_deg_s: float, lead_deg: float = 2.0) -> Result:
    # Start where the motion needs a few seconds to reach the horizon, braking included.
    start_alt = HORIZON_DEG + lead_deg + rate_deg_s * 1.5
    clock = SimClock.accelerated(500.0, START)
    sim = SimulatedMount(
        EQ6, site=SITE, clock=clock, limits=Limits(horizon_deg=-10.0, max_altitude_deg=90.0)
    )
    await sim.connect()
    await sim.goto_horizontal(start_alt, 250.0)
    await sim.wait_for_slew(timeout_s=30.0)
    await sim.abort()
    clock.set_rate(1.0)
    lowest = math.inf
    async with SynScanEmulator(sim) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(
            f"tcp://{host}:{port}",
            site=SITE,
            clock=sim.now,
            limits=Limits(horizon_deg=HORIZON_DEG),
        )
        await mount.connect()
        loop = asyncio.get_running_loop()
        began = loop.time()
        polls_before = mount.poller.polls
        await mount.move_axis(MountAxis.PRIMARY, rate_deg_s)
        still_since = loop.time()
        previous = sim.observed_at(sim.elapsed())[0]
        while loop.time() - still_since < 0.3 and loop.time() - began < 60.0:
            await asyncio.sleep(0.002)
            alt = sim.observed_at(sim.elapsed())[0]
            lowest = min(lowest, alt)
            if abs(alt - previous) > 1e-6:
                still_since = loop.time()
            previous = alt
        polls = mount.poller.polls - polls_before
        stops = mount.guard.stops
        with contextlib.suppress(Exception):
            await mount.disconnect()
    return Result(rate_deg_s, start_alt, lowest, stops, polls, loop.time() - began)


async def main(rates: tuple[float, ...], lead_deg: float = 2.0) -> list[Result]:
    logging.getLogger("scopelink.mount.guard").setLevel(logging.ERROR)
    results = [await run_once(rate, lead_deg) for rate in rates]
    print(f"horizon {HORIZON_DEG}°, SynScan emulator paced at 9600 baud, EQ6 (brakes at 3.3°/s²)")
    print("rate °/s  start alt°  lowest alt°  clearance°  guard stops  polls  run s")
    for r in results:
        print(
            f"{r.rate_deg_s:8.2f}  {r.start_alt_deg:10.2f}  {r.lowest_alt_deg:11.2f}  "
            f"{r.clearance_deg:10.2f}  {r.stops:11d}  {r.polls:5d}  {r.seconds:5.1f}"
        )
    return results


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--quick", action="store_true", help="one rate only")
    args = parser.parse_args()
    asyncio.run(main((1.0,) if args.quick else RATES_DEG_S))
