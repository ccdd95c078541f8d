"""Meridian limits on a SynScan hand control (the real driver against the emulator over TCP, on
an accelerated clock): the hand control picks the pier side of a goto itself, so scopelink
refuses a goto that would land on the wrong side, stops tracking at the limit itself (the hand
control would track into the pier), and checks where an automatic flip landed: a flip the hand
control did not make leaves tracking off (issue #15 part 3; docs/meridian.md)."""

from __future__ import annotations

import asyncio

import pytest

from scopelink.astro import PierSide
from scopelink.mount import LimitError, Limits, MountAxis, MountState, TrackingMode
from scopelink.mount.meridian import meridian_status
from tests.support.meridian import ra_j2000_at_hour_angle, synscan_rig

SPEED_UP = 200.0
"""Simulated seconds per real second: 1° of hour angle (4 min) in 1.2 s."""
DRIVER = Limits(meridian_east_deg=0.0, meridian_west_deg=1.0)
"""The driver's limits: tracking stops 1° past the meridian (10 min to track after a goto)."""


async def test_tracking_stops_at_the_limit_the_hand_control_would_track_through() -> None:
    # The hand control's own mount stops only at 5° (its limits): scopelink's 1° comes first.
    async with synscan_rig(
        DRIVER, hand_control=Limits(meridian_east_deg=0.0), speed_up=SPEED_UP
    ) as (
        mount,
        sim,
    ):
        await mount.goto_equatorial(ra_j2000_at_hour_angle(mount, -2.0 / 15.0), 20.0)
        landed = await mount.wait_for_slew(timeout_s=30.0)
        assert landed.pier_side is PierSide.WEST
        assert landed.tracking is not TrackingMode.OFF
        stopped = await mount.wait_for(lambda s: s.tracking is TrackingMode.OFF, timeout_s=30.0)
        assert sim.state.tracking is TrackingMode.OFF  # the device itself was told
        assert mount.meridian.stops == 1
        status = meridian_status(mount, stopped)
        assert status is not None
        assert 0.3 < status.past_deg <= 1.0, status
        assert any("limits.meridian_west_deg" in p for p in mount.state.problems)
        with pytest.raises(LimitError, match=r"limits\.meridian_west_deg"):
            await mount.set_tracking(TrackingMode.SIDEREAL)
        assert sim.state.tracking is TrackingMode.OFF


async def test_a_goto_the_hand_control_would_land_on_the_wrong_side_is_refused() -> None:
    # 7.5° east of the meridian: the hand control takes the west side, where tracking reaches
    # the 5° limit in 50 min; 60 are asked for, and it cannot be told to take the east side.
    limits = Limits(meridian_east_deg=10.0, meridian_west_deg=5.0, min_track_minutes=60.0)
    async with synscan_rig(limits, hand_control=Limits(), speed_up=SPEED_UP) as (mount, sim):
        before = sim.axes[0].position, sim.axes[1].position
        ra = ra_j2000_at_hour_angle(mount, -0.5)
        with pytest.raises(LimitError, match=r"limits\.min_track_minutes \(60\)") as refused:
            await mount.goto_equatorial(ra, 20.0)
        assert "nothing was sent" in str(refused.value)
        assert "\n" not in str(refused.value)
        assert (sim.axes[0].position, sim.axes[1].position) == before
        assert not sim.goto_in_progress
        assert mount.destination_side_of_pier(ra, 20.0) is PierSide.UNKNOWN
        # Two hours east the west side tracks long enough: sent, and it lands there.
        await mount.goto_equatorial(ra_j2000_at_hour_angle(mount, -2.0), 20.0)
        assert (await mount.wait_for_slew(timeout_s=30.0)).pier_side is PierSide.WEST


@pytest.mark.parametrize(
    ("hand_control_minutes", "flips"),
    [
        (30.0, True),  # the hand control's mount leaves the west side (4.4° left < 30 min)
        (10.0, False),  # it keeps the west side (17 min left): the flip did not happen
    ],
)
async def test_auto_flip_is_checked_and_a_failed_flip_leaves_tracking_off(
    hand_control_minutes: float, flips: bool
) -> None:
    limits = Limits(meridian_east_deg=0.0, meridian_west_deg=1.0, auto_flip=True)
    hand_control = Limits(meridian_east_deg=0.0, min_track_minutes=hand_control_minutes)
    async with synscan_rig(limits, hand_control=hand_control, speed_up=SPEED_UP) as (mount, sim):
        ra = ra_j2000_at_hour_angle(mount, -2.0 / 15.0)
        await mount.goto_equatorial(ra, 20.0)
        assert (await mount.wait_for_slew(timeout_s=30.0)).pier_side is PierSide.WEST
        loop = asyncio.get_running_loop()
        deadline = loop.time() + 60.0
        while mount.meridian.flips == 0 and "flip failed" not in mount.meridian.notice:
            assert loop.time() < deadline, "neither a flip nor a failed one"
            await asyncio.sleep(0.05)
        if flips:
            assert mount.meridian.flips == 1
            state = await mount.wait_for(
                lambda s: not s.slewing and s.pier_side is PierSide.EAST, timeout_s=30.0
            )
            assert state.tracking is not TrackingMode.OFF
            assert sim.state.pier_side is PierSide.EAST
        else:
            assert mount.meridian.flips == 0
            assert "the automatic flip failed" in mount.meridian.notice
            assert "tracking is off" in mount.meridian.notice
            await mount.wait_for(lambda s: s.tracking is TrackingMode.OFF, timeout_s=10.0)
            assert sim.state.tracking is TrackingMode.OFF
            assert sim.state.pier_side is PierSide.WEST


async def test_a_manual_motion_heading_past_the_limit_is_stopped_before_it() -> None:
    limits = Limits(meridian_east_deg=0.0, meridian_west_deg=3.0)
    async with synscan_rig(limits, hand_control=Limits(meridian_east_deg=0.0), speed_up=50.0) as (
        mount,
        sim,
    ):
        await mount.goto_equatorial(ra_j2000_at_hour_angle(mount, -1.0 / 15.0), 20.0)
        assert (await mount.wait_for_slew(timeout_s=30.0)).pier_side is PierSide.WEST
        await mount.set_tracking(TrackingMode.OFF)
        sim.clock.set_rate(1.0)  # the motion in real time, as the guard sees a real one

        def past(state: MountState) -> float:
            status = meridian_status(mount, state)
            assert status is not None
            return status.past_deg

        # Which way the polar axis turns the tube west: try 0.3 s, then head that way.
        start = past(await mount.refresh())
        await mount.move_axis(MountAxis.PRIMARY, 1.0)
        await asyncio.sleep(0.3)
        await mount.abort()
        await mount.wait_for(lambda s: not s.slewing, timeout_s=5.0)
        rate = 1.0 if past(await mount.refresh()) > start else -1.0
        await mount.move_axis(MountAxis.PRIMARY, rate)
        stopped = await mount.wait_for(
            lambda s: mount.guard.stops > 0 and not s.slewing, timeout_s=15.0
        )
        assert 1.5 < past(stopped) <= 3.0, past(stopped)
        assert "limits.meridian_west_deg" in mount.guard.notice
        assert past(await mount.refresh()) <= 3.0
