"""The horizon guard on real devices: the SynScan driver on TCP to the SynScan emulator, whose own
horizon is -10°, so only the guard keeps the tube above scopelink's 10° horizon; and the Sky
Tracker driver on TCP to its emulator, whose tracking the same guard turns off."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import LimitError, Limits, MountAxis, TrackingMode
from scopelink.sim import AZ_GTI
from tests.support.safety import (
    HORIZON_DEG,
    TOLERANCE_DEG,
    Rig,
    skytracker_rig,
    synscan_rig,
    wait_until_still,
)

FAST_DEG_S = 3.0
"""Nearly the SynScan's fastest slew (800x sidereal, 3.34°/s)."""


async def test_a_rate_motion_towards_the_horizon_is_stopped_above_it() -> None:
    # In the west, turning the polar axis westwards (with tracking) lowers the tube.
    async with synscan_rig(at=(13.0, 250.0)) as rig:
        await rig.mount.move_axis(MountAxis.PRIMARY, FAST_DEG_S)
        rest = await wait_until_still(rig)
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg
        assert rest < 12.0  # it did move down, and was stopped near the horizon
        assert rig.mount.guard.stops == 1
        await rig.mount.refresh()
        state = rig.mount.state
        assert not state.slewing
        assert any("below the configured horizon of 10.00°" in p for p in state.problems)


async def test_tracking_that_carries_the_mount_below_the_horizon_is_turned_off() -> None:
    # A star setting in the west, the clock 300x: 0.6° of sinking takes about a real second.
    async with synscan_rig(at=(10.6, 270.0), rate=300.0, tracking=True) as rig:
        state = await rig.mount.wait_for(lambda s: s.tracking is TrackingMode.OFF, timeout_s=15.0)
        assert any("sidereal tracking was stopped" in p for p in state.problems)
        assert rig.sim.tracking is TrackingMode.OFF  # the device itself stopped tracking
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg


async def test_sky_tracker_tracking_that_sets_is_turned_off_by_the_guard(tmp_path: Path) -> None:
    # The one guard covers the Sky Tracker too (issue #13): its tracking of a star setting in the
    # west is turned off above the horizon, not once a reading is already below it.
    async with skytracker_rig(tmp_path, at=(10.6, 270.0), rate=300.0) as rig:
        await rig.mount.set_tracking(TrackingMode.ALT_AZ)
        state = await rig.mount.wait_for(lambda s: s.tracking is TrackingMode.OFF, timeout_s=15.0)
        assert any("altaz tracking was stopped" in p for p in state.problems), state.problems
        assert rig.mount.guard.stops >= 1
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg


async def test_moving_away_from_the_horizon_is_never_stopped() -> None:
    async with synscan_rig(at=(10.4, 250.0)) as rig:
        await rig.mount.move_axis(MountAxis.PRIMARY, -FAST_DEG_S)  # eastwards: rising
        await asyncio.sleep(0.8)
        assert rig.mount.guard.stops == 0
        assert rig.true_alt() > 10.8
        await rig.mount.move_axis(MountAxis.PRIMARY, 0.0)


async def test_an_altaz_mount_at_its_horizon_may_not_move_down() -> None:
    async with synscan_rig(model=AZ_GTI, at=(10.1, 180.0)) as rig:
        await rig.mount.refresh()
        sent = len(rig.slews_received())
        with pytest.raises(LimitError, match="would take it lower"):
            await rig.mount.move_axis(MountAxis.SECONDARY, -1.0)
        assert len(rig.slews_received()) == sent  # nothing reached the link
        await rig.mount.move_axis(MountAxis.SECONDARY, 1.0)  # up is allowed
        await asyncio.sleep(0.3)
        await rig.mount.move_axis(MountAxis.SECONDARY, 0.0)
        assert rig.true_alt() > 10.15


async def test_the_altitude_limit_stops_a_motion_upwards() -> None:
    limits = Limits(horizon_deg=HORIZON_DEG, max_altitude_deg=80.0)
    async with synscan_rig(model=AZ_GTI, at=(77.5, 180.0), limits=limits) as rig:
        await rig.mount.move_axis(MountAxis.SECONDARY, FAST_DEG_S)
        await wait_until_still(rig)
        assert rig.max_alt_deg <= 80.0 + TOLERANCE_DEG, rig.max_alt_deg
        await rig.mount.refresh()
        state = rig.mount.state
        assert any("above the configured limit of 80.00°" in p for p in state.problems)


async def _settled(rig: Rig, quiet_s: float) -> None:
    """Return once no command has reached the device for ``quiet_s``."""
    loop = asyncio.get_running_loop()
    seen, since = len(rig.received), loop.time()
    while loop.time() - since < quiet_s:
        await asyncio.sleep(0.01)
        if len(rig.received) != seen:
            seen, since = len(rig.received), loop.time()


async def test_tracking_far_from_the_limits_costs_no_wire_traffic_until_a_slew_starts() -> None:
    async with synscan_rig(at=(13.0, 250.0), tracking=True) as rig:
        await asyncio.sleep(0.1)
        assert rig.mount.guard.running  # following the tracked position by astrometry...
        # The refreshes that follow turning tracking on may end late on a loaded machine (CI once
        # saw the last one 0.1 s in): the window starts once they are over.
        await asyncio.wait_for(_settled(rig, 0.2), timeout=5.0)
        sent = len(rig.received)
        await asyncio.sleep(1.5)  # longer than the idle poll period, which a guard must not need
        assert len(rig.received) == sent  # ...without a single exchange
        await rig.mount.move_axis(MountAxis.PRIMARY, FAST_DEG_S)  # wakes it: polls, then stops
        await wait_until_still(rig)
        assert rig.mount.guard.stops >= 1
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg


