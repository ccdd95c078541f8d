"""The Alpaca telescope driven by alpyca, a real third-party Alpaca client, over real HTTP."""

from __future__ import annotations

import time
from datetime import UTC, datetime
from functools import partial
from pathlib import Path

import pytest
from alpaca.exceptions import (
    InvalidOperationException,
    InvalidValueException,
    NotConnectedException,
    NotImplementedException,
    ParkedException,
    ValueNotSetException,
)
from alpaca.telescope import (
    AlignmentModes,
    DriveRates,
    EquatorialCoordinateType,
    GuideDirections,
    PierSide,
    Telescope,
    TelescopeAxes,
)

from scopelink.astro import angular_separation_deg, j2000_to_apparent
from scopelink.mount import Limits, TrackingMode
from scopelink.servers.alpaca import EquatorialSystem, TelescopeConfig
from scopelink.sim import AZ_GTI, SimulatedMount
from tests.support.alpaca import (
    WATCHABLE_SPEED_UP,
    blocking,
    client,
    radec_at,
    serve,
    sim_mount,
    wait_until,
)

SLEW_TIMEOUT_S = 20.0


def _separation_deg(ra1: float, dec1: float, ra2: float, dec2: float) -> float:
    return angular_separation_deg(ra1 * 15.0, dec1, ra2 * 15.0, dec2)


async def _connect(telescope: Telescope) -> None:
    def connect() -> None:
        telescope.Connected = True

    await blocking(connect)


