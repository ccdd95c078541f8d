"""What device emulators use: raw axes, slow gotos, set position, real-time clocks, presets."""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime

import pytest

from scopelink.astro import Site, angular_separation_deg, lst_hours
from scopelink.mount import AlignmentMode, MountAxis, TrackingMode
from scopelink.sim import EQ6, SKY_TRACKER, MountModel, SimClock, SimulatedMount

START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
SITE = Site(latitude_deg=45.0, longitude_deg=7.0)


def separation_arcsec(ra1: float, dec1: float, ra2: float, dec2: float) -> float:
    return angular_separation_deg(ra1 * 15.0, dec1, ra2 * 15.0, dec2) * 3600.0


async def test_slew_axis_to_lands_on_the_counter_and_set_position_redefines_it() -> None:
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped(START))
    await mount.connect()
    landing = mount.slew_axis_to(MountAxis.PRIMARY, 45.0)
    assert mount.goto_ends_at == landing
    assert mount.snapshot().slewing
    state = mount.step(landing)
    assert mount.axes[0].position == 45.0
    assert not state.slewing
    physical = mount.axes[0].physical_position_at(mount.elapsed())
    mount.set_axis_position(MountAxis.PRIMARY, 10.0)
    assert mount.axes[0].position == pytest.approx(10.0)
    assert mount.axes[0].physical_position_at(mount.elapsed()) == pytest.approx(physical)


async def test_tracking_resumes_after_a_slow_goto() -> None:
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped(START))
    await mount.connect()
    await mount.set_tracking(TrackingMode.SIDEREAL)
    landing = mount.slew_axis_to(MountAxis.SECONDARY, 60.0)
    state = mount.step(landing + 1.0)
    assert state.tracking is TrackingMode.SIDEREAL
    held = state
    state = mount.step(1200.0)
    assert (
        separation_arcsec(
            state.ra_j2000_hours or 0.0,
            state.dec_j2000_deg or 0.0,
            held.ra_j2000_hours or 0.0,
            held.dec_j2000_deg or 0.0,
        )
        < 0.1
    )


async def test_goto_with_an_accelerated_clock_lands_exactly() -> None:
    clock = SimClock.accelerated(1000.0, START)
    mount = SimulatedMount(EQ6, site=SITE, clock=clock)
    await mount.connect()
    ra = (lst_hours(clock.now(), SITE.longitude_deg) - 1.5) % 24.0
    await mount.goto_equatorial(ra, 35.0)
    await asyncio.wait_for(clock.sleep(120.0), 5.0)  # the slew takes about 40 s
    state = await mount.refresh()
    assert not state.slewing
    assert (
        separation_arcsec(state.ra_j2000_hours or 0.0, state.dec_j2000_deg or 0.0, ra, 35.0) < 0.1
    )


async def test_fork_mount_goto_and_tracking() -> None:
    fork = MountModel("fork", AlignmentMode.POLAR, 3.0, 3.0)
    mount = SimulatedMount(fork, site=SITE, clock=SimClock.stepped(START))
    await mount.connect()
    ra = (lst_hours(START, SITE.longitude_deg) + 2.0) % 24.0  # east of the meridian
    await mount.goto_equatorial(ra, 40.0)
    landing = mount.goto_ends_at
    assert landing is not None
    mount.step(landing)
    for _ in range(4):
        state = mount.step(1800.0)
        assert (
            separation_arcsec(state.ra_j2000_hours or 0.0, state.dec_j2000_deg or 0.0, ra, 40.0)
            < 0.1
        )


async def test_sky_tracker_utility_slew_ramps_to_4_deg_per_second() -> None:
    mount = SimulatedMount(SKY_TRACKER, site=SITE, clock=SimClock.stepped(START))
    await mount.connect()
    await mount.goto_horizontal(30.0, 90.0)
    landing = mount.goto_ends_at
    assert landing is not None
    mount.step(landing)
    await mount.move_axis(MountAxis.PRIMARY, 4.0)
    mount.step(1.0)
    assert mount.axes[0].rate == pytest.approx(2.0)  # half way up a 2 s ramp
    mount.step(1.5)
    assert mount.axes[0].rate == pytest.approx(4.0)
    await mount.move_axis(MountAxis.PRIMARY, 0.0)
    mount.step(1.0)
    assert mount.axes[0].rate == pytest.approx(2.0)
    mount.step(1.0)
    assert not mount.axes[0].is_moving


async def test_alt_az_tracking_turns_both_axes() -> None:
    from scopelink.sim import AZ_GTI

    mount = SimulatedMount(AZ_GTI, site=SITE, clock=SimClock.stepped(START))
    await mount.connect()
    ra = (lst_hours(START, SITE.longitude_deg) - 2.0) % 24.0
    await mount.goto_equatorial(ra, 20.0)
    landing = mount.goto_ends_at
    assert landing is not None
    mount.step(landing)
    assert mount.tracking is TrackingMode.ALT_AZ
    assert mount.axes[0].rate != 0.0
    assert mount.axes[1].rate < 0.0  # setting in the west
