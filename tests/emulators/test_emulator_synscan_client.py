"""The SynScan emulator against our own codec client, over a real pty and a real TCP socket."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from datetime import UTC, datetime

import pytest

from scopelink.astro import Site, angular_separation_deg, lst_hours
from scopelink.links import Link, open_serial, open_tcp
from scopelink.protocol.synscan import (
    Aligned,
    AnyCommand,
    AnyReply,
    Axis,
    CancelGoto,
    DateTime,
    DeviceVersion,
    Echo,
    EchoReply,
    FixedRateSlew,
    GetAzAlt,
    GetDeviceVersion,
    GetLocation,
    GetModel,
    GetPointingState,
    GetRaDec,
    GetTime,
    GetTrackingMode,
    GetVersion,
    GotoAzAlt,
    GotoInProgress,
    GotoRaDec,
    IsAligned,
    IsGotoInProgress,
    Location,
    Model,
    Passthrough,
    PassthroughFailed,
    PointingSide,
    PointingState,
    Position,
    SetAxisPosition,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SlowGoto,
    SyncRaDec,
    SynScanClientConnection,
    TrackingModeReply,
    VariableRateSlew,
    Version,
    VersionDialect,
)
from scopelink.servers.synscan import DEFAULT_FIRMWARE, Quirks, SynScanConfig, SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.synscan import ask

PRECISE_UNIT_DEG = 360.0 / 2**24
MADRID = Site(40.4, 3.7, pressure_hpa=0.0)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)


@dataclass
class Session:
    """A client connected to an emulator."""

    emulator: SynScanEmulator
    mount: SimulatedMount
    link: Link
    connection: SynScanClientConnection

    async def ask(self, command: AnyCommand, seconds: float = 3.0) -> AnyReply:
        return await ask(self.link, self.connection, command, seconds)


@asynccontextmanager
async def session(
    transport: str, config: SynScanConfig | None = None, *, clock: SimClock | None = None
) -> AsyncIterator[Session]:
    mount = SimulatedMount(EQ6, site=MADRID, clock=clock or SimClock.stepped(START))
    async with SynScanEmulator(mount, config) as emulator:
        if transport == "pty":
            link: Link = await open_serial(await emulator.on_pty())
        else:
            link = await open_tcp(*await emulator.on_tcp("127.0.0.1", 0))
        async with link:
            yield Session(emulator, mount, link, SynScanClientConnection())


TRANSPORTS = ["pty", "tcp"]


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_identity_and_queries(transport: str) -> None:
    async with session(transport) as s:
        assert await s.ask(Echo(0x23)) == EchoReply(0x23)
        assert await s.ask(GetVersion()) == DEFAULT_FIRMWARE
        assert await s.ask(GetModel()) == Model(0)
        assert await s.ask(IsAligned()) == Aligned(True)
        assert await s.ask(IsGotoInProgress()) == GotoInProgress(False)
        assert await s.ask(GetPointingState()) == PointingState(PointingSide.EAST)
        assert await s.ask(GetTrackingMode()) == TrackingModeReply(0)
        assert await s.ask(GetDeviceVersion(Axis.AZM_RA)) == DeviceVersion(3, 39)
        state = s.mount.snapshot()
        position = await s.ask(GetRaDec())
        assert isinstance(position, Position)
        assert abs(position.dec_degrees - (state.dec_j2000_deg or 0)) < PRECISE_UNIT_DEG
        coarse = await s.ask(GetRaDec(precise=False))
        assert isinstance(coarse, Position)
        assert abs(coarse.ra_hours - position.ra_hours) < 360 / 65536 / 15
        horizontal = await s.ask(GetAzAlt())
        assert isinstance(horizontal, Position)
        assert abs(horizontal.alt_degrees - (state.alt_deg or 0)) < PRECISE_UNIT_DEG
        assert abs(horizontal.az_degrees - (state.az_deg or 0)) < PRECISE_UNIT_DEG
        assert isinstance(
            await s.ask(Passthrough(bytes((1, 0x20, 5, 0, 0, 0, 3)))), PassthroughFailed
        )


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_goto_lands_within_one_precise_unit_and_tracking_holds(transport: str) -> None:
    async with session(transport) as s:
        target = GotoRaDec.from_hours_degrees(7.5, 35.0)
        assert (await s.ask(target)).describe() == "ok"
        assert await s.ask(IsGotoInProgress()) == GotoInProgress(True)
        s.mount.step(120.0)
        assert await s.ask(IsGotoInProgress()) == GotoInProgress(False)
        assert await s.ask(GetTrackingMode()) == TrackingModeReply(2)  # a goto enables tracking
        for _hours in range(3):
            position = await s.ask(GetRaDec())
            assert isinstance(position, Position)
            error = angular_separation_deg(
                position.ra_hours * 15, position.dec_degrees, target.ra_hours * 15, 35.0
            )
            assert error <= PRECISE_UNIT_DEG
            s.mount.step(3600.0)


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_sync_cancel_and_altaz_goto(transport: str) -> None:
    async with session(transport) as s:
        await s.ask(GotoRaDec.from_hours_degrees(7.5, 35.0))
        s.mount.step(120.0)
        await s.ask(SyncRaDec.from_hours_degrees(7.6, 35.5))
        position = await s.ask(GetRaDec())
        assert isinstance(position, Position)
        assert abs(position.ra_hours - 7.6) < 1e-5
        await s.ask(SyncRaDec.from_hours_degrees(12.0, 0.0))  # far away: ignored
        position = await s.ask(GetRaDec())
        assert isinstance(position, Position)
        assert abs(position.ra_hours - 7.6) < 1e-4

        await s.ask(GotoAzAlt.from_degrees(180.0, 30.0))
        s.mount.step(1.0)
        assert await s.ask(IsGotoInProgress()) == GotoInProgress(True)
        await s.ask(CancelGoto())
        assert await s.ask(IsGotoInProgress()) == GotoInProgress(False)
        s.mount.step(5.0)  # the motors ramp down
        stopped = await s.ask(GetAzAlt())
        s.mount.step(30.0)
        assert await s.ask(GetAzAlt()) == stopped


@pytest.mark.parametrize("transport", TRANSPORTS)
async def test_slews_tracking_site_and_time(transport: str) -> None:
    async with session(transport) as s:
        before = await s.ask(GetRaDec())
        assert isinstance(before, Position)
        await s.ask(FixedRateSlew(Axis.ALT_DEC, positive=False, rate=9))
        s.mount.step(5.0)
        await s.ask(FixedRateSlew(Axis.ALT_DEC, positive=False, rate=0))
        s.mount.step(2.0)
        after = await s.ask(GetRaDec())
        assert isinstance(after, Position)
        assert 10.0 < before.dec_degrees - after.dec_degrees < 20.0
        await s.ask(VariableRateSlew.from_arcsec_per_second(Axis.AZM_RA, 3600.0))
        s.mount.step(10.0)
        await s.ask(VariableRateSlew.from_arcsec_per_second(Axis.AZM_RA, 0.0))

        await s.ask(SetTrackingMode(2))
        assert await s.ask(GetTrackingMode()) == TrackingModeReply(2)
        await s.ask(SetTrackingMode(0))
        assert await s.ask(GetTrackingMode()) == TrackingModeReply(0)

        home = Location.from_degrees(28.3, 16.5)
        await s.ask(SetLocation(home))
        assert await s.ask(GetLocation()) == home
        assert s.mount.site.latitude_deg == pytest.approx(28.3)
        local = DateTime(23, 35, 35, 12, 31, 2025, -5, True)
        await s.ask(SetTime(local))
        assert await s.ask(GetTime()) == local  # the stepped clock has not moved

        await s.ask(SetAxisPosition(Axis.ALT_DEC, 400_000))
        await s.ask(SlowGoto(Axis.ALT_DEC, 300_000))
        assert await s.ask(IsGotoInProgress()) == GotoInProgress(True)
        s.mount.step(60.0)
        assert await s.ask(IsGotoInProgress()) == GotoInProgress(False)
        assert s.mount.counters_at(s.mount.elapsed())[1] == pytest.approx(300_000 / 2**24 * 360)


async def test_unaligned_hand_control_ignores_gotos_and_reports_altaz_from_power_on() -> None:
    async with session("tcp", SynScanConfig(aligned=False)) as s:
        assert await s.ask(IsAligned()) == Aligned(False)
        assert await s.ask(GetAzAlt()) == Position.from_az_alt(0.0, 0.0)
        await s.ask(GotoRaDec.from_hours_degrees(7.5, 35.0))
        assert await s.ask(IsGotoInProgress()) == GotoInProgress(False)


async def test_goto_below_the_horizon_is_acknowledged_and_never_moves() -> None:
    async with session("tcp") as s:
        before = await s.ask(GetAzAlt())
        assert (await s.ask(GotoRaDec.from_hours_degrees(0.0, -80.0))).describe() == "ok"
        assert await s.ask(IsGotoInProgress()) == GotoInProgress(False)
        s.mount.step(60.0)
        assert await s.ask(GetAzAlt()) == before


async def test_old_firmware_dialects() -> None:
    old = Version(3, 36, 2, VersionDialect.SYNSCAN_BINARY)
    config = SynScanConfig(model=3, firmware=old, quirks=Quirks(model_swapped=True))
    async with session("tcp", config) as s:
        assert await s.ask(GetVersion()) == old
        assert await s.ask(GetModel()) == Model(3, swapped=True)


async def test_slews_override_equatorial_tracking_except_fixed_rates_1_and_2() -> None:
    """The spec: slews override tracking, except fixed rates 1-2 while tracking equatorially."""
    from scopelink.astro import SIDEREAL_RATE_DEG_S
    from scopelink.mount import MountAxis
    from scopelink.sim.models import synscan_fixed_rate_deg_s

    def polar_axis(s: Session) -> float:
        return s.mount.counters_at(s.mount.elapsed())[MountAxis.PRIMARY.value]

    async def turned_in_100_s(s: Session, command: AnyCommand) -> float:
        await s.ask(command)
        s.mount.step(10.0)  # past the ramp
        start = polar_axis(s)
        s.mount.step(100.0)
        turned = polar_axis(s) - start
        await s.ask(FixedRateSlew(Axis.AZM_RA, positive=True, rate=0))
        s.mount.step(10.0)
        return turned

    async with session("tcp") as s:
        # away from the pole, where tracking turns the polar axis at exactly the sidereal rate
        ra_now = (lst_hours(START, MADRID.longitude_deg) - 1.0) % 24.0
        await s.mount.goto_equatorial(ra_now, 30.0)
        s.mount.step(300.0)
        await s.ask(SetTrackingMode(2))
        s.mount.step(1.0)
        guide = await turned_in_100_s(s, FixedRateSlew(Axis.AZM_RA, positive=True, rate=2))
        assert guide == pytest.approx(100 * (synscan_fixed_rate_deg_s(2) + SIDEREAL_RATE_DEG_S))
        fast = await turned_in_100_s(s, FixedRateSlew(Axis.AZM_RA, positive=True, rate=4))
        assert fast == pytest.approx(100 * synscan_fixed_rate_deg_s(4))
        variable = await turned_in_100_s(
            s, VariableRateSlew.from_arcsec_per_second(Axis.AZM_RA, 360.0)
        )
        assert variable == pytest.approx(10.0, rel=1e-3)