async def test_connect_and_read_every_property(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        assert await blocking(lambda: telescope.Connected) is False
        with pytest.raises(NotConnectedException):
            await blocking(lambda: telescope.RightAscension)
        await _connect(telescope)
        assert mount.state.connected

        def read_all() -> dict[str, object]:
            names = [
                "AlignmentMode", "Altitude", "AtHome", "AtPark", "Azimuth", "CanFindHome",
                "CanPark", "CanPulseGuide", "CanSetDeclinationRate", "CanSetGuideRates",
                "CanSetPark", "CanSetPierSide", "CanSetRightAscensionRate", "CanSetTracking",
                "CanSlew", "CanSlewAltAz", "CanSlewAltAzAsync", "CanSlewAsync", "CanSync",
                "CanSyncAltAz", "CanUnpark", "Declination", "DeclinationRate", "DoesRefraction",
                "EquatorialSystem", "GuideRateDeclination", "GuideRateRightAscension",
                "IsPulseGuiding", "RightAscension", "RightAscensionRate", "SideOfPier",
                "SiderealTime", "SiteElevation", "SiteLatitude", "SiteLongitude", "Slewing",
                "SlewSettleTime", "Tracking", "TrackingRate", "TrackingRates", "UTCDate",
                "Name", "Description", "DriverInfo", "DriverVersion", "InterfaceVersion",
                "SupportedActions", "DeviceState", "Connecting",
            ]  # fmt: skip
            return {name: getattr(telescope, name) for name in names}

        values = await blocking(read_all)
        state = mount.state
        caps = mount.capabilities
        assert values["AlignmentMode"] == AlignmentModes.algGermanPolar
        assert values["EquatorialSystem"] == EquatorialCoordinateType.equTopocentric
        assert values["InterfaceVersion"] == 4
        assert values["SupportedActions"] == []
        assert values["Altitude"] == pytest.approx(state.alt_deg, abs=0.01)
        assert values["Azimuth"] == pytest.approx(state.az_deg, abs=0.01)
        assert values["Declination"] == pytest.approx(state.dec_of_date_deg, abs=0.01)
        assert values["SiteLatitude"] == 50.0
        assert values["SiteLongitude"] == 10.0
        assert values["SiteElevation"] == 300.0
        assert values["CanPark"] is caps.can_park is True
        assert values["CanSlewAsync"] is caps.can_goto is True
        assert values["CanPulseGuide"] is True
        assert values["CanFindHome"] is False
        assert values["CanSetPierSide"] is False
        assert values["AtHome"] is False
        assert values["SideOfPier"] in (PierSide.pierEast, PierSide.pierWest)
        assert values["TrackingRates"] == [0, 1, 2, 3]
        assert values["GuideRateRightAscension"] == pytest.approx(mount.guide_rate_deg_s)
        assert values["Connecting"] is False
        utc = values["UTCDate"]
        assert abs((utc - mount.now()).total_seconds()) < 60.0  # type: ignore[operator]
        device_state = {item["Name"]: item["Value"] for item in values["DeviceState"]}  # type: ignore[attr-defined]
        assert device_state["AtPark"] is False
        assert device_state["RightAscension"] == pytest.approx(state.ra_of_date_hours, abs=0.01)
        rates = await blocking(lambda: telescope.AxisRates(TelescopeAxes.axisPrimary))
        assert rates[0].Maximum == pytest.approx(caps.max_axis_rate_deg_s)
        assert await blocking(lambda: telescope.AxisRates(TelescopeAxes.axisTertiary)) == []
        assert await blocking(lambda: telescope.CanMoveAxis(TelescopeAxes.axisSecondary))
        assert not await blocking(lambda: telescope.CanMoveAxis(TelescopeAxes.axisTertiary))
        for unsupported in ("ApertureArea", "ApertureDiameter", "FocalLength"):
            with pytest.raises(NotImplementedException):
                await blocking(lambda name=unsupported: getattr(telescope, name))  # type: ignore[misc]
        with pytest.raises(ValueNotSetException):
            await blocking(lambda: telescope.TargetRightAscension)
        with pytest.raises(NotImplementedException):
            await blocking(telescope.FindHome)
        with pytest.raises(NotImplementedException):
            await blocking(lambda: telescope.CommandBlind("X", True))


async def test_connect_disconnect_and_connecting(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await blocking(telescope.Connect)
        await wait_until(lambda: telescope.Connected, 5.0, "Connect")
        assert await blocking(lambda: telescope.Connecting) is False
        await blocking(telescope.Disconnect)
        assert await blocking(lambda: telescope.Connected) is False
        assert mount.state.connected, "the mount stays connected for other front ends"


async def test_async_slew_is_slewing_within_a_second_and_lands_on_target(tmp_path: Path) -> None:
    mount = sim_mount(speed_up=WATCHABLE_SPEED_UP)
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        ra_j2000, dec_j2000 = radec_at(mount, 45.0, 200.0)
        ra, dec = j2000_to_apparent(ra_j2000, dec_j2000, mount.now())

        def slew_then_read_slewing() -> tuple[float, bool]:
            started = time.monotonic()
            telescope.SlewToCoordinatesAsync(ra, dec)
            return time.monotonic() - started, telescope.Slewing

        took_s, slewing = await blocking(slew_then_read_slewing)
        assert took_s < 1.0
        assert slewing is True
        await wait_until(lambda: not telescope.Slewing, SLEW_TIMEOUT_S, "the slew's end")
        assert await blocking(lambda: telescope.Tracking) is True
        got = await blocking(lambda: (telescope.RightAscension, telescope.Declination))
        # Tracking holds the target: the apparent place drifts only by precession over seconds.
        assert _separation_deg(*got, ra, dec) < 0.01
        assert await blocking(lambda: telescope.TargetRightAscension) == pytest.approx(ra)
        landed = mount.state.ra_j2000_hours, mount.state.dec_j2000_deg
        assert None not in landed
        assert _separation_deg(*landed, ra_j2000, dec_j2000) < 0.01  # type: ignore[arg-type]


async def test_j2000_equatorial_system_slews_in_j2000(tmp_path: Path) -> None:
    mount = sim_mount()
    config = TelescopeConfig(equatorial_system=EquatorialSystem.J2000)
    async with serve(mount, state_dir=tmp_path, config=config) as server:
        telescope = client(server)
        await _connect(telescope)
        assert await blocking(lambda: telescope.EquatorialSystem) == 2
        ra, dec = radec_at(mount, 40.0, 120.0)
        await blocking(lambda: telescope.SlewToCoordinatesAsync(ra, dec))
        await wait_until(lambda: not telescope.Slewing, SLEW_TIMEOUT_S, "the slew's end")
        got = await blocking(lambda: (telescope.RightAscension, telescope.Declination))
        assert _separation_deg(*got, ra, dec) < 0.01


async def test_synchronous_slews_return_after_landing(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        ra_j2000, dec_j2000 = radec_at(mount, 50.0, 150.0)
        ra, dec = j2000_to_apparent(ra_j2000, dec_j2000, mount.now())

        def slew_to_target() -> None:
            telescope.TargetRightAscension = ra
            telescope.TargetDeclination = dec
            telescope._put("slewtotarget", tmo=SLEW_TIMEOUT_S)  # alpyca has no sync slews

        await blocking(slew_to_target)
        assert not mount.state.slewing
        landed = mount.state.ra_of_date_hours, mount.state.dec_of_date_deg
        assert None not in landed
        assert _separation_deg(*landed, ra, dec) < 0.01  # type: ignore[arg-type]

        with pytest.raises(InvalidOperationException):  # ASCOM: alt/az slews need tracking off
            await blocking(lambda: telescope.SlewToAltAzAsync(90.0, 40.0))

        def slew_to_altaz() -> None:
            telescope.Tracking = False
            telescope._put("slewtoaltaz", tmo=SLEW_TIMEOUT_S, Azimuth=90.0, Altitude=40.0)

        await blocking(slew_to_altaz)
        assert not mount.state.slewing
        assert mount.state.alt_deg == pytest.approx(40.0, abs=0.01)
        assert mount.state.az_deg == pytest.approx(90.0, abs=0.01)


async def test_sync_moves_the_reported_position(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        # Away from the pole: there a sync turns the RA axis far (refused, issue #11).
        ra_j2000, dec_j2000 = radec_at(mount, 40.0, 200.0)
        ra, dec = j2000_to_apparent(ra_j2000, dec_j2000, mount.now())
        await blocking(lambda: telescope.SlewToCoordinatesAsync(ra, dec))
        await wait_until(lambda: not telescope.Slewing, SLEW_TIMEOUT_S, "the slew's end")
        ra, dec = await blocking(lambda: (telescope.RightAscension, telescope.Declination))
        new_dec = dec - 1.0
        await blocking(lambda: telescope.SyncToCoordinates(ra, new_dec))
        got_dec = await blocking(lambda: telescope.Declination)
        assert got_dec == pytest.approx(new_dec, abs=0.01)


async def test_sync_to_alt_az_and_to_target(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        # Away from the pole: there a sync turns the RA axis far (refused, issue #11).
        await blocking(lambda: telescope.SlewToAltAzAsync(200.0, 40.0))
        await wait_until(lambda: not telescope.Slewing, SLEW_TIMEOUT_S, "the slew's end")
        await blocking(lambda: setattr(telescope, "Tracking", True))
        with pytest.raises(InvalidOperationException):  # ASCOM: needs tracking off
            await blocking(lambda: telescope.SyncToAltAz(201.0, 41.0))
        await blocking(lambda: setattr(telescope, "Tracking", False))
        await blocking(lambda: telescope.SyncToAltAz(201.0, 41.0))
        assert mount.state.alt_deg == pytest.approx(41.0, abs=0.01)
        assert mount.state.az_deg == pytest.approx(201.0, abs=0.01)

        def sync_to_target() -> tuple[float, float]:
            telescope.Tracking = True
            ra, dec = telescope.RightAscension, telescope.Declination
            telescope.TargetRightAscension = ra
            telescope.TargetDeclination = dec - 0.5
            telescope.SyncToTarget()
            return dec - 0.5, telescope.Declination

        wanted, got = await blocking(sync_to_target)
        assert got == pytest.approx(wanted, abs=0.01)


async def test_abort_stops_a_slew_short_of_its_target(tmp_path: Path) -> None:
    mount = sim_mount(speed_up=WATCHABLE_SPEED_UP)
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        ra_j2000, dec_j2000 = radec_at(mount, 30.0, 250.0)
        ra, dec = j2000_to_apparent(ra_j2000, dec_j2000, mount.now())
        await blocking(lambda: telescope.SlewToCoordinatesAsync(ra, dec))
        await blocking(telescope.AbortSlew)
        await wait_until(lambda: not telescope.Slewing, 5.0, "the stop after AbortSlew")
        got = await blocking(lambda: (telescope.RightAscension, telescope.Declination))
        assert _separation_deg(*got, ra, dec) > 10.0


async def test_park_refuses_motion_until_unparked(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        await blocking(telescope.Park)
        assert await blocking(lambda: telescope.AtPark) is True
        ra, dec = await blocking(lambda: (telescope.RightAscension, telescope.Declination))
        with pytest.raises(ParkedException):  # 0x408
            await blocking(lambda: telescope.SlewToCoordinatesAsync(ra, dec))
        with pytest.raises(ParkedException):
            await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisPrimary, 1.0))
        with pytest.raises(ParkedException):
            await blocking(lambda: telescope.PulseGuide(GuideDirections.guideNorth, 100))
        with pytest.raises(ParkedException):
            await blocking(telescope.AbortSlew)
        await blocking(telescope.Unpark)
        assert await blocking(lambda: telescope.AtPark) is False
        await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisPrimary, 0.0))


async def test_set_park_stores_the_current_position(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        assert await blocking(lambda: telescope.CanSetPark) is True
        await blocking(lambda: setattr(telescope, "Tracking", False))
        await blocking(lambda: telescope.SlewToAltAzAsync(100.0, 30.0))
        await wait_until(lambda: not telescope.Slewing, SLEW_TIMEOUT_S, "the slew's end")
        await blocking(telescope.SetPark)
        assert mount.park_position.alt_deg == pytest.approx(30.0, abs=0.01)
        assert mount.park_position.az_deg == pytest.approx(100.0, abs=0.01)


async def test_move_axis_turns_and_stops(tmp_path: Path) -> None:
    mount = sim_mount(speed_up=WATCHABLE_SPEED_UP)
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        before = mount.counters_at(mount.elapsed())
        await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisSecondary, 1.0))
        assert await blocking(lambda: telescope.Slewing) is True
        await wait_until(
            lambda: abs(mount.counters_at(mount.elapsed())[1] - before[1]) > 2.0, 5.0, "motion"
        )
        await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisSecondary, 0.0))
        await wait_until(lambda: not telescope.Slewing, 5.0, "the stop")
        with pytest.raises(InvalidValueException):
            await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisPrimary, 50.0))
        with pytest.raises(NotImplementedException):
            await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisTertiary, 1.0))


