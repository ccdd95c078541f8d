"""The emulated hand control switched off and on (issue #15 part 2, docs/parking.md): the tube
stays, the counters restart at their power-on values, the alignment is forgotten; seen by a
SynScan client over TCP, byte for byte."""

from __future__ import annotations

from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager
from datetime import UTC, datetime

import pytest

from scopelink.astro import Site, angular_separation_deg
from scopelink.links import open_tcp
from scopelink.mount import InvalidValueError, PierSide, TrackingMode
from scopelink.protocol.synscan import (
    Aligned,
    AnyCommand,
    AnyReply,
    Axis,
    GetAzAlt,
    GotoRaDec,
    IsAligned,
    Position,
    SetAxisPosition,
    SynScanClientConnection,
)
from scopelink.servers.synscan import SynScanEmulator
from scopelink.servers.synscan.device import SynScanHandControl
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.parking import tube_altaz
from tests.support.synscan import ask
from tests.support.synscan_driver import rig

MADRID = Site(40.4, -3.7)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)


Asker = Callable[[AnyCommand], Awaitable[AnyReply]]


def _sim() -> SimulatedMount:
    return SimulatedMount(EQ6, site=MADRID, clock=SimClock.stepped(START))


@asynccontextmanager
async def _client(sim: SimulatedMount) -> AsyncIterator[tuple[SynScanEmulator, Asker]]:
    """The emulator in front of ``sim`` and a SynScan client of it over TCP."""
    async with SynScanEmulator(sim) as emulator:
        link = await open_tcp(*await emulator.on_tcp("127.0.0.1", 0))
        async with link:
            client = SynScanClientConnection()

            async def asker(command: AnyCommand) -> AnyReply:
                return await ask(link, client, command)

            yield emulator, asker


async def test_power_cycle_keeps_the_tube_and_forgets_counters_and_alignment() -> None:
    sim = _sim()
    async with _client(sim) as (emulator, asker):
        await sim.goto_horizontal(40.0, 120.0)
        await sim.set_tracking(TrackingMode.SIDEREAL)
        sim.step(120.0)
        tube = tube_altaz(sim)
        assert await asker(IsAligned()) == Aligned(True)

        await emulator.power_cycle()

        sim.step(5.0)  # the tube did not move (but for the tracking motor's stop, 0.01")
        assert tube_altaz(sim) == pytest.approx(tube, abs=1e-4)
        tube = tube_altaz(sim)
        assert [axis.position for axis in sim.axes] == pytest.approx([0.0, 90.0], abs=1e-4)
        assert await asker(IsAligned()) == Aligned(False)
        assert sim.state.tracking is TrackingMode.OFF
        # unaligned Alt-Az readings are relative to where the counters started
        reply = await asker(GetAzAlt(precise=True))
        assert isinstance(reply, Position)
        assert (reply.ra_hours * 15.0, reply.dec_degrees) == pytest.approx((0.0, 0.0), abs=1e-4)
        # an unaligned hand control ignores gotos: acknowledged, nothing moves
        await asker(GotoRaDec.from_hours_degrees(5.0, 30.0))
        sim.step(30.0)
        assert tube_altaz(sim) == pytest.approx(tube, abs=1e-9)
        sim.step(600.0)  # the motors are off: no tracking either
        assert tube_altaz(sim) == pytest.approx(tube, abs=1e-9)


async def test_set_axis_position_keeps_a_flipped_secondary_flipped() -> None:
    sim = _sim()
    async with _client(sim) as (_, asker):
        await asker(SetAxisPosition.from_degrees(Axis.ALT_DEC, 200.0))
        assert sim.axes[1].position == pytest.approx(200.0, abs=1e-4)
        assert sim.state.pier_side is PierSide.WEST  # over the pole, not under it


async def test_cold_start_with_the_tube_elsewhere() -> None:
    """What ``emulate synscan --power-on-at AZ,ALT`` builds: the tube there, counters at home."""
    geometry = _sim().geometry
    home = geometry.to_axes(30.0, 200.0, PierSide.UNKNOWN)
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock.stepped(START), home=home)
    async with SynScanEmulator(sim, cold_start=True) as emulator:
        assert not emulator.hand_control.aligned
        alt, az = tube_altaz(sim)
        assert angular_separation_deg(az, alt, 200.0, 30.0) < 1e-6
        state = sim.snapshot()  # where the counters say: the pole
        assert state.alt_deg == pytest.approx(MADRID.latitude_deg, abs=1e-6)


async def test_a_bridge_cannot_power_cycle_the_mount_behind_it() -> None:
    async with rig() as r:  # a hand control in front of a real driver: a bridge
        bridge = SynScanHandControl(r.mount)
        with pytest.raises(InvalidValueError, match="only an emulated mount"):
            await bridge.power_cycle()
        assert r.emulator.hand_control.aligned  # nothing was switched off
