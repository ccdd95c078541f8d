"""Shared rig for the SynScan driver tests: the real emulator on a real pty or TCP socket, the
driver connected to it, and the simulated mount behind the emulator to check positions against."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from datetime import UTC, datetime

from scopelink.astro import Site, angular_separation_deg
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import MountState
from scopelink.protocol.synscan import AnyCommand, AnyReply
from scopelink.servers.faults import FaultInjector
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import EQ6, MountModel, SimClock, SimulatedMount

PRECISE_UNIT_DEG = 360.0 / 2**24
MADRID = Site(40.4, -3.7, elevation_m=650.0)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)
TRANSPORTS = ["pty", "tcp"]


@dataclass
class Rig:
    """A connected driver, the emulator it talks to and the simulated mount behind it."""

    mount: SynScanMount
    sim: SimulatedMount
    emulator: SynScanEmulator
    spec: str


@asynccontextmanager
async def rig(
    transport: str = "tcp",
    *,
    config: SynScanConfig | None = None,
    model: MountModel = EQ6,
    clock: SimClock | None = None,
    timeout_s: float = 5.0,
    faults: FaultInjector | None = None,
    site: Site = MADRID,
    connect: bool = True,
) -> AsyncIterator[Rig]:
    """The driver on ``transport`` ("pty" or "tcp") in front of an emulated hand control.

    The simulated clock is stepped by default (positions change only when a test steps it), and
    the driver reads the same clock, so its computed alt/az must match the simulator exactly.
    """
    sim = SimulatedMount(model, site=site, clock=clock or SimClock.stepped(START))
    async with SynScanEmulator(sim, config, faults=faults) as emulator:
        if transport == "pty":
            spec = await emulator.on_pty()
        else:
            host, port = await emulator.on_tcp("127.0.0.1", 0)
            spec = f"tcp://{host}:{port}"
        mount = SynScanMount(spec, site=site, clock=sim.now, timeout_s=timeout_s)
        if connect:
            await mount.connect()
        try:
            yield Rig(mount, sim, emulator, spec)
        finally:
            await mount.disconnect()


def assert_position_matches(
    state: MountState, truth: MountState, tolerance_deg: float = 2 * PRECISE_UNIT_DEG
) -> None:
    """The driver's reading points where the simulator says (RA/Dec and alt/az)."""
    assert state.ra_j2000_hours is not None
    assert state.dec_j2000_deg is not None
    assert truth.ra_j2000_hours is not None
    assert truth.dec_j2000_deg is not None
    equatorial = angular_separation_deg(
        state.ra_j2000_hours * 15.0,
        state.dec_j2000_deg,
        truth.ra_j2000_hours * 15.0,
        truth.dec_j2000_deg,
    )
    assert equatorial <= tolerance_deg, (state, truth)
    assert state.alt_deg is not None
    assert state.az_deg is not None
    assert truth.alt_deg is not None
    assert truth.az_deg is not None
    horizontal = angular_separation_deg(state.az_deg, state.alt_deg, truth.az_deg, truth.alt_deg)
    assert horizontal <= tolerance_deg, (state, truth)


def record_commands(emulator: SynScanEmulator) -> list[AnyCommand]:
    """Every command the emulated hand control answers from now on, in order (observed, not
    changed: its own handler answers each)."""
    seen: list[AnyCommand] = []
    answer = emulator.hand_control.answer

    async def recorded(command: AnyCommand) -> AnyReply:
        seen.append(command)
        return await answer(command)

    emulator.hand_control.answer = recorded  # type: ignore[method-assign]
    return seen
