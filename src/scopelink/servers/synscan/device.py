"""The hand control itself: each SynScan command becomes calls on a Mount and one reply.

One :class:`SynScanHandControl` per emulated device, shared by all its connections. It keeps what a
real hand control keeps and the motor controllers do not: its alignment state, its clock and time
zone, where the axes were at power-on, whether a goto it started is still running.
"""

from __future__ import annotations

import functools
import logging
import math
from collections.abc import Awaitable, Callable
from dataclasses import replace
from datetime import UTC, datetime, timedelta, timezone
from typing import Protocol, TypeVar, runtime_checkable

from scopelink.astro import SIDEREAL_RATE_DEG_S, angular_separation_deg, observed_to_j2000
from scopelink.mount import (
    AlignmentMode,
    InvalidValueError,
    Mount,
    MountAxis,
    MountError,
    MountState,
    PierSide,
    SunAvoidanceError,
    TrackingMode,
)
from scopelink.protocol import synscan
from scopelink.protocol.synscan import AnyCommand, AnyReply, Axis, Tracking
from scopelink.servers.synscan.config import SynScanConfig
from scopelink.sim import SimulatedMount, synscan_fixed_rate_deg_s

__all__ = ["AxisPositioning", "NoReply", "SynScanHandControl"]

logger = logging.getLogger(__name__)

GUIDING_RATES = frozenset({1, 2})
"""Fixed rates that, while tracking equatorially, add to tracking instead of replacing it."""

_FAILED_PASSTHROUGH_EXTRA = 0x01

_AXES = {Axis.AZM_RA: MountAxis.PRIMARY, Axis.ALT_DEC: MountAxis.SECONDARY}

_SYNSCAN_TRACKING = {
    TrackingMode.OFF: Tracking.OFF,
    TrackingMode.ALT_AZ: Tracking.ALT_AZ,
    TrackingMode.SIDEREAL: Tracking.EQUATORIAL,
    TrackingMode.LUNAR: Tracking.EQUATORIAL,
    TrackingMode.SOLAR: Tracking.EQUATORIAL,
    TrackingMode.KING: Tracking.EQUATORIAL,
    TrackingMode.PEC: Tracking.PEC,
}
_EQUATORIAL_TRACKING = frozenset(
    {
        TrackingMode.SIDEREAL,
        TrackingMode.LUNAR,
        TrackingMode.SOLAR,
        TrackingMode.KING,
        TrackingMode.PEC,
    }
)
_MOUNT_TRACKING: dict[int, TrackingMode] = {
    Tracking.OFF: TrackingMode.OFF,
    Tracking.ALT_AZ: TrackingMode.ALT_AZ,
    Tracking.EQUATORIAL: TrackingMode.SIDEREAL,
    Tracking.PEC: TrackingMode.PEC,
}


class NoReadingError(MountError):
    """The mount has no reading of what a command asks for."""


class NoReply(Exception):  # noqa: N818 - named after what the server does with it
    """The command gets no reply (the message says why)."""


_Read = TypeVar("_Read", bound=synscan.Command)
_Answer = Callable[["SynScanHandControl", _Read], Awaitable[AnyReply]]


def _state_read(answer: _Answer[_Read]) -> _Answer[_Read]:
    """Marks a read answered from the mount's state: without a current one it gets no reply
    (:class:`NoReply`), where the mount refusing any other command gets ``#``."""

    @functools.wraps(answer)
    async def read(hand_control: SynScanHandControl, command: _Read) -> AnyReply:
        try:
            return await answer(hand_control, command)
        except SunAvoidanceError:
            raise
        except MountError as error:
            raise NoReply(f"{command.describe()} not answered: {error}") from None

    return read


@runtime_checkable
class AxisPositioning(Protocol):
    """What a mount offers for the passthrough slow goto and set-position commands (the
    simulated mount does)."""

    def set_axis_position(self, axis: MountAxis, position_deg: float) -> None:
        """Declare that one axis counter now reads ``position_deg``, without moving it."""

    def slew_axis_to(
        self, axis: MountAxis, position_deg: float, *, max_rate_deg_s: float | None = None
    ) -> float:
        """Turn one axis counter to ``position_deg``; returns when (elapsed s) it lands."""


