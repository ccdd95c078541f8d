"""The SynScan driver against the real emulator, over a real pty and a real TCP socket."""

from __future__ import annotations

import dataclasses
from datetime import datetime, timedelta

import pytest

from scopelink.astro import PierSide, angular_separation_deg, j2000_to_apparent
from scopelink.drivers.synscan import NotAlignedError, SynScanMount
from scopelink.drivers.synscan.polling import FULL_READ_EVERY
from scopelink.mount import (
    AlignmentMode,
    DeviceError,
    GuideDirection,
    LimitError,
    Limits,
    MountAxis,
    NotConnectedError,
    NotSupportedError,
    ParkedError,
    ParkPosition,
    TrackingMode,
)
from scopelink.protocol.synscan import AnyCommand, AnyReply, CancelGoto
from scopelink.servers.synscan import SynScanConfig
from scopelink.sim import AZ_GTI, SimClock
from tests.support.synscan_driver import (
    MADRID,
    PRECISE_UNIT_DEG,
    START,
    TRANSPORTS,
    assert_position_matches,
    rig,
)


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_connect_identifies_the_hand_control_and_reads_the_position(transport: str) -> None:
    async with rig(transport) as r:
        identity = r.mount.identity
        assert (identity.protocol, identity.model, identity.firmware) == (
            "synscan",
            "EQ6 GOTO",
            "04.39.05",
        )
        assert identity.link == r.spec
        capabilities = r.mount.capabilities
        assert capabilities.alignment_mode is AlignmentMode.GERMAN_POLAR
        assert capabilities.tracking_modes == {
            TrackingMode.OFF,
            TrackingMode.SIDEREAL,
            TrackingMode.PEC,
            # By the driver's PC loop (docs/tracking.md): not the hand control's own modes.
            TrackingMode.LUNAR,
            TrackingMode.SOLAR,
            TrackingMode.KING,
        }
        assert capabilities.max_tracking_offset_arcsec_s == 3600.0
        assert capabilities.can_pulse_guide
        assert capabilities.can_report_pier_side
        assert r.mount.info is not None
        assert r.mount.info.motor_versions == ((3, 39), (3, 39))
        state = await r.mount.refresh()
        assert state.connected
        assert state.aligned
        assert not state.slewing
        assert state.tracking is TrackingMode.OFF
        assert state.pier_side is PierSide.EAST
        truth = r.sim.snapshot()
        assert_position_matches(state, truth)
        assert state.read_at == truth.read_at  # the stepped clock stands still
        assert state.ra_of_date_hours is not None
        assert state.dec_of_date_deg is not None
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        expected = j2000_to_apparent(state.ra_j2000_hours, state.dec_j2000_deg, state.read_at)
        assert (state.ra_of_date_hours, state.dec_of_date_deg) == pytest.approx(expected)


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_goto_lands_on_target_with_tracking_and_pier_side(transport: str) -> None:
    async with rig(transport) as r:
        await r.mount.goto_equatorial(7.5, 35.0)
        assert r.mount.state.slewing
        assert r.mount.target is not None
        assert r.mount.target.ra_j2000_hours == 7.5
        assert (await r.mount.refresh()).slewing
        r.sim.step(120.0)
        state = await r.mount.refresh()
        assert not state.slewing
        assert state.tracking is TrackingMode.SIDEREAL  # a goto enables tracking
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        error = angular_separation_deg(state.ra_j2000_hours * 15, state.dec_j2000_deg, 112.5, 35.0)
        assert error <= 2 * PRECISE_UNIT_DEG
        truth = r.sim.snapshot()
        assert_position_matches(state, truth)
        assert state.pier_side is truth.pier_side
        # LST is 8.4 h at START: 7.5 h was west of the meridian; 3 h later 14 h is east of it.
        r.sim.step(3 * 3600.0)
        await r.mount.goto_equatorial(14.0, 20.0)
        r.sim.step(120.0)
        flipped = await r.mount.refresh()
        assert flipped.pier_side is r.sim.snapshot().pier_side
        assert {state.pier_side, flipped.pier_side} == {PierSide.EAST, PierSide.WEST}


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_wait_for_slew_with_the_background_poller(transport: str) -> None:
    clock = SimClock.accelerated(40.0, START)
    async with rig(transport, clock=clock) as r, r.mount.watching():
        await r.mount.goto_equatorial(9.0, 10.0)
        state = await r.mount.wait_for_slew(timeout_s=20.0)
        assert not state.slewing
        assert state.ra_j2000_hours == pytest.approx(9.0, abs=1e-4)
        assert r.mount.poller.polls > 0


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_a_sync_is_kept_on_the_pc_and_corrects_the_reading(transport: str) -> None:
    async with rig(transport) as r:
        await r.mount.goto_equatorial(7.5, 35.0)
        r.sim.step(120.0)
        await r.mount.sync_equatorial(7.55, 35.3)  # docs/pointing.md: the hand control is not told
        state = r.mount.state
        assert state.ra_j2000_hours == pytest.approx(7.55, abs=1e-5)
        assert state.dec_j2000_deg == pytest.approx(35.3, abs=1e-5)
        assert r.mount.pointing.raw_state is not None
        assert_position_matches(r.mount.pointing.raw_state, r.sim.snapshot())
        assert len(r.mount.pointing.syncs) == 1


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_a_sync_the_hand_control_ignores_is_kept_on_the_pc(transport: str) -> None:
    async with rig(transport) as r:
        r.mount.syncs_on_device = True  # as a driver that tries the device first
        await r.mount.goto_equatorial(7.5, 35.0)
        r.sim.step(120.0)
        await r.mount.sync_equatorial(7.55, 35.3)  # within ~7°: the hand control takes it
        assert not r.mount.pointing.active
        assert r.mount.state.ra_j2000_hours == pytest.approx(7.55, abs=1e-5)
        # Past limits.max_sync_deg only to see the hand control's own silent refusal.
        r.mount.limits = Limits(max_sync_deg=180.0)
        await r.mount.sync_equatorial(12.0, 0.0)
        assert len(r.mount.pointing.syncs) == 1  # refused ("sync ignored"): kept on the PC
        assert r.mount.state.ra_j2000_hours == pytest.approx(12.0, abs=1e-5)
        assert r.sim.snapshot().ra_j2000_hours == pytest.approx(7.55, abs=1e-5)


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_goto_below_the_horizon_sends_nothing(transport: str) -> None:
    async with rig(transport) as r:
        r.mount.limits = Limits(horizon_deg=20.0)
        exchanges = r.mount.wire.statistics.exchanges
        with pytest.raises(LimitError):
            await r.mount.goto_horizontal(10.0, 180.0)
        with pytest.raises(LimitError):
            await r.mount.goto_equatorial(12.0, -60.0)
        assert r.mount.wire.statistics.exchanges == exchanges
        assert not r.sim.goto_in_progress


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_move_axis_and_abort(transport: str) -> None:
    async with rig(transport) as r:
        before = await r.mount.refresh()
        await r.mount.move_axis(MountAxis.SECONDARY, -2.0)
        moving = r.mount.state
        assert moving.slewing
        r.sim.step(3.0)
        assert (await r.mount.refresh()).slewing
        await r.mount.abort()
        assert not r.mount.state.slewing
        r.sim.step(5.0)  # the motors ramp down
        stopped = await r.mount.refresh()
        assert not stopped.slewing
        assert before.dec_j2000_deg is not None
        assert stopped.dec_j2000_deg is not None
        assert 2.0 < before.dec_j2000_deg - stopped.dec_j2000_deg < 8.0
        r.sim.step(30.0)
        still = await r.mount.refresh()
        assert (still.alt_deg, still.az_deg) == pytest.approx((stopped.alt_deg, stopped.az_deg))

        await r.mount.move_axis_fixed(MountAxis.PRIMARY, 9, positive=True)
        r.sim.step(2.0)
        await r.mount.move_axis(MountAxis.PRIMARY, 0.0)
        assert not r.mount.state.slewing
        r.sim.step(5.0)
        assert_position_matches(await r.mount.refresh(), r.sim.snapshot())


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_tracking_modes_site_and_time(transport: str) -> None:
    async with rig(transport) as r:
        await r.mount.set_tracking(TrackingMode.SIDEREAL)
        assert (await r.mount.refresh()).tracking is TrackingMode.SIDEREAL
        await r.mount.set_tracking(TrackingMode.PEC)
        assert (await r.mount.refresh()).tracking is TrackingMode.PEC
        await r.mount.set_tracking(TrackingMode.OFF)
        assert (await r.mount.refresh()).tracking is TrackingMode.OFF
        with pytest.raises(NotSupportedError):
            await r.mount.set_tracking(TrackingMode.ALT_AZ)

        # W carries latitude and longitude only: the air (refraction) stays as it was.
        elsewhere = dataclasses.replace(MADRID, latitude_deg=28.3, longitude_deg=-16.5)
        await r.mount.set_site(elsewhere)
        assert r.mount.site == elsewhere
        assert r.sim.site.latitude_deg == pytest.approx(28.3)
        assert r.sim.site.longitude_deg == pytest.approx(-16.5)
        assert_position_matches(await r.mount.refresh(), r.sim.snapshot())

        r.mount.utc_offset_hours = 1
        later = START + timedelta(days=3, hours=2, minutes=35, seconds=7)
        await r.mount.set_time(later)
        hand_control = r.emulator.hand_control
        assert hand_control.now() == later
        assert hand_control.utc_offset_hours == 1
        with pytest.raises(ValueError, match="time zone"):
            await r.mount.set_time(datetime(2026, 1, 1))


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_park_and_unpark(transport: str) -> None:
    async with rig(transport) as r:
        await r.mount.set_tracking(TrackingMode.SIDEREAL)
        r.mount.park_position = ParkPosition(alt_deg=30.0, az_deg=200.0)
        await r.mount.park()
        assert not r.mount.state.parked  # parked once arrived (issue #11 part 4)
        assert r.mount.state.slewing
        with pytest.raises(ParkedError):
            await r.mount.goto_equatorial(7.5, 35.0)
        r.sim.step(120.0)
        state = await r.mount.refresh()
        assert state.parked
        assert not state.slewing
        assert state.tracking is TrackingMode.OFF
        assert (state.alt_deg, state.az_deg) == pytest.approx((30.0, 200.0), abs=1e-4)
        await r.mount.unpark()
        assert not (await r.mount.refresh()).parked
        await r.mount.goto_equatorial(7.5, 35.0)

        with pytest.raises(LimitError, match="park position"):  # refused when set
            r.mount.park_position = ParkPosition(alt_deg=-5.0, az_deg=0.0)
        r.mount.park_position = ParkPosition(alt_deg=5.0, az_deg=0.0)
        r.mount.limits = Limits(horizon_deg=10.0)
        with pytest.raises(LimitError, match="park position"):  # and when parking
            await r.mount.park()


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_an_unaligned_hand_control_refuses_gotos_but_tracks_and_slews(
    transport: str,
) -> None:
    async with rig(transport, config=SynScanConfig(aligned=False)) as r:
        assert not r.mount.state.aligned
        with pytest.raises(NotAlignedError, match="not aligned"):
            await r.mount.goto_equatorial(7.5, 35.0)
        here = await r.mount.refresh()  # the hand control would ignore it: kept on the PC
        assert here.ra_j2000_hours is not None
        assert here.dec_j2000_deg is not None
        await r.mount.sync_equatorial(here.ra_j2000_hours + 0.01, here.dec_j2000_deg)
        assert r.mount.state.ra_j2000_hours == pytest.approx(here.ra_j2000_hours + 0.01, abs=1e-4)
        await r.mount.set_tracking(TrackingMode.SIDEREAL)
        await r.mount.move_axis(MountAxis.PRIMARY, 1.0)
        await r.mount.move_axis(MountAxis.PRIMARY, 0.0)
        assert (await r.mount.refresh()).tracking is TrackingMode.SIDEREAL
        r.emulator.hand_control.aligned = True  # aligned on the keypad meanwhile
        assert (await r.mount.refresh()).aligned
        assert not r.mount.pointing.active  # a new alignment: the PC-side syncs are forgotten
        await r.mount.goto_equatorial(7.5, 35.0)


