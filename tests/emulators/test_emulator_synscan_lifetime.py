"""The SynScan emulator switches off what it switched on: a mount it connected on entry is
disconnected on exit, so none of the mount's watchers (the meridian watch of a tracking mount)
outlives the emulator. A mount the caller connected stays the caller's."""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime

from scopelink.astro import Site
from scopelink.mount import TrackingMode
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(40.4, -3.7)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)


def _connected(mount: SimulatedMount) -> bool:
    """A call, so mypy does not narrow the state across the exit."""
    return mount.state.connected


def _others() -> set[asyncio.Task[object]]:
    current = asyncio.current_task()
    return {task for task in asyncio.all_tasks() if task is not current}


async def test_a_mount_the_emulator_connected_is_switched_off_with_it() -> None:
    before = _others()
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.accelerated(1.0, START))
    async with SynScanEmulator(mount, wire=None) as emulator:
        await emulator.on_tcp("127.0.0.1", 0)
        await mount.set_tracking(TrackingMode.SIDEREAL)
        assert _connected(mount)
    assert not _connected(mount)
    await asyncio.sleep(0.3)  # the watchers' own wake-up period is 0.25 s at most
    assert {task.get_name() for task in _others() - before} == set()


async def test_a_mount_the_caller_connected_stays_connected() -> None:
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.accelerated(1.0, START))
    await mount.connect()
    async with SynScanEmulator(mount, wire=None) as emulator:
        await emulator.on_tcp("127.0.0.1", 0)
    assert mount.state.connected
    await mount.disconnect()
