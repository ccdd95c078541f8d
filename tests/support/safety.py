"""Rig for the safety tests: a real driver on a real link to a device emulator whose simulated
mount has a permissive horizon (-10°), so only scopelink's own checks and guard keep the tube up.

Everything the device receives is recorded (a spy on the emulator's command handler: what reached
the link, decoded), and the simulated mount's true altitude is sampled in the background.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

from scopelink.astro import Site, angular_separation_deg, observed_to_j2000
from scopelink.drivers.skytracker import SkyTrackerMount
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import Limits, Mount, MountAxis, TrackingMode
from scopelink.protocol.synscan import (
    AnyCommand,
    AnyReply,
    FixedRateSlew,
    GotoAzAlt,
    GotoRaDec,
    VariableRateSlew,
)
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import EQ6, SKY_TRACKER, MountModel, SimClock, SimulatedMount

SITE = Site(latitude_deg=48.0, longitude_deg=11.0, pressure_hpa=0.0)
"""No refraction: the driver's and the simulator's altitudes are then the same geometry."""
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
HORIZON_DEG = 10.0
"""scopelink's configured horizon in these tests (the device's own is -10°)."""
DEVICE_LIMITS = Limits(horizon_deg=-10.0, max_altitude_deg=90.0, sun_avoidance_deg=0.0)
TOLERANCE_DEG = 0.5
"""How far below scopelink's horizon the true altitude may dip during a guarded rate motion:
the guard aims to stop 0.2° above it; the rest absorbs a poll delayed by a loaded CPU."""


def j2000_at(sim: SimulatedMount, alt_deg: float, az_deg: float) -> tuple[float, float]:
    """The J2000 position at an observed alt/az on the simulator's clock now."""
    return observed_to_j2000(alt_deg, az_deg, sim.now(), SITE)


@dataclass
class Rig:
    """A connected driver, the emulator it talks to, the simulated mount behind it."""

    mount: Mount
    sim: SimulatedMount
    received: list[object] = field(default_factory=list)
    """Every command the device received, decoded, in order."""
    min_alt_deg: float = math.inf
    """The lowest true altitude the simulated mount reached while sampled."""
    max_alt_deg: float = -math.inf

    def sample(self) -> float:
        alt, _ = self.sim.observed_at(self.sim.elapsed())
        self.min_alt_deg = min(self.min_alt_deg, alt)
        self.max_alt_deg = max(self.max_alt_deg, alt)
        return alt

    def true_alt(self) -> float:
        return self.sim.observed_at(self.sim.elapsed())[0]

    def gotos_received(self) -> list[object]:
        return [c for c in self.received if isinstance(c, GotoRaDec | GotoAzAlt)]

    def slews_received(self) -> list[object]:
        return [c for c in self.received if isinstance(c, VariableRateSlew | FixedRateSlew)]

    def reset_extremes(self) -> None:
        self.min_alt_deg, self.max_alt_deg = math.inf, -math.inf


async def _sampler(rig: Rig) -> None:
    while True:
        rig.sample()
        await asyncio.sleep(0.002)


async def place(sim: SimulatedMount, alt_deg: float, az_deg: float) -> None:
    """Point the simulated mount at (alt, az) by its own goto and wait for the landing."""
    await sim.goto_horizontal(alt_deg, az_deg)
    await sim.wait_for_slew(timeout_s=10.0)
    await sim.abort()


@asynccontextmanager
async def synscan_rig(
    *,
    model: MountModel = EQ6,
    at: tuple[float, float] = (30.0, 250.0),
    rate: float = 1.0,
    limits: Limits | None = None,
    tracking: bool = False,
    real_time: bool = False,
) -> AsyncIterator[Rig]:
    """The SynScan driver (horizon 10° unless ``limits``) on TCP to the SynScan emulator
    (9600-baud pacing) in front of a simulated ``model`` pointing at ``at`` (alt, az); the
    simulator's clock runs ``rate`` times real time; ``real_time`` sets it to the PC's clock (for
    a driver in another process, which reads the PC's clock)."""
    clock = SimClock.accelerated(500.0, START)
    sim = SimulatedMount(model, site=SITE, clock=clock, limits=DEVICE_LIMITS)
    await sim.connect()
    await place(sim, *at)
    clock.set_rate(rate)
    if real_time:  # the axes stand still, so alt/az stay where they were placed
        clock.set_time(datetime.now(UTC))
    config = SynScanConfig(model=model.synscan_model_code or 0)
    async with SynScanEmulator(sim, config) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(
            f"tcp://{host}:{port}",
            site=SITE,
            clock=sim.now,
            limits=limits or Limits(horizon_deg=HORIZON_DEG),
        )
        rig = Rig(mount, sim)
        hand_control = emulator.hand_control
        answer = hand_control.answer

        async def recording_answer(command: AnyCommand) -> AnyReply:
            rig.received.append(command)
            return await answer(command)

        hand_control.answer = recording_answer  # type: ignore[method-assign]
        await mount.connect()
        if tracking:
            await mount.set_tracking(TrackingMode.SIDEREAL)
        sampler = asyncio.create_task(_sampler(rig))
        try:
            yield rig
        finally:
            sampler.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await sampler
            await mount.disconnect()


@asynccontextmanager
async def skytracker_rig(
    data_dir: Path, *, at: tuple[float, float] = (20.0, 180.0), rate: float = 1.0
) -> AsyncIterator[Rig]:
    """The Sky Tracker driver (horizon 10°) on TCP to the Sky Tracker emulator in front of the
    simulated Sky Tracker pointing at ``at``; every command the box and its Sky Commander
    receive is recorded."""
    clock = SimClock.accelerated(rate, START)
    sim = SimulatedMount(SKY_TRACKER, site=SITE, clock=clock, limits=DEVICE_LIMITS)
    sim.set_axis_position(MountAxis.PRIMARY, at[1])
    sim.set_axis_position(MountAxis.SECONDARY, at[0])
    async with SkyTrackerEmulator(sim, data_dir) as emulator:
        host, port = await emulator.on_tcp()
        mount = SkyTrackerMount(
            f"tcp://{host}:{port}",
            site=SITE,
            clock=sim.clock.now,
            limits=Limits(horizon_deg=HORIZON_DEG),
        )
        rig = Rig(mount, sim)
        tracker, commander = emulator.tracker, emulator.commander
        handle, respond = tracker.handle, commander.respond

        def recording_handle(command: object) -> bytes:
            rig.received.append(command)
            return handle(command)

        def recording_respond(event: object) -> bytes:
            rig.received.append(event)
            return respond(event)

        tracker.handle = recording_handle  # type: ignore[method-assign]
        commander.respond = recording_respond  # type: ignore[method-assign]
        await mount.connect()
        sampler = asyncio.create_task(_sampler(rig))
        try:
            yield rig
        finally:
            sampler.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await sampler
            await mount.disconnect()


async def wait_until_still(rig: Rig, timeout_s: float = 10.0) -> float:
    """Wait until the true pointing moves by less than 0.01°/s (the slew ended; tracking alone
    moves at most 0.004°/s); returns the altitude then."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout_s
    last = rig.sim.observed_at(rig.sim.elapsed())
    while loop.time() < deadline:
        await asyncio.sleep(0.1)
        rig.sample()
        now = rig.sim.observed_at(rig.sim.elapsed())
        if angular_separation_deg(now[1], now[0], last[1], last[0]) < 1e-3:
            return now[0]
        last = now
    raise AssertionError(f"the mount was still moving after {timeout_s} s (alt {last[0]:.2f}°)")