async def test_an_altaz_mount() -> None:
    async with rig("tcp", model=AZ_GTI, config=SynScanConfig(model=165)) as r:
        assert r.mount.identity.model == "AZ-GTi"
        capabilities = r.mount.capabilities
        assert capabilities.alignment_mode is AlignmentMode.ALT_AZ
        # Sidereal on an alt-az mount is its alt-az tracking (custom rates are offsets from it).
        assert capabilities.tracking_modes == {
            TrackingMode.OFF,
            TrackingMode.ALT_AZ,
            TrackingMode.SIDEREAL,
        }
        assert not capabilities.can_report_pier_side
        with pytest.raises(NotSupportedError):
            await r.mount.pulse_guide(GuideDirection.NORTH, 100)
        await r.mount.goto_horizontal(45.0, 120.0)
        r.sim.step(120.0)
        state = await r.mount.refresh()
        assert not state.slewing
        assert (state.alt_deg, state.az_deg) == pytest.approx((45.0, 120.0), abs=1e-4)
        assert state.pier_side is PierSide.UNKNOWN
        await r.mount.goto_equatorial(7.5, 35.0)
        r.sim.step(120.0)
        state = await r.mount.refresh()
        assert state.tracking is TrackingMode.ALT_AZ
        assert_position_matches(state, r.sim.snapshot())


