"""The Mount API over a Sky-Watcher SynScan hand control (serial protocol v3.3).

Usage::

    mount = await SynScanMount.open("/dev/ttyUSB0", site=Site(51.48, 0.0))  # and connect
    await mount.goto_object("M31")
    await mount.wait_for_slew(timeout_s=120)

Every exchange goes through :class:`~scopelink.drivers.synscan.exchange.SynScanWire` (one command in
flight, replies read by length, timeouts and resynchronisation). Decisions where the spec is
silent are in ``docs/drivers-synscan.md``.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import math
from datetime import UTC, datetime, timedelta, timezone
from typing import Any, Self

from scopelink.astro import SIDEREAL_RATE_DEG_S, PierSide, Site, angular_separation_deg
from scopelink.drivers.common import LinkFactory
from scopelink.drivers.synscan.altaz_rates import SynScanAltAzRates
from scopelink.drivers.synscan.base import AXES, rate_zero
from scopelink.drivers.synscan.identify import synscan_tracking
from scopelink.drivers.synscan.parking import SlowGotoRefusedError
from scopelink.drivers.synscan.settling import SettleDetector
from scopelink.mount import (
    AlignmentMode,
    DeviceError,
    GuideDirection,
    MountAxis,
    MountError,
    NotSupportedError,
    ParkPosition,
    Priority,
    TrackingMode,
)
from scopelink.mount.errors import SyncRefusedError
from scopelink.protocol.synscan import (
    Ack,
    Aligned,
    CancelGoto,
    DateTime,
    FixedRateSlew,
    GetLocation,
    GetTime,
    GotoAzAlt,
    GotoInProgress,
    GotoRaDec,
    IsAligned,
    IsGotoInProgress,
    Location,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SyncRaDec,
    VariableRateSlew,
)

__all__ = ["NotAlignedError", "SynScanMount"]

logger = logging.getLogger(__name__)

SYNC_TOLERANCE_DEG = 0.05
"""A sync read back further than this from its target was not obeyed (the hand control ignores
syncs beyond ~7° silently). Generous against drift between the ``s`` and the ``e`` read back."""

STALE_TIME = timedelta(seconds=0.5)
"""A ``set_time`` exchange that took this long on the driver's clock (a retry after a fault) is
sent again with the time moved on by as much: the hand control's clock has whole seconds."""


class NotAlignedError(MountError):
    """The hand control is not aligned, so it ignores gotos and syncs: align it on the keypad."""


def _separation_deg(ra1_hours: float, dec1: float, ra2_hours: float, dec2: float) -> float:
    return float(angular_separation_deg(ra1_hours * 15.0, dec1, ra2_hours * 15.0, dec2))


