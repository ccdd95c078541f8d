"""The horizon guard on a noisy Sky Tracker line (issue #11, part 1, for the other driver): with
30 % of the box's and the Sky Commander's replies garbled or lost, a slew down at the UTILITY
arrow speed (4°/s) never carries the tube below the horizon, and the stop goes out at once.

The Sky Tracker driver on TCP to the Sky Tracker emulator (9600-baud pacing), whose simulated
mount has a permissive -10° horizon; scopelink's is 10°. Faults are armed after the connect, on
any command of the box and of the Sky Commander, from seeded generators.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

import pytest

from scopelink.drivers.skytracker import SkyTrackerMount
from scopelink.mount import Limits, MountAxis, MountError
from scopelink.protocol.skytracker import ReleaseDirections
from scopelink.servers.faults import Fault, FaultInjector, FaultKind
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.sim import SKY_TRACKER, SimClock, SimulatedMount
from tests.test_safety_support import DEVICE_LIMITS, HORIZON_DEG, SITE, START

START_ALT_DEG = 22.0
"""At 4°/s the guard's budget (5.3° of braking at 1.5°/s², and the stop's latency) is reached
after about 2 s of motion (the box ramps up at 2°/s²)."""


@asynccontextmanager
async def noisy_skytracker(
    data_dir: Path, kind: FaultKind, probability: float, seed: int
) -> AsyncIterator[tuple[SkyTrackerMount, SimulatedMount, SkyTrackerEmulator, list[object]]]:
    sim = SimulatedMount(
        SKY_TRACKER, site=SITE, clock=SimClock.accelerated(1.0, START), limits=DEVICE_LIMITS
    )
    sim.set_axis_position(MountAxis.PRIMARY, 180.0)
    sim.set_axis_position(MountAxis.SECONDARY, START_ALT_DEG)
    faults, commander_faults = FaultInjector(seed=seed), FaultInjector(seed=seed + 1000)
    received: list[object] = []
    async with SkyTrackerEmulator(
        sim, data_dir, faults=faults, commander_faults=commander_faults
    ) as emulator:
        handle = emulator.tracker.handle

        def recording_handle(command: object) -> bytes:
            received.append(command)
            return handle(command)

        emulator.tracker.handle = recording_handle  # type: ignore[method-assign]
        host, port = await emulator.on_tcp()
        mount = SkyTrackerMount(
            f"tcp://{host}:{port}",
            site=SITE,
            clock=sim.clock.now,
            limits=Limits(horizon_deg=HORIZON_DEG),
        )
        await mount.connect()
        for injector in (faults, commander_faults):
            injector.add(Fault(kind, times=None, probability=probability))
        try:
            yield mount, sim, emulator, received
        finally:
            faults.clear()
            commander_faults.clear()
            with contextlib.suppress(MountError):
                await mount.disconnect()


async def lowest_until_rest(sim: SimulatedMount, timeout_s: float = 20.0) -> float:
    loop = asyncio.get_running_loop()
    lowest = math.inf
    began = still_since = loop.time()
    previous = sim.observed_at(sim.elapsed())[0]
    while loop.time() - still_since < 0.5 and loop.time() - began < timeout_s:
        await asyncio.sleep(0.002)
        alt = sim.observed_at(sim.elapsed())[0]
        lowest = min(lowest, alt)
        if abs(alt - previous) > 1e-6:
            still_since = loop.time()
        previous = alt
    return lowest


@pytest.mark.parametrize("kind", [FaultKind.MALFORMED, FaultKind.DROP])
async def test_a_slew_down_never_ends_below_the_horizon_on_a_noisy_line(
    tmp_path: Path, kind: FaultKind
) -> None:
    for seed in range(2):
        async with noisy_skytracker(tmp_path, kind, 0.3, seed) as (mount, sim, _, _received):
            with contextlib.suppress(MountError):
                await mount.move_axis(MountAxis.SECONDARY, -4.0)
            lowest = await lowest_until_rest(sim)
            assert lowest >= HORIZON_DEG, (seed, lowest)
            assert lowest < START_ALT_DEG - 1.0  # it did move


async def test_a_stop_goes_out_at_once_while_a_reply_is_missing(tmp_path: Path) -> None:
    # Every reply lost from now on: the stop must not wait for the poll's reply timeout nor for
    # the resynchronisation after it.
    async with noisy_skytracker(tmp_path, FaultKind.DROP, 0.01, 0) as (mount, _, emulator, got):
        await mount.move_axis(MountAxis.PRIMARY, 1.0)  # panning: no limit near
        async with mount.watching():
            await asyncio.sleep(0.2)
            emulator.faults.add(Fault(FaultKind.DROP, times=None))
            emulator.commander_faults.add(Fault(FaultKind.DROP, times=None))
            await asyncio.sleep(0.3)  # a poll is waiting for its reply now
            releases = sum(isinstance(c, ReleaseDirections) for c in got)
            loop = asyncio.get_running_loop()
            began = loop.time()
            abort = asyncio.create_task(mount.abort())
            while sum(isinstance(c, ReleaseDirections) for c in got) == releases:
                await asyncio.sleep(0.002)
                assert loop.time() - began < 5.0
            reached_s = loop.time() - began
            abort.cancel()
            with contextlib.suppress(asyncio.CancelledError, MountError):
                await abort
        assert reached_s < 0.3, reached_s