async def test_disconnect_stops_manual_motion_and_refuses_commands() -> None:
    async with rig("tcp") as r:
        await r.mount.move_axis(MountAxis.PRIMARY, 2.0)
        await r.mount.disconnect()
        assert not r.mount.state.connected
        r.sim.step(5.0)  # the motor ramps down
        resting = r.sim.snapshot()
        r.sim.step(10.0)
        still = r.sim.snapshot()
        assert (still.alt_deg, still.az_deg) == pytest.approx((resting.alt_deg, resting.az_deg))
        with pytest.raises(NotConnectedError, match="not connected"):
            await r.mount.goto_equatorial(7.5, 35.0)
        await r.mount.connect()
        assert r.mount.state.connected


async def test_open_and_an_unreachable_link_is_a_clear_error() -> None:
    """The constructor touches nothing; ``connect`` opens; ``await SynScanMount.open`` does
    both (the same meaning as ``SkyTrackerMount.open``)."""
    async with rig("tcp", connect=False) as r:
        mount = SynScanMount(r.spec, site=MADRID, clock=r.sim.now)
        before = mount.state
        await mount.connect()
        assert not before.connected
        assert mount.state.connected
        assert mount.identity.link == r.spec
        await mount.disconnect()
        opened = await SynScanMount.open(r.spec, site=MADRID, clock=r.sim.now)
        assert opened.state.connected
        assert opened.identity.link == r.spec
        await opened.disconnect()
    unreachable = SynScanMount("tcp://127.0.0.1:1", site=MADRID, timeout_s=0.5)
    with pytest.raises(DeviceError, match=r"cannot open tcp://127\.0\.0\.1:1"):
        await unreachable.connect()
    assert not unreachable.state.connected
    with pytest.raises(DeviceError, match=r"cannot open tcp://127\.0\.0\.1:1"):
        await SynScanMount.open("tcp://127.0.0.1:1", site=MADRID, timeout_s=0.5)