class SynScanMount(SynScanAltAzRates):
    """A SynScan hand control on ``link``: a link spec (``/dev/ttyUSB0``, ``tcp://host:11880``,
    a pty path) or a factory that opens a :class:`~scopelink.links.Link`.

    ``timeout_s`` bounds every reply (the spec's 5 s). ``guide_rate_deg_s`` is the pulse-guide
    speed. ``utc_offset_hours`` is the time zone ``set_time`` gives the hand control (it keeps
    local time; whole hours only). ``altaz_settle_timeout_s`` bounds how long a position that
    stopped short of an Alt-Az goto target still counts as slewing on firmware whose ``L``
    sticks. ``clock`` is the PC's UTC clock, used to convert the J2000 position to alt/az.
    """

    @classmethod
    async def open(cls, link: str | LinkFactory, **options: Any) -> Self:
        """Construct the driver for ``link`` and connect it; ``options`` are the constructor's
        keywords. (The constructor alone touches nothing: ``BlockingMount(SynScanMount(...))``
        connects in its own thread.)"""
        mount = cls(link, **options)
        await mount.connect()
        return mount

    async def connect(self) -> None:
        """Open the link, echo, identify (``V``, ``m``, motor versions, ``J``, ``w``) and read the
        state once; on any failure the link is closed again and the error raised. While
        connected with its link lost, reopens it now (as the poller does by itself)."""
        if self._connected and self._reidentify:
            await self._read_state(Priority.COMMAND)
            return
        try:
            await self._identify()
        except BaseException:
            await self.wire.close()
            raise
        assert self.info is not None
        self._connected = True
        self._parked = False
        self._goto_running = False
        self._settle = None
        self._axis_rates.clear()
        try:
            await self._read_state(Priority.COMMAND)
        except BaseException:
            self._connected = False
            await self.wire.close()
            raise

    async def disconnect(self) -> None:
        """Stop manual motion this driver started (nothing could stop it later), then close.

        Gotos and tracking carry on, as INDI leaves them: a mount tracking an exposure should not
        stop because the PC let go of the link. A stop that fails here stays owed (the state
        says the mount may move) and is sent first by the next :meth:`connect`.
        """
        self._reidentify = False
        if not self._connected:
            await self.wire.close()
            return
        try:
            with contextlib.suppress(MountError):
                await self._end_custom_rates()  # the PC loop cannot outlive the link (rates.py)
            moving = await self._cancel_pulses()  # a cut-short pulse leaves its axis moving
            moving |= {axis for axis, rate in self._axis_rates.items() if rate}
            for axis in sorted(moving, key=lambda axis: axis.value):
                with contextlib.suppress(MountError):
                    await self._stop_axis(axis)
        finally:
            self._connected = False
            self._axis_rates.clear()
            await self.wire.close()
            # A stop that failed stays owed (and the state says the mount may move): the next
            # connect sends it first.
            slewing = bool(self._owed)
            self._publish(dataclasses.replace(self.state, connected=False, slewing=slewing))

    async def _require_aligned(self, what: str) -> None:
        if not self._aligned:
            self._aligned = (await self._ask(IsAligned(), Aligned)).aligned
        if not self._aligned:
            raise NotAlignedError(
                f"the hand control is not aligned, so it would ignore the {what}: align it on the "
                "keypad first (tracking and manual slews work without alignment)"
            )

    async def _goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        if self.resumed:  # counters restored after a power cycle: by slow goto (parking.py)
            alt, az = self.observed_altaz(ra_j2000_hours, dec_j2000_deg)
            await self._slow_goto(alt, az, tracking=self._sky_tracking())
            self._follow(ra_j2000_hours, dec_j2000_deg)
            return
        await self._require_aligned("goto")
        pulsing = await self._cancel_pulses()
        with self._stops_owed_on_failure(cancel_goto=True, axes=pulsing):
            await self._ask(GotoRaDec.from_hours_degrees(ra_j2000_hours, dec_j2000_deg), Ack)
        self._goto_started(None)

    def _sky_tracking(self) -> TrackingMode:
        altaz = self._capabilities.alignment_mode is AlignmentMode.ALT_AZ
        return TrackingMode.ALT_AZ if altaz else TrackingMode.SIDEREAL

    async def _slow_goto(self, alt_deg: float, az_deg: float, *, tracking: TrackingMode) -> None:
        """A resumed goto: tracking set first (it starts where the axes land), then a slow goto
        per axis to the counters that point at ``alt_deg``/``az_deg``."""
        pulsing = await self._cancel_pulses()
        with self._stops_owed_on_failure(cancel_goto=True, axes=pulsing):
            async with self.wire.exclusive():
                await self._ask(SetTrackingMode(synscan_tracking(tracking)), Ack)
                self._tracking = tracking
                await self._slow_goto_axes(self.axes_for(alt_deg, az_deg))
        self._goto_started(None)
        self._publish(dataclasses.replace(self.state, tracking=tracking))

    async def _goto_horizontal(self, alt_deg: float, az_deg: float) -> None:
        if self.resumed:
            await self._slow_goto(alt_deg, az_deg, tracking=TrackingMode.OFF)
            return
        await self._require_aligned("goto")
        pulsing = await self._cancel_pulses()
        with self._stops_owed_on_failure(cancel_goto=True, axes=pulsing):
            await self._ask(GotoAzAlt.from_degrees(az_deg, alt_deg), Ack)
        self._goto_started((alt_deg, az_deg))

    def _goto_started(self, altaz_target: tuple[float, float] | None) -> None:
        self._axis_rates.clear()  # a goto takes over from manual motion, as on the keypad
        self._refine = None
        self._motion_epoch += 1
        self._goto_running = True
        self._settle = None
        if altaz_target is not None:
            self._settle = SettleDetector(
                *altaz_target,
                started_at_s=asyncio.get_running_loop().time(),
                timeout_s=self.altaz_settle_timeout_s,
            )
        self._publish(dataclasses.replace(self.state, slewing=True))

    async def _sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        await self._require_aligned("sync")
        await self._ask(SyncRaDec.from_hours_degrees(ra_j2000_hours, dec_j2000_deg), Ack)
        state = await self._read_state(Priority.COMMAND)
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        error = _separation_deg(
            state.ra_j2000_hours, state.dec_j2000_deg, ra_j2000_hours, dec_j2000_deg
        )
        if error > SYNC_TOLERANCE_DEG:
            raise SyncRefusedError(
                f"sync ignored by the hand control (more than ~7° away?): it still reports a "
                f"position {error:.2f}° from the sync target"
            )

    async def _abort(self) -> None:
        """At once: ``M`` and rate 0 on both axes, ahead of everything queued and, when the stream
        is out of step, written before any resynchronisation (see ``SynScanWire.stop_at_once``).
        Then confirmed: ``M``, rate 0 on both axes (firmware up to 3.36 resumes rate motion after
        ``M``), tracking re-enabled as it was, and ``L`` checked (``M`` again if a goto still
        runs). A stop not confirmed (an error, or the caller gave up waiting) stays owed: it is
        sent again before anything else."""
        await self._cancel_pulses()
        try:
            await self._stop_at_once([CancelGoto(), *(rate_zero(axis) for axis in MountAxis)])
            async with self.wire.exclusive():
                await self._ask(CancelGoto(), Ack)
                for axis in MountAxis:
                    await self._send_rate_zero(axis)
                self._axis_rates.clear()
                await self._resume_tracking()
                for attempt in range(2):
                    running = await self._ask(IsGotoInProgress(), GotoInProgress)
                    if not running.in_progress:
                        break
                    if attempt == 1:
                        raise DeviceError(
                            "abort: the hand control still reports a goto in progress"
                        )
                    await self._ask(CancelGoto(), Ack)
        except (DeviceError, asyncio.CancelledError) as error:
            cause = str(error) or "the abort was given up before the device confirmed it"
            self._owe_stops(cancel_goto=True, axes=set(MountAxis), cause=cause)
            raise
        self._motion_epoch += 1
        self._goto_running = False
        self._refine = None
        self._settle = None
        self._publish(dataclasses.replace(self.state, slewing=False, pulse_guiding=False))

    async def _stop_axis(self, axis: MountAxis) -> None:
        await self._stop_at_once([rate_zero(axis)])
        with self._stops_owed_on_failure(axes={axis}):
            async with self.wire.exclusive():
                await self._send_rate_zero(axis)
                self._axis_rates.pop(axis, None)
                await self._resume_tracking()

    async def _move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        """A variable-rate slew (0.25"/s steps); 0 stops the axis and tracking resumes."""
        self._cancel_pulse(axis)
        if rate_deg_s == 0.0:
            await self._stop_axis(axis)
        else:
            command = VariableRateSlew.from_arcsec_per_second(AXES[axis], rate_deg_s * 3600.0)
            with self._stops_owed_on_failure(axes={axis}):
                await self._ask_passthrough(command)
            self._axis_rates[axis] = rate_deg_s
            self._goto_running = False
            self._settle = None
        self._publish(dataclasses.replace(self.state, slewing=self._slewing))

    async def move_axis_fixed(self, axis: MountAxis, speed: int, *, positive: bool = True) -> None:
        """Slew one axis at hand-control speed ``speed`` (1-9, as the keypad; 0 stops).

        On an equatorial mount that is tracking, speeds 1 and 2 add to tracking (guiding speeds).
        """
        if not 0 <= speed <= 9:
            raise ValueError(f"fixed speed {speed} must lie in 0..9")
        if speed == 0:
            await self.move_axis(axis, 0.0)
            return
        self._require_unparked()
        multiple = (2, 8, 16, 32, 64, 128, 400, 600, 800)[speed - 1]
        rate = multiple * SIDEREAL_RATE_DEG_S if positive else -multiple * SIDEREAL_RATE_DEG_S

        async def start() -> None:
            self._cancel_pulse(axis)
            with self._stops_owed_on_failure(axes={axis}):
                await self._ask_passthrough(FixedRateSlew(AXES[axis], positive, speed))
            self._axis_rates[axis] = rate
            self._goto_running = False
            self._publish(dataclasses.replace(self.state, slewing=True))

        await self._guarded_rate_motion(axis, rate, start)

    async def _pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        """A variable-rate slew at the guide rate on one axis, stopped by a PC timer."""
        if not self._capabilities.can_pulse_guide:
            raise NotSupportedError(
                "guide pulses need an equatorial mount (north and east are no fixed axis "
                "directions on an alt-az mount)"
            )
        axis, sign = self._guide_axis(direction)
        guide_rate = self.guide_rates_deg_s[0 if axis is MountAxis.PRIMARY else 1]
        if self._loop_joining:  # custom rates: the pulse is added to the loop (rates.py)
            if duration_ms > 0:
                await self._pulse_into_loop(axis, sign * guide_rate, duration_ms)
            return
        self._cancel_pulse(axis)
        if duration_ms == 0:
            return
        rate = sign * guide_rate
        if axis is MountAxis.PRIMARY and self._tracking is not TrackingMode.OFF:
            # A rate slew replaces tracking on that axis: carry the tracking rate along.
            rate += math.copysign(SIDEREAL_RATE_DEG_S, self.site.latitude_deg)
        command = VariableRateSlew.from_arcsec_per_second(AXES[axis], rate * 3600.0)
        with self._stops_owed_on_failure(axes={axis}):
            await self._ask_passthrough(command)
        # Timed from write to write: the hand control's delay in obeying each command cancels.
        ends_at = self.wire.last_write_at + duration_ms / 1000.0
        self._pulses[axis] = asyncio.create_task(
            self._end_pulse(axis, ends_at), name=f"end guide pulse {axis.name}"
        )
        self._publish(dataclasses.replace(self.state, pulse_guiding=True))

    def _guide_axis(self, direction: GuideDirection) -> tuple[MountAxis, float]:
        """Axis and rate sign that move the tube towards ``direction`` on an equatorial mount."""
        hemisphere = 1.0 if self.site.latitude_deg >= 0 else -1.0
        if direction in (GuideDirection.EAST, GuideDirection.WEST):
            return (
                MountAxis.PRIMARY,
                hemisphere if direction is GuideDirection.WEST else -hemisphere,
            )
        # Past the meridian flip the Dec axis runs the other way.
        flipped = self._pier_side is PierSide.WEST
        sign = -hemisphere if flipped else hemisphere
        return MountAxis.SECONDARY, sign if direction is GuideDirection.NORTH else -sign

    async def _end_pulse(self, axis: MountAxis, ends_at: float) -> None:
        await asyncio.sleep(ends_at - asyncio.get_running_loop().time())
        try:
            with self._stops_owed_on_failure(axes={axis}):
                async with self.wire.exclusive():
                    await self._send_rate_zero(axis)
                    await self._resume_tracking()
        except MountError as error:
            logger.warning("%s: ending a guide pulse failed: %s", self.wire.name, error)
            if not self._owed:  # an owed stop already names the problem, and is sent later
                self._report_problem(f"ending a guide pulse failed: {error}")
        finally:
            if self._pulses.get(axis) is asyncio.current_task():
                del self._pulses[axis]
            if not self._pulses:
                self._publish(dataclasses.replace(self.state, pulse_guiding=False))

    def _cancel_pulse(self, axis: MountAxis) -> None:
        task = self._pulses.pop(axis, None)
        if task is not None:
            task.cancel()

    async def _cancel_pulses(self) -> set[MountAxis]:
        """Forget running pulses (the caller's next command takes the axes over); returns their
        axes, still moving at the guide rate."""
        pulses = dict(self._pulses)
        self._pulses.clear()
        for task in pulses.values():
            task.cancel()
        for task in pulses.values():
            with contextlib.suppress(asyncio.CancelledError):
                await task
        return set(pulses)

    async def _set_tracking(self, mode: TrackingMode) -> None:
        if mode is TrackingMode.SIDEREAL and self._sky_tracking() is TrackingMode.ALT_AZ:
            mode = TrackingMode.ALT_AZ  # an alt-az mount follows the stars by its alt-az mode
        await self._end_custom_rates()  # custom rates: a loop on the PC (rates.py)
        await self._ask(SetTrackingMode(synscan_tracking(mode)), Ack)
        self._tracking = mode
        self._publish(dataclasses.replace(self.state, tracking=mode))
        await self._start_custom_rates()

    async def _park(self) -> None:
        """Tracking off, then to :attr:`park_position`: by an Alt-Az goto, or by a slow goto
        per axis (given as axis positions, the default home of an equatorial mount, resumed:
        see ``docs/parking.md``); parked until unpark."""
        park = self.park_position
        self._limits.check_altaz(park.alt_deg, park.az_deg, what="park position")
        try:
            await self._park_at(park, self._slow_park_axes(park))
        except SlowGotoRefusedError as error:
            if park.axes_deg is not None or self.resumed:
                raise
            logger.warning("%s: %s: parking with an Alt-Az goto", self.wire.name, error)
            self._slow_goto_refused = True  # the default park goes by 'b' from now on
            await self._park_at(park, None)

    async def _park_at(self, park: ParkPosition, axes: tuple[float, float] | None) -> None:
        if not self.resumed:  # unaligned, counters say nothing of where the tube points
            if axes is not None:
                self._aligned = False  # ask 'J' anew: the hand control obeys slow gotos anyway
            await self._require_aligned("park goto")
        pulsing = await self._cancel_pulses()
        with self._stops_owed_on_failure(cancel_goto=True, axes=pulsing):
            async with self.wire.exclusive():
                await self._ask(SetTrackingMode(synscan_tracking(TrackingMode.OFF)), Ack)
                self._tracking = TrackingMode.OFF
                if axes is None:
                    await self._ask(GotoAzAlt.from_degrees(park.az_deg, park.alt_deg), Ack)
                else:
                    await self._slow_goto_axes(axes)
        self._parked = True
        self._park_target = park
        self._park_axes = axes
        self._goto_started((park.alt_deg, park.az_deg) if axes is None else None)
        self._publish(dataclasses.replace(self.state, parked=False, tracking=TrackingMode.OFF))

    async def _unpark(self) -> None:
        self._parked = False
        self._park_axes = None
        self._publish(dataclasses.replace(self.state, parked=False))

    async def _set_site(self, site: Site) -> None:
        if self._connected:
            await self._ask(
                SetLocation(Location.from_degrees(site.latitude_deg, site.longitude_deg)), Ack
            )
        self._site_mismatch = ""

    async def read_site(self) -> Site:
        """The site the hand control holds (``w``), with our elevation and weather."""
        self._require_connected()
        location = await self._ask(GetLocation(), Location)
        longitude = (location.longitude + 180.0) % 360.0 - 180.0
        return dataclasses.replace(
            self.site, latitude_deg=location.latitude, longitude_deg=longitude
        )

    async def read_time(self) -> datetime:
        """The hand control's clock (``h``), in UTC (its zone and DST flag applied)."""
        self._require_connected()
        reply = await self._ask(GetTime(), DateTime)
        return reply.to_datetime().astimezone(UTC)

    async def _set_time(self, utc: datetime) -> None:
        started = self.now()
        await self._ask(self._set_time_command(utc), Ack)
        moved_on = self.now() - started
        if moved_on >= STALE_TIME:
            # Re-sent after a fault: the hand control got a time that was old by then.
            await self._ask(self._set_time_command(utc + moved_on), Ack)

    def _set_time_command(self, utc: datetime) -> SetTime:
        zone = timezone(timedelta(hours=self.utc_offset_hours))
        local = utc.astimezone(zone).replace(microsecond=0)
        return SetTime(DateTime.from_datetime(local))
