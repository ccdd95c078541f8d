"""Helpers for the Sky Tracker driver tests: the real emulator on a pty or TCP, the driver on it."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from scopelink.astro import Site, angular_separation_deg, observed_to_j2000
from scopelink.drivers.skytracker import BusOptions, SkyTrackerMount
from scopelink.links import Link, open_link
from scopelink.mount import Limits, MountAxis
from scopelink.protocol.skytracker import TrackerMode
from scopelink.servers.faults import FaultInjector
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.sim import SKY_TRACKER, SimClock, SimulatedMount

SITE = Site(latitude_deg=48.0, longitude_deg=11.0, pressure_hpa=0.0)
EPOCH = datetime(2026, 1, 1, 20, 0, tzinfo=UTC)
CLOCK_RATE = 40.0
"""Simulated seconds per real second: a 30 s GOTO takes 0.75 s."""
TRANSPORTS = ["pty", "tcp"]
FAST = BusOptions(retry_delays_s=(0.05, 0.1, 0.2))
FAST_TIMEOUT_S = 0.5
"""Spec timing (100 ms grant), shorter reply timeout and back-off so fault tests stay quick."""


def sky_tracker_mount(rate: float = CLOCK_RATE) -> SimulatedMount:
    """The Sky Tracker alt-az preset on an accelerated clock, level and pointing north."""
    return SimulatedMount(SKY_TRACKER, site=SITE, clock=SimClock.accelerated(rate, EPOCH))


def sky_at(sim: SimulatedMount, alt_deg: float, az_deg: float) -> tuple[float, float]:
    """J2000 of an observed alt/az now: a target that is where we want it in the sky."""
    return observed_to_j2000(alt_deg, az_deg, sim.clock.now(), SITE)


def separation_deg(a: tuple[float, float], b: tuple[float, float]) -> float:
    """Angle between two J2000 (RA hours, Dec degrees) positions."""
    return float(angular_separation_deg(a[0] * 15.0, a[1], b[0] * 15.0, b[1]))


@dataclass
class Rig:
    emulator: SkyTrackerEmulator
    sim: SimulatedMount
    driver: SkyTrackerMount
    spec: str

    def sim_j2000(self) -> tuple[float, float]:
        return self.sim.j2000_at(self.sim.elapsed())

    def point(self, alt_deg: float, az_deg: float) -> tuple[float, float]:
        """Put the scope at an alt/az at once (no GOTO: quicker where the GOTO is not tested);
        returns the J2000 position there."""
        self.sim.set_axis_position(MountAxis.PRIMARY, az_deg)
        self.sim.set_axis_position(MountAxis.SECONDARY, alt_deg)
        return self.sim_j2000()


async def serve(emulator: SkyTrackerEmulator, transport: str) -> str:
    """Serve ``emulator`` on a new pty or TCP port; the driver's link spec for it."""
    if transport == "pty":
        return await emulator.on_pty()
    host, port = await emulator.on_tcp()
    return f"tcp://{host}:{port}"


@asynccontextmanager
async def rig(
    data_dir: Path,
    transport: str,
    *,
    faults: FaultInjector | None = None,
    strict_line: bool = False,
    timeout_s: float = FAST_TIMEOUT_S,
    bus: BusOptions = FAST,
    connect: bool = True,
    limits: Limits | None = None,
    guide_speed_arcsec_s: int | None = None,
    clock_rate: float = CLOCK_RATE,
    pace: bool = True,
) -> AsyncIterator[Rig]:
    """Emulator + driver; the driver is disconnected and the emulator stopped afterwards.

    ``pace=False`` drops the 9600-baud pacing both ways (replies and sends come at once): for
    tests of the logic that run many emulators at once and need not the wire's timing.
    """
    sim = sky_tracker_mount(clock_rate)
    async with SkyTrackerEmulator(
        sim, data_dir, faults=faults, strict_line=strict_line, pace=pace
    ) as emulator:
        spec = await serve(emulator, transport)

        async def unpaced() -> Link:
            return await open_link(spec)

        driver = SkyTrackerMount(
            spec if pace else unpaced,
            site=SITE,
            clock=sim.clock.now,
            timeout_s=timeout_s,
            bus=bus,
            limits=limits,
            guide_speed_arcsec_s=guide_speed_arcsec_s,
            name=spec,
        )
        if connect:
            await driver.connect()
        try:
            yield Rig(emulator, sim, driver, spec)
        finally:
            await driver.disconnect()


POSITION_TOLERANCE_DEG = 0.02
"""The Sky Commander rounds RA/Dec to 3 decimals (RA 0.001 h = 0.015°·cos δ) both ways (``L99``
and position), and tracks in 0.5 s ticks."""


async def eventually(condition: Callable[[], bool], timeout_s: float = 5.0) -> None:
    """Wait until ``condition()`` holds (the emulator runs on its own)."""
    async with asyncio.timeout(timeout_s):
        while not condition():  # noqa: ASYNC110 - the emulator offers no event to wait on
            await asyncio.sleep(0.01)


def box_mode(rig_: Rig) -> TrackerMode:
    """The emulated box's mode (a function, so type checkers do not narrow it between reads)."""
    return rig_.emulator.tracker.mode


def driver_position(rig_: Rig) -> tuple[float, float]:
    state = rig_.driver.state
    assert state.ra_j2000_hours is not None
    assert state.dec_j2000_deg is not None
    return state.ra_j2000_hours, state.dec_j2000_deg


async def assert_position_matches_sim(rig_: Rig) -> None:
    """A refresh reads where the simulator points, between readings of the sim around it."""
    before = rig_.sim_j2000()
    await rig_.driver.refresh()
    after = rig_.sim_j2000()
    read = driver_position(rig_)
    assert min(separation_deg(read, before), separation_deg(read, after)) < POSITION_TOLERANCE_DEG