def test_time_zone_is_whole_hours() -> None:
    with pytest.raises(ValueError, match="UTC offset"):
        SynScanMount("tcp://127.0.0.1:1", site=MADRID, utc_offset_hours=20)


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_abort_holds_the_wire_while_the_poller_runs(transport: str) -> None:
    async with rig(transport) as r:
        seen: list[AnyCommand] = []
        answer = r.emulator.hand_control.answer

        async def note(command: AnyCommand) -> AnyReply:
            seen.append(command)
            return await answer(command)

        r.emulator.hand_control.answer = note  # type: ignore[method-assign]
        async with r.mount.watching():
            await r.mount.set_tracking(TrackingMode.SIDEREAL)
            await r.mount.move_axis(MountAxis.PRIMARY, 1.0)
            await r.mount.wait_for(lambda _: r.mount.poller.polls >= 2, timeout_s=5.0)
            polls_before = r.mount.poller.polls
            await r.mount.abort()
            await r.mount.wait_for(lambda state: not state.slewing, timeout_s=5.0)
        assert polls_before > 0
        start = next(i for i, c in enumerate(seen) if isinstance(c, CancelGoto))
        names = [type(c).__name__ for c in seen[start : start + 5]]
        assert names == [
            "CancelGoto",
            "FixedRateSlew",
            "FixedRateSlew",
            "SetTrackingMode",
            "IsGotoInProgress",
        ]


async def test_a_mount_at_rest_reads_tracking_and_pier_side_every_tenth_cycle() -> None:
    async with rig("tcp") as r:
        exchanges = r.mount.wire.statistics.exchanges
        for _ in range(FULL_READ_EVERY):
            await r.mount.refresh()
        # L and e in every cycle, t and p in one of them.
        assert r.mount.wire.statistics.exchanges - exchanges == 2 * FULL_READ_EVERY + 2
        await r.sim.set_tracking(TrackingMode.SIDEREAL)  # as if on the keypad
        states = [await r.mount.refresh() for _ in range(FULL_READ_EVERY)]
        assert states[-1].tracking is TrackingMode.SIDEREAL
        assert all(state.pier_side is PierSide.EAST for state in states)


async def test_a_hand_control_with_another_site_is_named_until_set_site() -> None:
    async with rig("tcp", connect=False) as r:
        elsewhere = dataclasses.replace(MADRID, latitude_deg=52.0)
        mount = SynScanMount(r.spec, site=elsewhere, clock=r.sim.now)
        await mount.connect()
        try:
            assert mount.state.problems
            assert "hand control's site (40.4000°, -3.7000°)" in mount.state.problems[0]
            assert "set_site" in mount.state.problems[0]
            await mount.set_site(elsewhere)
            assert not (await mount.refresh()).problems
            assert r.sim.site.latitude_deg == pytest.approx(52.0)
        finally:
            await mount.disconnect()