class SynScanHandControl:
    """The state and command semantics of one SynScan hand control in front of ``mount``.

    Fixed rates 1-9 are the simulator's table of the hand control's speed keys.
    Call :meth:`power_on` once before the first command.
    """

    def __init__(
        self, mount: Mount, config: SynScanConfig | None = None, *, axis_passthrough: bool = True
    ) -> None:
        self.mount = mount
        self.config = config or SynScanConfig()
        self.axis_passthrough = axis_passthrough
        """Whether "slow goto" and "set axis position" reach a mount that offers them (the
        device emulator's simulated mount). A bridge (``scopelink serve``) turns them off: they
        move or redefine an axis counter past every check of the Mount API (horizon, Sun,
        ``limits.max_sync_deg``), and it answers them as over a real device."""
        self.aligned = self.config.aligned
        self.clock_offset = timedelta(0)
        """How far the hand control's clock is ahead of the mount's (set by ``H``)."""
        self.utc_offset_hours = 0
        self.dst = False
        self._power_on_az_alt = (0.0, 0.0)
        self._goto_running = False
        self._goto_sticky = False
        self._goto_sent_at: datetime | None = None
        self._axis_rates: dict[MountAxis, float] = {}

    async def power_on(self) -> None:
        """Remember where the axes point now: unaligned Alt-Az positions are relative to it
        (the last reading when no current one can be had: a bridge starts all the same)."""
        try:
            state = await self.mount.current_state()
        except MountError as error:
            logger.warning("power-on position from the last reading: %s", error)
            state = self.mount.state
        self._power_on_az_alt = (state.az_deg or 0.0, state.alt_deg or 0.0)

    async def power_cycle(self) -> None:
        """Switch the hand control and the motor controllers off and on again, as a real one.

        The tube stays where it points; the motors stop (tracking too); the counters read their
        power-on values again (the geometry's home: counterweight down at the pole, or level
        pointing north) and the hand control forgets its alignment, any goto and that it was
        parked. Its site and clock are kept (a real one asks for them at power-on: the observer
        types the same). Only an emulated mount can be power-cycled (a bridge cannot switch off
        the mount behind it): anything else raises :class:`InvalidValueError`.
        """
        mount = self.mount
        if not isinstance(mount, SimulatedMount):
            raise InvalidValueError("only an emulated mount can be power-cycled")
        await mount.abort()  # the motors stop when the power goes
        if mount.tracking is not TrackingMode.OFF:
            await mount.set_tracking(TrackingMode.OFF)
        await mount.unpark()  # the hand control does not remember that it was parked
        for axis, home in zip(MountAxis, mount.geometry.home, strict=True):
            mount.set_axis_position(axis, home)  # the counters restart; the tube does not move
        mount.set_aligned(False)
        self.aligned = False
        self._goto_running = self._goto_sticky = False
        self._goto_sent_at = None
        self._axis_rates.clear()
        logger.info("power cycled: counters at their power-on values, not aligned")
        await self.power_on()

    def now(self) -> datetime:
        """The hand control's clock (UTC)."""
        return self.mount.now() + self.clock_offset

    async def answer(self, command: AnyCommand) -> AnyReply:
        """Carry out ``command`` on the mount and return the reply a real hand control sends.

        A command the mount refuses (below the horizon, parked, not supported) is still
        acknowledged with ``#`` and changes nothing, as the hand control does. A read of the
        position or state that the mount cannot give as current (the link down, the reading
        older than ``stale_after_s``, none yet) gets no reply (:class:`NoReply` is raised): a
        hand control that
        does not answer is what SynScan clients' timeouts and resynchronisation handle; a
        ``#`` where 18 bytes are due, or an old position, would be read as data.
        """
        try:
            return await synscan.dispatch(command, self)
        except SunAvoidanceError as error:  # shown at the default log level: it matters by day
            logger.warning("%s refused: %s", command.describe(), error)
            return synscan.Ack()
        except MountError as error:
            logger.info("%s refused: %s", command.describe(), error)
            return synscan.Ack()

    # --- the answer to each command (its synscan.CommandHandler method) --------------------------

    @_state_read
    async def get_ra_dec(self, command: synscan.GetRaDec) -> AnyReply:
        state = await self.mount.current_state()
        ra, dec = state.ra_j2000_hours, state.dec_j2000_deg
        if ra is None or dec is None:
            raise NoReadingError("the mount has not reported its position yet")
        return synscan.Position.from_ra_dec(ra, dec, command.precise)

    @_state_read
    async def get_az_alt(self, command: synscan.GetAzAlt) -> AnyReply:
        az, alt = self._reported_az_alt(await self.mount.current_state())
        return synscan.Position.from_az_alt(az, alt, command.precise)

    async def goto_ra_dec(self, command: synscan.GotoRaDec) -> AnyReply:
        await self._goto_ra_dec(command.ra_hours, command.dec_degrees)
        return synscan.Ack()

    async def goto_az_alt(self, command: synscan.GotoAzAlt) -> AnyReply:
        await self._goto_az_alt(command.az_degrees, command.alt_degrees)
        return synscan.Ack()

    async def sync_ra_dec(self, command: synscan.SyncRaDec) -> AnyReply:
        await self._sync(command.ra_hours, command.dec_degrees)
        return synscan.Ack()

    @_state_read
    async def get_tracking_mode(self, command: synscan.GetTrackingMode) -> AnyReply:
        state = await self.mount.current_state(position=False)
        return synscan.TrackingModeReply(_SYNSCAN_TRACKING[state.tracking])

    async def set_tracking_mode(self, command: synscan.SetTrackingMode) -> AnyReply:
        await self._set_tracking(command.mode)
        return synscan.Ack()

    async def fixed_rate_slew(self, command: synscan.FixedRateSlew) -> AnyReply:
        await self._fixed_rate(_AXES[command.axis], command.positive, command.rate)
        return synscan.Ack()

    async def variable_rate_slew(self, command: synscan.VariableRateSlew) -> AnyReply:
        rate_deg_s = command.arcsec_per_second / 3600.0
        await self._slew(_AXES[command.axis], rate_deg_s, on_top_of_tracking=False)
        return synscan.Ack()

    async def get_device_version(self, command: synscan.GetDeviceVersion) -> AnyReply:
        return synscan.DeviceVersion(*self.config.motor_version)

    async def slow_goto(self, command: synscan.SlowGoto) -> AnyReply:
        return await self._axis_position(command, _AXES[command.axis])

    async def set_axis_position(self, command: synscan.SetAxisPosition) -> AnyReply:
        return await self._axis_position(command, _AXES[command.axis])

    async def passthrough(self, command: synscan.Passthrough) -> AnyReply:
        return self._unanswerable_passthrough(command)

    async def get_location(self, command: synscan.GetLocation) -> AnyReply:
        site = self.mount.site
        return synscan.Location.from_degrees(site.latitude_deg, site.longitude_deg)

    async def set_location(self, command: synscan.SetLocation) -> AnyReply:
        location = command.location
        try:
            site = replace(
                self.mount.site,
                latitude_deg=location.latitude,
                longitude_deg=(location.longitude + 180.0) % 360.0 - 180.0,
            )
        except ValueError as error:  # W bytes come as sent: latitude 100° reaches here
            raise InvalidValueError(f"{command.describe()}: {error}") from None
        await self.mount.set_site(site)
        return synscan.Ack()

    async def get_time(self, command: synscan.GetTime) -> AnyReply:
        return self._local_time()

    async def set_time(self, command: synscan.SetTime) -> AnyReply:
        time = command.time
        try:
            local = time.to_datetime()
        except ValueError as error:  # H bytes come as sent: month 0, hour 76, UTC+45...
            raise InvalidValueError(f"{command.describe()}: {error}") from None
        self.clock_offset = local.astimezone(UTC) - self.mount.now()
        self.utc_offset_hours, self.dst = time.utc_offset_hours, time.dst
        return synscan.Ack()

    async def get_version(self, command: synscan.GetVersion) -> AnyReply:
        return self.config.firmware

    async def get_model(self, command: synscan.GetModel) -> AnyReply:
        return synscan.Model(self.config.model, self.config.quirks.model_swapped)

    async def echo(self, command: synscan.Echo) -> AnyReply:
        return synscan.EchoReply(command.value)

    async def is_aligned(self, command: synscan.IsAligned) -> AnyReply:
        return synscan.Aligned(self.aligned)

    @_state_read
    async def is_goto_in_progress(self, command: synscan.IsGotoInProgress) -> AnyReply:
        return synscan.GotoInProgress(await self._goto_in_progress())

    async def cancel_goto(self, command: synscan.CancelGoto) -> AnyReply:
        await self._cancel()
        return synscan.Ack()

    @_state_read
    async def get_pointing_state(self, command: synscan.GetPointingState) -> AnyReply:
        return synscan.PointingState(self._pointing_side(await self.mount.current_state()))

    # --- positions --------------------------------------------------------------------------------

    def _reported_az_alt(self, state: MountState) -> tuple[float, float]:
        az, alt = state.az_deg, state.alt_deg
        if az is None or alt is None:
            raise NoReadingError("the mount has not reported its position yet")
        if self.aligned:
            return az, alt
        az0, alt0 = self._power_on_az_alt
        return (az - az0) % 360.0, alt - alt0

    def _pointing_side(self, state: MountState) -> synscan.PointingSide:
        flipped = state.pier_side is PierSide.WEST
        if self.mount.site.latitude_deg < 0:
            flipped = not flipped
        return synscan.PointingSide.WEST if flipped else synscan.PointingSide.EAST

    # --- gotos and syncs --------------------------------------------------------------------------

    async def _goto_ra_dec(self, ra_hours: float, dec_deg: float) -> None:
        if not self.aligned:
            logger.info("RA/Dec goto ignored: the hand control is not aligned")
            return
        await self.mount.goto_equatorial(*_fold_over_pole(ra_hours, dec_deg, 12.0))
        self._goto_running, self._goto_sticky = True, False
        self._goto_sent_at = self.mount.now()
        state = self.mount.state
        # A mount that tracks after a goto by itself (the simulator, a Sky Tracker's GOTO)
        # reports slewing now; changing its tracking mid-goto could abort the goto.
        if state.tracking is TrackingMode.OFF and not state.slewing:
            await self.mount.set_tracking(self._sky_tracking_mode())

    async def _goto_az_alt(self, az_deg: float, alt_deg: float) -> None:
        if not self.aligned:
            az0, alt0 = self._power_on_az_alt
            az_deg, alt_deg = az_deg + az0, alt_deg + alt0
        az_deg, alt_deg = _fold_over_pole(az_deg, alt_deg, 180.0)
        capabilities = self.mount.capabilities
        if capabilities.can_goto and not capabilities.can_goto_altaz:
            # A mount that only goes to RA/Dec (a Sky Tracker): the same place on the sky now.
            ra_hours, dec_deg = observed_to_j2000(
                alt_deg, az_deg % 360.0, self.mount.now(), self.mount.site
            )
            await self.mount.goto_equatorial(ra_hours, dec_deg)
        else:
            await self.mount.goto_horizontal(alt_deg, az_deg)
        self._goto_running = True
        self._goto_sent_at = self.mount.now()
        self._goto_sticky = self.config.quirks.sticky_altaz_goto

    async def _sync(self, ra_hours: float, dec_deg: float) -> None:
        if not self.aligned:
            logger.info("sync ignored: the hand control is not aligned")
            return
        ra_hours, dec_deg = _fold_over_pole(ra_hours, dec_deg, 12.0)
        limit = self.config.quirks.sync_limit_deg
        state = await self.mount.current_state()
        if limit is not None and state.ra_j2000_hours is not None:
            distance = angular_separation_deg(
                state.ra_j2000_hours * 15.0, state.dec_j2000_deg or 0.0, ra_hours * 15.0, dec_deg
            )
            if distance > limit:
                logger.info("sync %.2f° away ignored (limit %.1f°)", distance, limit)
                return
        await self.mount.sync_equatorial(ra_hours, dec_deg)

    async def _goto_in_progress(self) -> bool:
        if not self._goto_running:
            return False
        if self._goto_sticky:
            return True
        state = await self.mount.current_state(position=False)
        if self._goto_sent_at is not None and state.read_at < self._goto_sent_at:
            return True  # a cached reading from before the goto says nothing about it
        self._goto_running = state.slewing
        return self._goto_running

    async def _cancel(self) -> None:
        self._goto_running = self._goto_sticky = False
        await self.mount.abort()
        if self.config.quirks.resume_after_cancel:
            for axis, rate in self._axis_rates.items():
                if rate:
                    await self.mount.move_axis(axis, rate)
        else:
            self._axis_rates.clear()

    # --- tracking and rates -----------------------------------------------------------------------

    def _sky_tracking_mode(self) -> TrackingMode:
        """How this mount follows the sky: alt-az tracking on an alt-az mount, else sidereal."""
        altaz = self.mount.capabilities.alignment_mode is AlignmentMode.ALT_AZ
        preferred = TrackingMode.ALT_AZ if altaz else TrackingMode.SIDEREAL
        modes = self.mount.capabilities.tracking_modes
        if preferred in modes:
            return preferred
        return next(m for m in (TrackingMode.SIDEREAL, TrackingMode.ALT_AZ) if m in modes)

    async def _set_tracking(self, mode: int) -> None:
        wanted = _MOUNT_TRACKING.get(mode)
        if wanted is None:
            logger.info("tracking mode %d is unknown: ignored", mode)
            return
        if wanted not in self.mount.capabilities.tracking_modes:
            wanted = self._sky_tracking_mode()
        await self.mount.set_tracking(wanted)

    async def _fixed_rate(self, axis: MountAxis, positive: bool, rate: int) -> None:
        speed = synscan_fixed_rate_deg_s(rate)
        await self._slew(
            axis, speed if positive else -speed, on_top_of_tracking=rate in GUIDING_RATES
        )

    async def _slew(self, axis: MountAxis, rate_deg_s: float, *, on_top_of_tracking: bool) -> None:
        """A keypad or variable-rate slew. The Mount adds ``move_axis`` to tracking; the spec
        has slews override equatorial tracking except fixed rates 1-2, so the others are sent
        net of the tracking rate (the axis then turns at exactly the commanded rate)."""
        if rate_deg_s and not on_top_of_tracking and self._tracking_equatorially():
            rate_deg_s -= self._tracking_rate_deg_s(axis)
        await self._move(axis, rate_deg_s)

    def _tracking_equatorially(self) -> bool:
        equatorial = self.mount.capabilities.alignment_mode is not AlignmentMode.ALT_AZ
        return equatorial and self.mount.state.tracking in _EQUATORIAL_TRACKING

    def _tracking_rate_deg_s(self, axis: MountAxis) -> float:
        """The axis rate of equatorial tracking: sidereal westwards on the polar axis."""
        if axis is MountAxis.SECONDARY:
            return 0.0
        return math.copysign(SIDEREAL_RATE_DEG_S, self.mount.site.latitude_deg)

    async def _move(self, axis: MountAxis, rate_deg_s: float) -> None:
        self._axis_rates[axis] = rate_deg_s
        self._goto_running = self._goto_sticky = False  # a rate slew takes over, as on the keypad
        await self.mount.move_axis(axis, rate_deg_s)

    async def _axis_position(
        self, command: synscan.SlowGoto | synscan.SetAxisPosition, axis: MountAxis
    ) -> AnyReply:
        if not (self.axis_passthrough and isinstance(self.mount, AxisPositioning)):
            return self._unanswerable_passthrough(command)
        position = (command.degrees + 180.0) % 360.0 - 180.0
        if axis is MountAxis.SECONDARY:
            # [-90, 270): a German mount's flipped secondary lies in (90, 270] (sim.geometry),
            # so a later slew from it turns the tube over the visible pole, never under it.
            position = (command.degrees + 90.0) % 360.0 - 90.0
        if isinstance(command, synscan.SlowGoto):
            self.mount.slew_axis_to(axis, position)
            self._goto_running, self._goto_sticky = True, False
        else:
            self.mount.set_axis_position(axis, position)
        return synscan.Ack()

    def _unanswerable_passthrough(self, command: synscan.PassthroughCommand) -> AnyReply:
        """No motor controller answers: the failed form (extra byte), or silence and ``#``."""
        length = command.reply_length if isinstance(command, synscan.Passthrough) else 0
        if self.config.quirks.failed_passthrough:
            return synscan.PassthroughFailed(bytes(length), _FAILED_PASSTHROUGH_EXTRA)
        return synscan.PassthroughReply(bytes(length))

    # --- time ---------------------------------------------------------------------------------

    def _local_time(self) -> synscan.DateTime:
        zone = timezone(timedelta(hours=self.utc_offset_hours + int(self.dst)))
        local = self.now().astimezone(zone).replace(microsecond=0)
        return synscan.DateTime.from_datetime(local, self.dst)


def _fold_over_pole(around: float, angle_deg: float, half_turn: float) -> tuple[float, float]:
    """(RA or Az, Dec or Alt) with the second read signed in [-180, 180) from the wire.

    Beyond ±90° the target is over the pole (or zenith): fold the second angle back and turn the
    first by ``half_turn`` (12 h or 180°), which is the same direction in the sky.
    """
    if abs(angle_deg) <= 90.0:
        return around, angle_deg
    return (around + half_turn) % (2 * half_turn), math.copysign(180.0 - abs(angle_deg), angle_deg)
