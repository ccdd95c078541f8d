"""The horizon guard on a noisy Sky Tracker line (issue #11, part 1, for the other driver): with
30 % of the box's and the Sky Commander's replies garbled or lost, a slew down at the UTILITY
arrow speed (4°/s) never carries the tube below the horizon, and the stop goes out at once.

The rig is the benchmark's (``bench.safety_guard.noisy_skytracker``): the Sky Tracker driver on
TCP to the Sky Tracker emulator (9600-baud pacing), whose simulated mount has a permissive -10°
horizon; scopelink's is 10°. Faults are armed after the connect, on any command of the box and of
the Sky Commander, from seeded generators.
"""

from __future__ import annotations

import asyncio
import contextlib
from pathlib import Path

import pytest
from bench.safety_guard import (
    HORIZON_DEG,
    SKYTRACKER_START_ALT_DEG,
    lowest_until_rest,
    noisy_skytracker,
)

from scopelink.mount import MountAxis, MountError
from scopelink.protocol.skytracker import ReleaseDirections
from scopelink.servers.faults import Fault, FaultKind


@pytest.mark.parametrize("kind", [FaultKind.MALFORMED, FaultKind.DROP])
async def test_a_slew_down_never_ends_below_the_horizon_on_a_noisy_line(
    tmp_path: Path, kind: FaultKind
) -> None:
    # One seed per kind here (a trial takes 4-5 s); the benchmark runs five per level.
    async with noisy_skytracker(tmp_path, kind, 0.3, seed=0) as (mount, sim, _, _received):
        with contextlib.suppress(MountError):
            await mount.move_axis(MountAxis.SECONDARY, -4.0)
        lowest = await lowest_until_rest(sim)
        assert lowest >= HORIZON_DEG, lowest
        assert lowest < SKYTRACKER_START_ALT_DEG - 1.0  # it did move


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
        assert reached_s < 1.0, reached_s  # never, before the fix