async def test_pulse_guide_nudges_declination(tmp_path: Path) -> None:
    mount = sim_mount(speed_up=WATCHABLE_SPEED_UP)
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        ra_j2000, dec_j2000 = radec_at(mount, 40.0, 200.0)  # away from the pole
        ra, dec = j2000_to_apparent(ra_j2000, dec_j2000, mount.now())
        await blocking(lambda: telescope.SlewToCoordinatesAsync(ra, dec))
        await wait_until(lambda: not telescope.Slewing, SLEW_TIMEOUT_S, "the slew's end")
        dec_before = await blocking(lambda: telescope.Declination)
        duration_ms = 20_000  # simulated: one real second at x20 (WATCHABLE_SPEED_UP)
        await blocking(lambda: telescope.PulseGuide(GuideDirections.guideNorth, duration_ms))
        assert await blocking(lambda: telescope.IsPulseGuiding) is True
        await wait_until(lambda: not telescope.IsPulseGuiding, 5.0, "the pulse's end")
        moved_arcsec = (await blocking(lambda: telescope.Declination) - dec_before) * 3600.0
        expected_arcsec = mount.guide_rate_deg_s * duration_ms / 1000.0 * 3600.0
        assert moved_arcsec == pytest.approx(expected_arcsec, abs=3.0)


