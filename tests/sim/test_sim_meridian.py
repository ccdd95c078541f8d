"""The meridian watch on the simulated German mount, through the Mount API on an accelerated
clock: an automatic flip is a goto like any other, and one that a limit refuses leaves tracking
off (issue #15 part 3; docs/meridian.md)."""

from __future__ import annotations

import dataclasses
from datetime import UTC, datetime

import pytest

from scopelink.astro import PierSide, Site, lst_hours
from scopelink.mount import Limits, MountAxis, TrackingMode
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(latitude_deg=50.0, longitude_deg=10.0, elevation_m=300.0)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)


async def test_a_flip_the_altitude_limit_refuses_leaves_tracking_off() -> None:
    limits = Limits(meridian_east_deg=0.0, meridian_west_deg=1.0, auto_flip=True)
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.accelerated(200.0, START), limits=limits)
    await mount.connect()
    try:
        ra = (lst_hours(mount.now(), SITE.longitude_deg) + 2.0 / 15.0) % 24.0  # 2° east
        await mount.goto_equatorial(ra, 20.0)
        landed = await mount.wait_for_slew(timeout_s=30.0)
        assert landed.pier_side is PierSide.WEST
        assert landed.alt_deg is not None
        # Lower the ceiling below the target now (the simulator planned its own stops with the
        # old limits): the flip's goto to the same place must be refused by it.
        mount.limits = dataclasses.replace(limits, max_altitude_deg=landed.alt_deg - 2.0)
        stopped = await mount.wait_for(
            lambda s: (
                mount.meridian.stops > 0
                and s.tracking is TrackingMode.OFF
                and "flip failed" in mount.meridian.notice
            ),
            timeout_s=30.0,
        )
        assert mount.meridian.flips == 0
        assert "above the configured limit" in mount.meridian.notice
        assert "tracking is off" in mount.meridian.notice
        assert any("the automatic flip failed" in p for p in mount.state.problems)
        assert stopped.pier_side is PierSide.WEST
        assert not stopped.slewing
        assert (await mount.refresh()).tracking is TrackingMode.OFF
    finally:
        await mount.disconnect()


async def test_the_physics_stops_tracking_and_manual_motion_at_the_configured_limit() -> None:
    limits = Limits(meridian_east_deg=0.0, meridian_west_deg=3.0)
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped(START), limits=limits)
    await mount.connect()
    ra = (lst_hours(mount.now(), SITE.longitude_deg) + 1.0) % 24.0  # an hour east
    await mount.goto_equatorial(ra, 20.0)
    landing = mount.goto_ends_at
    assert landing is not None
    state = mount.step(landing - mount.elapsed() + 1.0)
    assert state.pier_side is PierSide.WEST
    # Stepped, no watch runs: the simulator itself stops 3° past the meridian (not at its
    # mechanical 7.5°), 18° of hour angle after the goto: about 72 min.
    state = mount.step(3 * 3600.0)
    assert state.tracking is TrackingMode.OFF
    assert mount.limit_stop is not None
    assert 4250.0 < mount.limit_stop.at_s < 4400.0
    assert mount.axes[0].position == pytest.approx(93.0, abs=1e-3)  # north, west side: 90 + 3
    # A manual motion further west stops at the limit too; back east it runs.
    await mount.move_axis(MountAxis.PRIMARY, 1.0)
    mount.step(10.0)
    assert mount.axes[0].position == pytest.approx(93.0, abs=1e-3)
    await mount.move_axis(MountAxis.PRIMARY, -1.0)
    mount.step(5.0)
    assert mount.axes[0].position < 92.0
