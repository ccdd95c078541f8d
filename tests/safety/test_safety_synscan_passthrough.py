"""The SynScan server of ``scopelink serve`` in front of the simulated mount: the motor
passthrough commands "slow goto" and "set axis position" would move an axis counter directly,
past every check of the Mount API (the horizon, the Sun, ``limits.max_sync_deg``). The bridge
answers them as over a real device (no motor controller behind it); the device emulator
(``scopelink emulate``) keeps carrying them out, as a real hand control does."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime

from scopelink.astro import Site
from scopelink.links import Link, open_tcp
from scopelink.mount import Limits
from scopelink.protocol.synscan import (
    Axis,
    PassthroughFailed,
    SetAxisPosition,
    SlowGoto,
    SynScanClientConnection,
)
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import AZ_GTI, SimClock, SimulatedMount
from tests.support.synscan import ask

SITE = Site(51.5, 0.0, pressure_hpa=0.0)
NIGHT = datetime(2026, 1, 10, 23, 0, tzinfo=UTC)
HORIZON_DEG = 10.0


@asynccontextmanager
async def served(*, bridge: bool) -> AsyncIterator[tuple[SimulatedMount, Link]]:
    """The simulated AZ-GTi at altitude 20° behind a SynScan server set up as ``serve`` sets it
    up (``bridge``) or as ``scopelink emulate`` does."""
    clock = SimClock.stepped(NIGHT)
    mount = SimulatedMount(AZ_GTI, site=SITE, clock=clock, limits=Limits(horizon_deg=HORIZON_DEG))
    await mount.connect()
    await mount.goto_horizontal(20.0, 180.0)
    clock.advance(60.0)
    config = SynScanConfig(model=AZ_GTI.synscan_model_code or 0)
    emulator = (
        SynScanEmulator(mount, config, wire=None, dead_man=True, axis_passthrough=False)
        if bridge
        else SynScanEmulator(mount, config, wire=None)
    )
    async with emulator:
        link = await open_tcp(*await emulator.on_tcp("127.0.0.1", 0))
        async with link:
            yield mount, link


async def test_serve_refuses_a_slow_goto_below_the_horizon() -> None:
    async with served(bridge=True) as (mount, link):
        client = SynScanClientConnection()
        reply = await ask(link, client, SlowGoto.from_degrees(Axis.ALT_DEC, -5.0))
        assert isinstance(reply, PassthroughFailed)
        mount.clock.advance(60.0)
        state = await mount.refresh()
        assert state.alt_deg is not None
        assert state.alt_deg > 19.0  # it did not move


async def test_serve_refuses_to_redefine_an_axis_counter() -> None:
    async with served(bridge=True) as (mount, link):
        client = SynScanClientConnection()
        before = await mount.refresh()
        reply = await ask(link, client, SetAxisPosition.from_degrees(Axis.ALT_DEC, 60.0))
        assert isinstance(reply, PassthroughFailed)
        after = await mount.refresh()
        assert after.alt_deg == before.alt_deg


async def test_the_emulated_hand_control_carries_a_slow_goto_out_as_the_device_does() -> None:
    async with served(bridge=False) as (mount, link):
        client = SynScanClientConnection()
        await ask(link, client, SlowGoto.from_degrees(Axis.ALT_DEC, 30.0))
        mount.clock.advance(60.0)
        state = await mount.refresh()
        assert state.alt_deg is not None
        assert abs(state.alt_deg - 30.0) < 0.5
