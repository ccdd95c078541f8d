"""The ASCOM ITelescopeV4 device over any :class:`~scopelink.mount.Mount`.

Every member of the interface is in :attr:`TelescopeDevice.members`, keyed by its lower-case
URL name, with a handler for GET (properties), PUT (methods and setters) or both. Reads come from
the mount's state cache (``mount.state``), never from the wire; commands go through the
Mount's public, limit-checked methods. What the mount cannot do answers NotImplemented (0x400).
See ``docs/alpaca.md`` for the member table and the decisions taken where ASCOM is silent.
"""

from __future__ import annotations

import asyncio
import enum
import logging
import re
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, replace
from datetime import UTC, datetime

from scopelink import __version__ as scopelink_version
from scopelink.astro import (
    apparent_to_j2000,
    destination_side_of_pier,
    hour_angle_hours,
    j2000_to_apparent,
    lst_hours,
    observed_to_j2000,
)
from scopelink.mount import (
    MAX_PULSE_GUIDE_MS,
    AlignmentMode,
    GuideDirection,
    Mount,
    MountAxis,
    MountError,
    MountState,
    ParkPosition,
    TrackingMode,
)
from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber, from_mount_error
from scopelink.servers.alpaca.params import Params

__all__ = [
    "INTERFACE_VERSION",
    "MAX_SETTLE_TIME_S",
    "DriveRate",
    "EquatorialSystem",
    "Member",
    "TelescopeConfig",
    "TelescopeDevice",
]

logger = logging.getLogger(__name__)

INTERFACE_VERSION = 4
"""ITelescopeV4 (ASCOM Platform 7): Connect/Disconnect/Connecting and DeviceState."""

MAX_SETTLE_TIME_S = 300
"""Longest SlewSettleTime accepted (seconds): a longer one holds every synchronous slew for
that long, which is a typo (milliseconds?) rather than a mount's settling."""

_SLEW_POLL_S = 0.05
"""How often a synchronous slew looks at the state cache for the end of the slew."""


class EquatorialSystem(enum.IntEnum):
    """ASCOM ``EquatorialCoordinateType``: the frame RightAscension/Declination use."""

    TOPOCENTRIC = 1  # "JNow": apparent place of date, what most ASCOM drivers report
    J2000 = 2


class DriveRate(enum.IntEnum):
    """ASCOM ``DriveRates``."""

    SIDEREAL = 0
    LUNAR = 1
    SOLAR = 2
    KING = 3


_DRIVE_RATE_OF_MODE = {
    TrackingMode.SIDEREAL: DriveRate.SIDEREAL,
    TrackingMode.ALT_AZ: DriveRate.SIDEREAL,
    TrackingMode.PEC: DriveRate.SIDEREAL,
    TrackingMode.LUNAR: DriveRate.LUNAR,
    TrackingMode.SOLAR: DriveRate.SOLAR,
}

_ALIGNMENT = {AlignmentMode.ALT_AZ: 0, AlignmentMode.POLAR: 1, AlignmentMode.GERMAN_POLAR: 2}
_GUIDE_DIRECTIONS = (
    GuideDirection.NORTH,
    GuideDirection.SOUTH,
    GuideDirection.EAST,
    GuideDirection.WEST,
)
_FRACTION_DIGITS = re.compile(r"(\.\d{6})\d+")
_FRESH_READS = {
    "altitude": True,
    "azimuth": True,
    "rightascension": True,
    "declination": True,
    "sideofpier": True,
    "atpark": False,
    "slewing": False,
    "tracking": False,
    "ispulseguiding": False,
}
"""Reads of the device's state, refused while it is not current: True for the position's age,
False for the state flags' (docs/alpaca.md, "Lost and stalled devices")."""