async def test_tracking_and_tracking_rates(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        await blocking(lambda: setattr(telescope, "Tracking", True))
        assert mount.state.tracking is TrackingMode.SIDEREAL
        await blocking(lambda: setattr(telescope, "TrackingRate", DriveRates.driveLunar))
        assert _tracking(mount) is TrackingMode.LUNAR
        assert await blocking(lambda: telescope.TrackingRate) == DriveRates.driveLunar
        await blocking(lambda: setattr(telescope, "TrackingRate", DriveRates.driveKing))
        assert _tracking(mount) is TrackingMode.KING
        await blocking(lambda: setattr(telescope, "TrackingRate", DriveRates.driveLunar))
        await blocking(lambda: setattr(telescope, "Tracking", False))
        assert _tracking(mount) is TrackingMode.OFF
        assert await blocking(lambda: telescope.TrackingRate) == DriveRates.driveLunar


async def test_alt_az_mount_tracks_with_its_own_mode(tmp_path: Path) -> None:
    mount = SimulatedMount(AZ_GTI, site=sim_mount().site)
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        assert await blocking(lambda: telescope.AlignmentMode) == AlignmentModes.algAltAz
        with pytest.raises(NotImplementedException):
            await blocking(lambda: telescope.SideOfPier)
        await blocking(lambda: setattr(telescope, "Tracking", True))
        assert mount.state.tracking is TrackingMode.ALT_AZ


async def test_slew_below_the_horizon_is_refused_and_the_mount_stays(tmp_path: Path) -> None:
    mount = sim_mount(limits=Limits(horizon_deg=20.0))
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        before = mount.counters_at(mount.elapsed())
        ra_j2000, dec_j2000 = radec_at(mount, 10.0, 180.0)
        ra, dec = j2000_to_apparent(ra_j2000, dec_j2000, mount.now())
        with pytest.raises(InvalidValueException, match="horizon"):
            await blocking(lambda: telescope.SlewToCoordinatesAsync(ra, dec))
        with pytest.raises(InvalidValueException, match="horizon"):
            await blocking(lambda: telescope.SlewToAltAzAsync(180.0, 5.0))
        assert await blocking(lambda: telescope.Slewing) is False
        assert mount.counters_at(mount.elapsed()) == pytest.approx(before, abs=1e-3)


async def test_site_and_time_are_settable(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)

        def set_site() -> None:
            telescope.SiteLatitude = 45.5
            telescope.SiteLongitude = -70.25
            telescope.SiteElevation = 1200.0

        await blocking(set_site)
        assert (mount.site.latitude_deg, mount.site.longitude_deg) == (45.5, -70.25)
        assert mount.site.elevation_m == 1200.0
        with pytest.raises(InvalidValueException):
            await blocking(lambda: setattr(telescope, "SiteLatitude", 91.0))
        assert mount.site.latitude_deg == 45.5
        await blocking(lambda: setattr(telescope, "UTCDate", "2027-03-04T05:06:07.1234567Z"))
        assert abs((mount.now() - datetime(2027, 3, 4, 5, 6, 7, tzinfo=UTC)).total_seconds()) < 60.0


def _tracking(mount: SimulatedMount) -> TrackingMode:
    """The tracking mode now (a function call, so mypy does not narrow it across awaits)."""
    return mount.state.tracking


async def test_destination_side_of_pier_matches_where_the_slew_lands(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await _connect(telescope)
        for az in (120.0, 240.0):  # east, then west of the meridian
            ra_j2000, dec_j2000 = radec_at(mount, 40.0, az)
            ra, dec = j2000_to_apparent(ra_j2000, dec_j2000, mount.now())
            predicted = await blocking(partial(telescope.DestinationSideOfPier, ra, dec))
            await blocking(partial(telescope.SlewToCoordinatesAsync, ra, dec))
            await wait_until(lambda: not telescope.Slewing, SLEW_TIMEOUT_S, "the slew's end")
            assert await blocking(lambda: telescope.SideOfPier) == predicted
            expected = PierSide.pierWest if az < 180.0 else PierSide.pierEast
            assert predicted == expected
