"""Guide pulses: variable-rate slews timed on the PC, over a real pty and a real TCP socket."""

from __future__ import annotations

import dataclasses
import math
import time

import pytest

from scopelink.astro import PierSide
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import GuideDirection, MountAxis, TrackingMode
from scopelink.protocol.synscan import AnyCommand, AnyReply, Axis, FixedRateSlew, VariableRateSlew
from scopelink.sim import SimClock
from tests.support.synscan_driver import MADRID, START, TRANSPORTS, rig


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_pulse_guides_are_timed_on_the_pc(transport: str) -> None:
    # The emulator runs in this process and the simulator spends 0.2 s of CPU on a rate command:
    # pulses of 1 s leave it idle again long before the stop is due.
    speedup = 10.0
    async with rig(transport, clock=SimClock.accelerated(speedup, START)) as r:
        await r.mount.goto_equatorial(7.5, 35.0)
        await r.mount.wait_for_slew(timeout_s=15.0)
        before = await r.mount.refresh()
        assert before.tracking is TrackingMode.SIDEREAL
        assert before.pier_side is PierSide.EAST

        # When each rate command reached the hand control (real time), before it was carried out.
        arrivals: list[tuple[float, AnyCommand]] = []
        answer = r.emulator.hand_control.answer

        async def note_arrival(command: AnyCommand) -> AnyReply:
            arrivals.append((time.monotonic(), command))
            return await answer(command)

        r.emulator.hand_control.answer = note_arrival  # type: ignore[method-assign]
        expected = r.mount.guide_rate_deg_s * 1.0 * speedup  # 1 s of real time
        for direction, sign in ((GuideDirection.NORTH, 1.0), (GuideDirection.SOUTH, -1.0)):
            arrivals.clear()
            start = await r.mount.refresh()
            await r.mount.pulse_guide(direction, 1000)
            assert r.mount.state.pulse_guiding
            await r.mount.wait_for(lambda s: not s.pulse_guiding, timeout_s=5.0)
            end = await r.mount.refresh()
            assert not end.pulse_guiding
            assert end.tracking is TrackingMode.SIDEREAL  # tracking resumed after the pulse
            rates = [
                (at, c) for at, c in arrivals if isinstance(c, VariableRateSlew | FixedRateSlew)
            ]
            assert [type(c) for _, c in rates] == [VariableRateSlew, FixedRateSlew]
            # Never early; late only by event-loop lateness (this process also runs the emulator
            # and its simulator, and CI shares two cores).
            assert 0.98 <= rates[1][0] - rates[0][0] <= 1.5
            assert isinstance(rates[0][1], VariableRateSlew)
            assert rates[0][1].axis is Axis.ALT_DEC
            assert rates[0][1].positive is (sign > 0)
            assert start.dec_j2000_deg is not None
            assert end.dec_j2000_deg is not None
            # The simulator's own CPU time under load blurs the motion more than the timing.
            assert end.dec_j2000_deg - start.dec_j2000_deg == pytest.approx(
                sign * expected, rel=0.5
            )
        # East/west: the slew replaces tracking for the pulse, so the sky offset is the guide
        # rate alone (west: the pointing moves west, RA decreasing).
        for direction, sign in ((GuideDirection.WEST, -1.0), (GuideDirection.EAST, 1.0)):
            start = await r.mount.refresh()
            await r.mount.pulse_guide(direction, 1000)
            await r.mount.wait_for(lambda s: not s.pulse_guiding, timeout_s=5.0)
            end = await r.mount.refresh()
            assert end.tracking is TrackingMode.SIDEREAL
            assert start.ra_j2000_hours is not None
            assert end.ra_j2000_hours is not None
            assert end.dec_j2000_deg is not None
            moved = (end.ra_j2000_hours - start.ra_j2000_hours) * 15.0
            moved *= math.cos(math.radians(end.dec_j2000_deg))
            assert moved == pytest.approx(sign * expected, rel=0.5)


def test_guide_directions_follow_hemisphere_and_pier_side() -> None:
    """East/west: the RA axis (positive is westward, as the hand control's W key); north/south:
    the Dec axis, reversed past the meridian flip and in the southern hemisphere."""
    mount = SynScanMount("tcp://127.0.0.1:1", site=MADRID)
    expected_north = {
        GuideDirection.WEST: (MountAxis.PRIMARY, 1.0),
        GuideDirection.EAST: (MountAxis.PRIMARY, -1.0),
        GuideDirection.NORTH: (MountAxis.SECONDARY, 1.0),
        GuideDirection.SOUTH: (MountAxis.SECONDARY, -1.0),
    }
    for direction, (axis, sign) in expected_north.items():
        assert mount._guide_axis(direction) == (axis, sign)
    mount._pier_side = PierSide.WEST  # flipped: the Dec axis runs the other way
    assert mount._guide_axis(GuideDirection.NORTH) == (MountAxis.SECONDARY, -1.0)
    assert mount._guide_axis(GuideDirection.WEST) == (MountAxis.PRIMARY, 1.0)
    south = SynScanMount("tcp://127.0.0.1:1", site=dataclasses.replace(MADRID, latitude_deg=-33))
    assert south._guide_axis(GuideDirection.WEST) == (MountAxis.PRIMARY, -1.0)
    assert south._guide_axis(GuideDirection.NORTH) == (MountAxis.SECONDARY, -1.0)


async def test_disconnect_during_a_pulse_stops_its_axis() -> None:
    async with rig("tcp") as r:
        await r.mount.pulse_guide(GuideDirection.NORTH, 10_000)
        assert r.sim.snapshot().slewing
        await r.mount.disconnect()
        r.sim.step(5.0)  # the motor ramps down
        resting = r.sim.snapshot()
        assert not resting.slewing
        r.sim.step(60.0)
        still = r.sim.snapshot()  # tracking is off: the tube holds its alt/az
        assert (still.alt_deg, still.az_deg) == (resting.alt_deg, resting.az_deg)