@dataclass(frozen=True, slots=True)
class TelescopeConfig:
    """What the Alpaca telescope says about itself and which frame it speaks."""

    equatorial_system: EquatorialSystem = EquatorialSystem.TOPOCENTRIC
    name: str = "scopelink telescope"
    description: str = "scopelink: a Sky-Watcher SynScan / Sky Tracker mount over ASCOM Alpaca"
    slew_timeout_s: float = 600.0
    """Longest a synchronous slew (SlewToCoordinates, SlewToTarget, SlewToAltAz) may take."""


Handler = Callable[[Params], object]
"""Takes the request's parameters; returns the Value (or an awaitable of it), None for none."""


@dataclass(frozen=True, slots=True)
class Member:
    """One ITelescopeV4 member: its GET and PUT handlers and whether it needs a connection."""

    get: Handler | None = None
    put: Handler | None = None
    needs_connection: bool = True


def _not_implemented(what: str) -> Handler:
    def handler(_: Params) -> object:
        raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, f"{what} is not implemented by this mount")

    return handler


def format_utc(when: datetime) -> str:
    """ASCOM's UTCDate text: ISO 8601 in UTC with a trailing ``Z``."""
    return when.astimezone(UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


def parse_utc(text: str) -> datetime:
    """An ISO 8601 date-time; ``Z`` or an offset, or none (then it is UTC, as ASCOM says)."""
    cleaned = _FRACTION_DIGITS.sub(r"\1", text.strip())  # .NET sends 7 fraction digits
    try:
        when = datetime.fromisoformat(cleaned)
        return when.replace(tzinfo=UTC) if when.tzinfo is None else when.astimezone(UTC)
    except ValueError:
        raise AlpacaError(
            ErrorNumber.INVALID_VALUE,
            f"UTCDate {text!r} is not an ISO 8601 date-time (e.g. 2026-11-22T21:30:00Z)",
        ) from None
    except OverflowError:  # an offset that carries it past year 9999 or before year 1
        raise AlpacaError(
            ErrorNumber.INVALID_VALUE, f"UTCDate {text!r} lies outside any calendar"
        ) from None


class TelescopeDevice:
    """ASCOM ``telescope/0`` over ``mount``: one object per served device."""

    def __init__(self, mount: Mount, config: TelescopeConfig | None = None) -> None:
        self.mount = mount
        self.config = config or TelescopeConfig()
        self._connected = False
        self._connect_task: asyncio.Task[None] | None = None
        self._target_ra: float | None = None
        self._target_dec: float | None = None
        self._slew_started_at: datetime | None = None
        self._settle_time_s = 0
        self._drive_rate = DriveRate.SIDEREAL
        self.members: dict[str, Member] = self._member_table()

    # --- connection ------------------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        """Whether an Alpaca client has connected and the mount itself is connected."""
        return self._connected and self.mount.state.connected

    @property
    def connecting(self) -> bool:
        return self._connect_task is not None and not self._connect_task.done()

    async def connect(self) -> None:
        """Connect the mount if it is not already (other front ends may share it)."""
        if not self.mount.state.connected:
            try:
                await self.mount.connect()
            except MountError as error:
                raise from_mount_error(error) from error
        self._connected = True

    def disconnect(self) -> None:
        """Forget the Alpaca connection; the mount stays connected for other front ends."""
        self._connected = False

    def _start_connect(self, _: Params) -> None:
        if not self.connecting:
            self._connect_task = asyncio.create_task(self._connect_in_background())

    async def _connect_in_background(self) -> None:
        try:
            await self.connect()
        except AlpacaError as error:
            logger.warning("Alpaca Connect failed: %s", error.message)

    async def close(self) -> None:
        """Stop a Connect still running (the server is shutting down)."""
        task = self._connect_task
        if task is not None and not task.done():
            task.cancel()
            await asyncio.gather(task, return_exceptions=True)

    def require_connected(self) -> None:
        if not self._connected:
            raise AlpacaError(
                ErrorNumber.NOT_CONNECTED, "not connected: set Connected to True (or Connect) first"
            )
        if not self.mount.state.connected:
            self.require_fresh()  # names the link's loss and the last reading's age
            raise AlpacaError(ErrorNumber.NOT_CONNECTED, "the mount has lost its connection")

    def require_fresh(self, *, position: bool = True) -> MountState:
        """The state, if it may be served as current: 0x407 while the link is down, 0x500 when
        the reading is older than the mount's ``stale_after_s`` (both name its age)."""
        try:
            return self.mount.fresh_state(position=position)
        except MountError as error:
            raise from_mount_error(error) from None

    # --- state helpers ---------------------------------------------------------------------------

    @property
    def state(self) -> MountState:
        return self.mount.state

    @property
    def slewing(self) -> bool:
        """The cache's word, or True while the cache still predates a slew we just started."""
        state = self.mount.state
        started = self._slew_started_at
        return state.slewing or (started is not None and state.read_at < started)

    def _position(self, value: float | None, what: str) -> float:
        if value is None:
            raise AlpacaError(
                ErrorNumber.DRIVER_ERROR, f"the mount has not reported its {what} yet"
            )
        return value

    def _radec_if_known(self, state: MountState) -> tuple[float | None, float | None]:
        """RA/Dec of ``state`` in the configured frame (None before the first reading)."""
        if self.config.equatorial_system is EquatorialSystem.J2000:
            return state.ra_j2000_hours, state.dec_j2000_deg
        return state.ra_of_date_hours, state.dec_of_date_deg

    def _radec(self) -> tuple[float, float]:
        """The current RA/Dec in the configured frame."""
        ra, dec = self._radec_if_known(self.mount.state)
        return self._position(ra, "position"), self._position(dec, "position")

    def to_j2000(self, ra_hours: float, dec_deg: float) -> tuple[float, float]:
        """Client coordinates (the configured frame) as J2000."""
        if self.config.equatorial_system is EquatorialSystem.J2000:
            return ra_hours, dec_deg
        return apparent_to_j2000(ra_hours, dec_deg, self.mount.now())

    def _to_apparent(self, ra_hours: float, dec_deg: float) -> tuple[float, float]:
        if self.config.equatorial_system is EquatorialSystem.TOPOCENTRIC:
            return ra_hours, dec_deg
        return j2000_to_apparent(ra_hours, dec_deg, self.mount.now())

    def _supported_drive_rates(self) -> list[DriveRate]:
        modes = self.mount.capabilities.tracking_modes
        return [rate for rate in DriveRate if self._mode_for(rate) in modes]

    def _mode_for(self, rate: DriveRate) -> TrackingMode | None:
        modes = self.mount.capabilities.tracking_modes
        if rate is DriveRate.SIDEREAL:
            # An alt-az mount follows the stars on both axes: its own mode (SynScan's "alt-az").
            preferred = (
                (TrackingMode.ALT_AZ, TrackingMode.SIDEREAL)
                if self.mount.capabilities.alignment_mode is AlignmentMode.ALT_AZ
                else (TrackingMode.SIDEREAL, TrackingMode.PEC, TrackingMode.ALT_AZ)
            )
            for mode in preferred:
                if mode in modes:
                    return mode
            return None
        if rate is DriveRate.LUNAR:
            return TrackingMode.LUNAR
        if rate is DriveRate.SOLAR:
            return TrackingMode.SOLAR
        return None

    def _is_gem(self) -> bool:
        return self.mount.capabilities.alignment_mode is AlignmentMode.GERMAN_POLAR

    @staticmethod
    async def _call(action: Awaitable[None]) -> None:
        try:
            await action
        except MountError as error:
            raise from_mount_error(error) from error

    def _require_unparked(self) -> None:
        if self.mount.state.parked:
            raise AlpacaError(
                ErrorNumber.INVALID_WHILE_PARKED, "the mount is parked: Unpark it first"
            )

    def _require_tracking_off(self, what: str) -> None:
        if self.mount.state.tracking is not TrackingMode.OFF:
            raise AlpacaError(
                ErrorNumber.INVALID_OPERATION, f"{what} needs Tracking off (ASCOM): set it False"
            )

    # --- common members --------------------------------------------------------------------------

    async def _put_connected(self, params: Params) -> None:
        if params.boolean("Connected"):
            await self.connect()
        else:
            self.disconnect()

    def _put_disconnect(self, _: Params) -> None:
        self.disconnect()

    def _driver_info(self, _: Params) -> str:
        identity = self.mount.identity
        model = f"{identity.protocol} {identity.model}".strip()
        firmware = f" (firmware {identity.firmware})" if identity.firmware else ""
        return (
            f"scopelink {scopelink_version} ASCOM Alpaca telescope server; mount: {model}{firmware}"
        )

    def _device_state(self, _: Params) -> list[dict[str, object]]:
        # ASCOM: a value that cannot be read is left out. A stale reading is not current.
        state = self.mount.state
        flags_fresh = self._is_fresh(position=False)
        values: dict[str, object] = {"AtHome": False}
        if flags_fresh:
            values |= {
                "AtPark": state.parked,
                "IsPulseGuiding": state.pulse_guiding,
                "Slewing": self.slewing,
                "Tracking": state.tracking is not TrackingMode.OFF,
            }
        values["SiderealTime"] = self.sidereal_time()
        values["UTCDate"] = format_utc(self.mount.now())
        position_fresh = self._is_fresh(position=True)
        if position_fresh and state.alt_deg is not None and state.az_deg is not None:
            values["Altitude"] = state.alt_deg
            values["Azimuth"] = state.az_deg
        ra, dec = self._radec_if_known(state)
        if position_fresh and ra is not None and dec is not None:
            values["RightAscension"] = ra
            values["Declination"] = dec
        if position_fresh and self.mount.capabilities.can_report_pier_side:
            values["SideOfPier"] = int(state.pier_side)
        values["TimeStamp"] = format_utc(state.read_at)[:-1]  # ASCOM: local-less ISO stamp
        return [{"Name": name, "Value": value} for name, value in values.items()]

    def _is_fresh(self, *, position: bool) -> bool:
        try:
            self.mount.fresh_state(position=position)
        except MountError:
            return False
        return True

    def _fresh_read(self, read: Handler, *, position: bool) -> Handler:
        """``read``, refused while the state it reports is not current (see require_fresh)."""

        def handler(params: Params) -> object:
            self.require_fresh(position=position)
            return read(params)

        return handler

    # --- telescope reads -------------------------------------------------------------------------

    def sidereal_time(self) -> float:
        """Local apparent sidereal time (hours) at the mount's clock and site."""
        return lst_hours(self.mount.now(), self.mount.site.longitude_deg)

    def _side_of_pier(self, _: Params) -> int:
        if not self.mount.capabilities.can_report_pier_side:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount does not report pier side")
        return int(self.mount.state.pier_side)

    def _destination_side_of_pier(self, params: Params) -> int:
        ra = params.number("RightAscension", 0.0, 24.0)
        dec = params.number("Declination", -90.0, 90.0)
        if not self._is_gem():
            raise AlpacaError(
                ErrorNumber.NOT_IMPLEMENTED, "only a German equatorial mount has a pier side"
            )
        ra_apparent, _ = self._to_apparent(ra % 24.0, dec)
        lst = lst_hours(self.mount.now(), self.mount.site.longitude_deg)
        return int(destination_side_of_pier(hour_angle_hours(lst, ra_apparent)))

    def _tracking_rate(self, _: Params) -> int:
        tracking = self.mount.state.tracking
        return int(_DRIVE_RATE_OF_MODE.get(tracking, self._drive_rate))

    def _guide_rate(self, _: Params) -> float:
        # The Mount API has no guide rate; a mount that knows its own (the simulator) says it.
        rate = getattr(self.mount, "guide_rate_deg_s", None)
        if not isinstance(rate, float):
            raise AlpacaError(
                ErrorNumber.NOT_IMPLEMENTED, "this mount does not report a guide rate"
            )
        return rate

    def _axis(self, params: Params) -> int:
        return params.integer("Axis", 0, 2)

    def _axis_rates(self, params: Params) -> list[dict[str, float]]:
        axis = self._axis(params)
        caps = self.mount.capabilities
        if axis == 2 or not caps.can_move_axis[axis]:
            return []
        return [{"Minimum": 0.0, "Maximum": caps.max_axis_rate_deg_s}]

    def _can_move_axis(self, params: Params) -> bool:
        axis = self._axis(params)
        return axis != 2 and self.mount.capabilities.can_move_axis[axis]

    def _target(self, value: float | None, what: str) -> float:
        if value is None:
            raise AlpacaError(ErrorNumber.VALUE_NOT_SET, f"{what} has not been set")
        return value

    # --- telescope setters -----------------------------------------------------------------------

    def _put_target_ra(self, params: Params) -> None:
        self._target_ra = params.number("TargetRightAscension", 0.0, 24.0) % 24.0

    def _put_target_dec(self, params: Params) -> None:
        self._target_dec = params.number("TargetDeclination", -90.0, 90.0)

    def _put_settle_time(self, params: Params) -> None:
        self._settle_time_s = params.integer("SlewSettleTime", 0, MAX_SETTLE_TIME_S)

    async def _put_tracking(self, params: Params) -> None:
        on = params.boolean("Tracking")
        mode = self._mode_for(self._drive_rate) if on else TrackingMode.OFF
        if mode is None:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot track")
        await self._call(self.mount.set_tracking(mode))

    async def _put_tracking_rate(self, params: Params) -> None:
        value = params.integer("TrackingRate", 0, 3)
        rate = DriveRate(value)
        if rate not in self._supported_drive_rates():
            raise AlpacaError(
                ErrorNumber.INVALID_VALUE, f"tracking rate {rate.name.lower()} is not supported"
            )
        self._drive_rate = rate
        mode = self._mode_for(rate)
        if mode is not None and self.mount.state.tracking is not TrackingMode.OFF:
            await self._call(self.mount.set_tracking(mode))

    async def _put_utc_date(self, params: Params) -> None:
        when = parse_utc(params.text("UTCDate"))
        # The Mount API refuses a time no mount can keep (0x401) before a mount that keeps no
        # time says so (0x400): the same value gets the same answer on every mount.
        await self._call(self.mount.set_time(when))

    async def _set_site(self, **change: float) -> None:
        if not self.mount.capabilities.can_set_site:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount's site cannot be set")
        try:
            site = replace(self.mount.site, **change)
        except (TypeError, ValueError) as error:
            raise AlpacaError(ErrorNumber.INVALID_VALUE, str(error)) from None
        await self._call(self.mount.set_site(site))

    async def _put_latitude(self, params: Params) -> None:
        await self._set_site(latitude_deg=params.number("SiteLatitude", -90.0, 90.0))

    async def _put_longitude(self, params: Params) -> None:
        await self._set_site(longitude_deg=params.number("SiteLongitude", -180.0, 180.0))

    async def _put_elevation(self, params: Params) -> None:
        await self._set_site(elevation_m=params.number("SiteElevation", -300.0, 10000.0))

    # --- motion ----------------------------------------------------------------------------------

    def _mark_slew_started(self, started: datetime) -> None:
        self._slew_started_at = started

    async def _goto_radec(self, ra_hours: float, dec_deg: float) -> None:
        self._require_unparked()
        ra_j2000, dec_j2000 = self.to_j2000(ra_hours % 24.0, dec_deg)
        started = self.mount.now()
        await self._call(self.mount.goto_equatorial(ra_j2000, dec_j2000))
        self._mark_slew_started(started)

    async def _goto_altaz(self, params: Params) -> None:
        azimuth = params.number("Azimuth", 0.0, 360.0) % 360.0
        altitude = params.number("Altitude", -90.0, 90.0)
        self._require_unparked()
        self._require_tracking_off("SlewToAltAz")
        started = self.mount.now()
        await self._call(self.mount.goto_horizontal(altitude, azimuth))
        self._mark_slew_started(started)

    def _coordinates(self, params: Params) -> tuple[float, float]:
        ra = params.number("RightAscension", 0.0, 24.0) % 24.0
        dec = params.number("Declination", -90.0, 90.0)
        return ra, dec

    async def _slew_to_coordinates_async(self, params: Params) -> None:
        ra, dec = self._coordinates(params)
        self._target_ra, self._target_dec = ra, dec
        await self._goto_radec(ra, dec)

    async def _slew_to_coordinates(self, params: Params) -> None:
        await self._slew_to_coordinates_async(params)
        await self._wait_for_slew()

    async def _slew_to_target_async(self, _: Params) -> None:
        ra = self._target(self._target_ra, "TargetRightAscension")
        dec = self._target(self._target_dec, "TargetDeclination")
        await self._goto_radec(ra, dec)

    async def _slew_to_target(self, params: Params) -> None:
        await self._slew_to_target_async(params)
        await self._wait_for_slew()

    async def _slew_to_altaz(self, params: Params) -> None:
        await self._goto_altaz(params)
        await self._wait_for_slew()

    async def _wait_for_slew(self) -> None:
        """Return once the state cache says the slew has ended, then wait SlewSettleTime."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.config.slew_timeout_s
        while self.slewing or not self.mount.state.connected:
            if not self.mount.state.connected:  # the end of the slew cannot be seen
                self.require_fresh(position=False)
            if loop.time() > deadline:
                raise AlpacaError(
                    ErrorNumber.DRIVER_ERROR,
                    f"the slew has not ended within {self.config.slew_timeout_s:g} s",
                )
            await asyncio.sleep(_SLEW_POLL_S)
        if self._settle_time_s:
            await asyncio.sleep(self._settle_time_s)

    async def _sync(self, ra_hours: float, dec_deg: float) -> None:
        self._require_unparked()
        if not self.mount.capabilities.can_sync:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot sync")
        ra_j2000, dec_j2000 = self.to_j2000(ra_hours, dec_deg)
        await self._call(self.mount.sync_equatorial(ra_j2000, dec_j2000))

    async def _sync_to_coordinates(self, params: Params) -> None:
        ra, dec = self._coordinates(params)
        self._target_ra, self._target_dec = ra, dec
        await self._sync(ra, dec)

    async def _sync_to_target(self, _: Params) -> None:
        ra = self._target(self._target_ra, "TargetRightAscension")
        dec = self._target(self._target_dec, "TargetDeclination")
        await self._sync(ra, dec)

    async def _sync_to_altaz(self, params: Params) -> None:
        azimuth = params.number("Azimuth", 0.0, 360.0) % 360.0
        altitude = params.number("Altitude", -90.0, 90.0)
        if not self.mount.capabilities.can_sync:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot sync")
        self._require_unparked()
        self._require_tracking_off("SyncToAltAz")
        ra, dec = observed_to_j2000(altitude, azimuth, self.mount.now(), self.mount.site)
        await self._call(self.mount.sync_equatorial(ra, dec))

    async def _abort_slew(self, _: Params) -> None:
        if not self._connected:
            self.require_connected()
        self._require_unparked()
        await self._call(self.mount.abort())
        self._slew_started_at = None

    async def _move_axis(self, params: Params) -> None:
        axis = self._axis(params)
        rate = params.number("Rate")
        if axis == 2 or not self.mount.capabilities.can_move_axis[axis]:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, f"axis {axis} cannot be moved at a rate")
        self._require_unparked()
        await self._call(self.mount.move_axis(MountAxis(axis), rate))

    async def _pulse_guide(self, params: Params) -> None:
        direction = params.integer("Direction", 0, 3)
        duration = params.integer("Duration", 0, MAX_PULSE_GUIDE_MS)
        if not self.mount.capabilities.can_pulse_guide:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot pulse-guide")
        self._require_unparked()
        await self._call(self.mount.pulse_guide(_GUIDE_DIRECTIONS[direction], duration))

    async def _park(self, _: Params) -> None:
        if not self.mount.capabilities.can_park:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot park")
        if self.mount.state.parked:
            return  # ASCOM: Park when already parked does nothing
        started = self.mount.now()
        await self._call(self.mount.park())
        self._mark_slew_started(started)

    async def _unpark(self, _: Params) -> None:
        if not self.mount.capabilities.can_park:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot unpark")
        await self._call(self.mount.unpark())

    def _set_park(self, _: Params) -> None:
        if not self.mount.capabilities.can_set_park:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount's park position is fixed")
        state = self.mount.state
        alt = self._position(state.alt_deg, "position")
        az = self._position(state.az_deg, "position")
        try:  # refused outside the limits: every later Park would drive the mount there
            self.mount.park_position = ParkPosition(alt, az % 360.0)
        except MountError as error:
            raise from_mount_error(error) from error

    # --- the member table ------------------------------------------------------------------------

    def _member_table(self) -> dict[str, Member]:
        caps = self.mount.capabilities
        config = self.config
        mount = self.mount
        ni = _not_implemented

        def static(value: object) -> Member:
            return Member(get=lambda _: value, needs_connection=False)

        def can(value: bool) -> Member:
            return static(value)

        table: dict[str, Member] = {
            # common members
            "connected": Member(
                get=lambda _: self.connected, put=self._put_connected, needs_connection=False
            ),
            "connecting": Member(get=lambda _: self.connecting, needs_connection=False),
            "connect": Member(put=self._start_connect, needs_connection=False),
            "disconnect": Member(put=self._put_disconnect, needs_connection=False),
            "devicestate": Member(get=self._device_state),
            "description": static(config.description),
            "driverinfo": Member(get=self._driver_info, needs_connection=False),
            "driverversion": static(scopelink_version),
            "interfaceversion": static(INTERFACE_VERSION),
            "name": static(config.name),
            "supportedactions": static([]),
            "action": Member(put=self._action, needs_connection=False),
            "commandblind": Member(put=ni("CommandBlind"), needs_connection=False),
            "commandbool": Member(put=ni("CommandBool"), needs_connection=False),
            "commandstring": Member(put=ni("CommandString"), needs_connection=False),
            # capabilities and fixed facts
            "alignmentmode": static(_ALIGNMENT[caps.alignment_mode]),
            "equatorialsystem": static(int(config.equatorial_system)),
            "canfindhome": can(False),
            "canpark": can(caps.can_park),
            "canunpark": can(caps.can_park),
            "cansetpark": can(caps.can_set_park),
            "canpulseguide": can(caps.can_pulse_guide),
            "cansetdeclinationrate": can(False),
            "cansetrightascensionrate": can(False),
            "cansetguiderates": can(False),
            "cansetpierside": can(False),
            "cansettracking": can(len(caps.tracking_modes - {TrackingMode.OFF}) > 0),
            "canslew": can(caps.can_goto),
            "canslewasync": can(caps.can_goto),
            "canslewaltaz": can(caps.can_goto_altaz),
            "canslewaltazasync": can(caps.can_goto_altaz),
            "cansync": can(caps.can_sync),
            "cansyncaltaz": can(caps.can_sync),
            "canmoveaxis": Member(get=self._can_move_axis, needs_connection=False),
            "axisrates": Member(get=self._axis_rates, needs_connection=False),
            "trackingrates": Member(
                get=lambda _: [int(rate) for rate in self._supported_drive_rates()],
                needs_connection=False,
            ),
            "aperturearea": Member(get=ni("ApertureArea")),
            "aperturediameter": Member(get=ni("ApertureDiameter")),
            "focallength": Member(get=ni("FocalLength")),
            # state
            "altitude": Member(get=lambda _: self._position(mount.state.alt_deg, "altitude")),
            "azimuth": Member(get=lambda _: self._position(mount.state.az_deg, "azimuth")),
            "rightascension": Member(get=lambda _: self._radec()[0]),
            "declination": Member(get=lambda _: self._radec()[1]),
            "athome": Member(get=lambda _: False),
            "atpark": Member(get=lambda _: mount.state.parked),
            "slewing": Member(get=lambda _: self.slewing),
            "ispulseguiding": Member(get=lambda _: mount.state.pulse_guiding),
            "sideofpier": Member(get=self._side_of_pier, put=ni("Setting SideOfPier")),
            "destinationsideofpier": Member(get=self._destination_side_of_pier),
            "siderealtime": Member(get=lambda _: self.sidereal_time()),
            "tracking": Member(
                get=lambda _: mount.state.tracking is not TrackingMode.OFF,
                put=self._put_tracking,
            ),
            "trackingrate": Member(get=self._tracking_rate, put=self._put_tracking_rate),
            "rightascensionrate": Member(get=lambda _: 0.0, put=ni("RightAscensionRate")),
            "declinationrate": Member(get=lambda _: 0.0, put=ni("DeclinationRate")),
            "guideratedeclination": Member(get=self._guide_rate, put=ni("GuideRateDeclination")),
            "guideraterightascension": Member(
                get=self._guide_rate, put=ni("GuideRateRightAscension")
            ),
            "doesrefraction": Member(
                get=lambda _: mount.site.refracts, put=ni("Setting DoesRefraction")
            ),
            "utcdate": Member(get=lambda _: format_utc(mount.now()), put=self._put_utc_date),
            "sitelatitude": Member(get=lambda _: mount.site.latitude_deg, put=self._put_latitude),
            "sitelongitude": Member(
                get=lambda _: mount.site.longitude_deg, put=self._put_longitude
            ),
            "siteelevation": Member(get=lambda _: mount.site.elevation_m, put=self._put_elevation),
            "slewsettletime": Member(get=lambda _: self._settle_time_s, put=self._put_settle_time),
            "targetrightascension": Member(
                get=lambda _: self._target(self._target_ra, "TargetRightAscension"),
                put=self._put_target_ra,
            ),
            "targetdeclination": Member(
                get=lambda _: self._target(self._target_dec, "TargetDeclination"),
                put=self._put_target_dec,
            ),
            # methods
            "abortslew": Member(put=self._abort_slew),
            "findhome": Member(put=ni("FindHome")),
            "moveaxis": Member(put=self._move_axis),
            "park": Member(put=self._park),
            "unpark": Member(put=self._unpark),
            "setpark": Member(put=self._set_park),
            "pulseguide": Member(put=self._pulse_guide),
            "slewtoaltaz": Member(put=self._slew_to_altaz),
            "slewtoaltazasync": Member(put=self._goto_altaz),
            "slewtocoordinates": Member(put=self._slew_to_coordinates),
            "slewtocoordinatesasync": Member(put=self._slew_to_coordinates_async),
            "slewtotarget": Member(put=self._slew_to_target),
            "slewtotargetasync": Member(put=self._slew_to_target_async),
            "synctoaltaz": Member(put=self._sync_to_altaz),
            "synctocoordinates": Member(put=self._sync_to_coordinates),
            "synctotarget": Member(put=self._sync_to_target),
        }
        for name, position in _FRESH_READS.items():
            if name == "sideofpier" and not caps.can_report_pier_side:
                continue  # not implemented, however fresh
            member = table[name]
            assert member.get is not None
            table[name] = replace(member, get=self._fresh_read(member.get, position=position))
        # An abort is tried while the link is down too (the driver tries it, or owes it).
        table["abortslew"] = replace(table["abortslew"], needs_connection=False)
        return table

    def _action(self, params: Params) -> None:
        name = params.optional("Action") or ""
        raise AlpacaError(
            ErrorNumber.ACTION_NOT_IMPLEMENTED,
            f"action {name!r} is not supported (SupportedActions is empty)",
        )