async def test_panning_into_a_rising_horizon_profile_is_stopped_before_it() -> None:
    # A house to the south: the horizon rises from 10° at azimuth 150° to 25° at 200°, so a tube
    # level at 15° meets it at azimuth 166.7° while its altitude never changes.
    limits = Limits(horizon_deg=HORIZON_DEG, horizon_profile=((150.0, 10.0), (200.0, 25.0)))
    async with synscan_rig(model=AZ_GTI, at=(15.0, 161.0), limits=limits, rate=2.0) as rig:
        await rig.mount.move_axis(MountAxis.PRIMARY, 2.0)
        await wait_until_still(rig)
        alt, az = rig.sim.observed_at(rig.sim.elapsed())
        assert az > 162.0  # it did pan
        assert alt >= limits.horizon_at(az) - TOLERANCE_DEG, (alt, az, limits.horizon_at(az))
        assert any("horizon of" in p for p in rig.mount.state.problems)


@pytest.mark.parametrize(
    ("axis", "az_deg"),
    # Where each axis moves the altitude most: the polar axis low in the west (the hour angle),
    # the declination axis low in the south (on the meridian the polar axis moves no altitude).
    # In the east the tube is on the other side of the pier: both axes there too.
    [
        (MountAxis.PRIMARY, 250.0),
        (MountAxis.SECONDARY, 185.0),
        (MountAxis.PRIMARY, 110.0),
        (MountAxis.SECONDARY, 110.0),
    ],
)
async def test_an_equatorial_mount_at_its_horizon_may_only_move_up(
    axis: MountAxis, az_deg: float
) -> None:
    # The guard tells which way each axis moves the altitude from the pier side, the hemisphere
    # and the astrometry: exactly one direction is refused, and the other one rises. (Starting
    # just below the horizon, a short move up leaves it at the horizon for the second try.)
    async with synscan_rig(at=(9.9, az_deg)) as rig:
        await rig.mount.refresh()
        outcomes: dict[float, str] = {}
        for rate in (1.0, -1.0):
            sent = len(rig.slews_received())
            try:
                await rig.mount.move_axis(axis, rate)
            except LimitError as error:
                outcomes[rate] = str(error)
                assert len(rig.slews_received()) == sent  # refused: nothing reached the link
                continue
            outcomes[rate] = "moved"
            before = rig.true_alt()
            await asyncio.sleep(0.3)
            await rig.mount.move_axis(axis, 0.0)
            assert rig.true_alt() > before + 0.05, rate  # the allowed direction is up
        refused = [message for message in outcomes.values() if "would take it lower" in message]
        assert len(refused) == 1, outcomes


async def test_tracking_through_the_zenith_is_left_alone_without_an_altitude_limit() -> None:
    # At the default 90° nothing can pass the limit: a star culminating by the zenith is tracked.
    async with synscan_rig(at=(89.8, 95.0), rate=300.0, tracking=True) as rig:
        await asyncio.sleep(2.0)  # ten simulated minutes: up through 89.9° and down again
        await rig.mount.refresh()
        assert rig.mount.guard.stops == 0
        assert rig.mount.state.tracking is TrackingMode.SIDEREAL
        assert rig.max_alt_deg > 89.85


async def test_keypad_speed_motions_are_guarded_too() -> None:
    # The SynScan driver's keypad speeds (move_axis_fixed) go through the same guard.
    async with synscan_rig(at=(13.0, 250.0)) as rig:
        assert isinstance(rig.mount, SynScanMount)
        await rig.mount.move_axis_fixed(MountAxis.PRIMARY, 9)  # 800x sidereal, westwards
        await wait_until_still(rig)
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg
        assert rig.mount.guard.stops == 1
    async with synscan_rig(model=AZ_GTI, at=(10.1, 180.0)) as rig:
        assert isinstance(rig.mount, SynScanMount)
        await rig.mount.refresh()
        sent = len(rig.slews_received())
        with pytest.raises(LimitError, match="would take it lower"):
            await rig.mount.move_axis_fixed(MountAxis.SECONDARY, 9, positive=False)
        assert len(rig.slews_received()) == sent


async def test_an_unexpected_error_in_a_stop_does_not_end_the_watch(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A driver bug seen once under load (a RuntimeError from asyncio inside the driver's abort)
    # used to end the guard's task: the motion then went on unwatched, below the horizon.
    async with synscan_rig(at=(13.0, 250.0)) as rig:
        real_abort = rig.mount.abort
        failures: list[str] = []

        async def abort_failing_once() -> None:
            if not failures:
                failures.append("abort")
                raise RuntimeError("Cannot change state of expiring Timeout")
            await real_abort()

        monkeypatch.setattr(rig.mount, "abort", abort_failing_once)
        await rig.mount.move_axis(MountAxis.PRIMARY, FAST_DEG_S)
        rest = await wait_until_still(rig)
        assert failures == ["abort"]  # the fault did happen
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg
        assert rest < 12.0
