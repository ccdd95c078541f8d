"""A rig for the meridian-limit tests: the SynScan driver, with its own limits, in front of the
emulated hand control, whose simulated German mount has limits of its own (the hand control's
choice of pier side), on an accelerated clock."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from scopelink.astro import lst_hours
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import Limits, Mount
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.synscan_driver import MADRID, START


def ra_j2000_at_hour_angle(mount: Mount, ha_hours: float) -> float:
    """A J2000 RA at about ``ha_hours`` from the meridian now (precession is ~0.4 min here)."""
    return (lst_hours(mount.now(), mount.site.longitude_deg) - ha_hours) % 24.0


@asynccontextmanager
async def synscan_rig(
    limits: Limits, *, hand_control: Limits, speed_up: float
) -> AsyncIterator[tuple[SynScanMount, SimulatedMount]]:
    """The driver (``limits``) on TCP in front of the emulator, whose simulated mount picks its
    pier side under ``hand_control``; the clock runs ``speed_up`` times real time."""
    clock = SimClock.accelerated(speed_up, START)
    sim = SimulatedMount(EQ6, site=MADRID, clock=clock, limits=hand_control)
    async with SynScanEmulator(sim) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(f"tcp://{host}:{port}", site=MADRID, clock=sim.now, limits=limits)
        await mount.connect()
        try:
            async with mount.watching():
                yield mount, sim
        finally:
            await mount.disconnect()
