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
import time
from collections.abc import Callable, Iterator
from datetime import UTC, datetime, timedelta, timezone
from typing import Any, Self, TypeVar

from scopelink.astro import (
    PierSide,
    Site,
    angular_separation_deg,
)
from scopelink.drivers.common import LinkFactory, Pointing, Reconnection, link_factory
from scopelink.drivers.synscan.exchange import DEFAULT_TIMEOUT_S, SynScanWire
from scopelink.drivers.synscan.identify import (
    SIDEREAL_RATE_DEG_S,
    HandControlInfo,
    capabilities_for,
    mount_tracking,
    synscan_tracking,
)
from scopelink.drivers.synscan.settling import SettleDetector
from scopelink.drivers.synscan.stops import OwedStops
from scopelink.mount import (
    AlignmentMode,
    Capabilities,
    DeviceError,
    GuideDirection,
    Identity,
    Limits,
    Mount,
    MountAxis,
    MountError,
    MountState,
    NotConnectedError,
    NotSupportedError,
    ParkPosition,
    Priority,
    TrackingMode,
    utc_now,
)
from scopelink.protocol.synscan import (
    Ack,
    Aligned,
    AnyCommand,
    AnyReply,
    Axis,
    CancelGoto,
    DateTime,
    DeviceVersion,
    FixedRateSlew,
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
    PassthroughFailed,
    PointingSide,
    PointingState,
    Position,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SyncRaDec,
    VariableRateSlew,
    Version,
    VersionDialect,
)
from scopelink.protocol.synscan import TrackingMode as TrackingModeReply

__all__ = ["DEFAULT_GUIDE_RATE_DEG_S", "NotAlignedError", "SynScanMount"]

logger = logging.getLogger(__name__)

DEFAULT_GUIDE_RATE_DEG_S = 0.5 * SIDEREAL_RATE_DEG_S
"""Guide pulses move at half the sidereal rate, the usual autoguider setting."""

FULL_READ_EVERY = 10
"""Poll cycles of a mount at rest read ``L`` and ``e`` only; every tenth also reads ``t`` and
``p`` (a tracking change on the keypad shows within about a third of a second)."""

PARK_TOLERANCE_DEG = 1.0
"""The park goto must end this close to the park position for the mount to read parked (the
hand control's alt/az and ours differ by refraction, under 0.6° above the horizon)."""

SYNC_TOLERANCE_DEG = 0.05
"""A sync read back further than this from its target was not obeyed (the hand control ignores
syncs beyond ~7° silently). Generous against drift between the ``s`` and the ``e`` read back."""

STALE_TIME = timedelta(seconds=0.5)
"""A ``set_time`` exchange that took this long on the driver's clock (a retry after a fault) is
sent again with the time moved on by as much: the hand control's clock has whole seconds."""

_AXES = {MountAxis.PRIMARY: Axis.AZM_RA, MountAxis.SECONDARY: Axis.ALT_DEC}

R = TypeVar("R", bound=AnyReply)


class NotAlignedError(MountError):
    """The hand control is not aligned, so it ignores gotos and syncs: align it on the keypad."""


class SynScanMount(Mount):
    """A SynScan hand control on ``link``: a link spec (``/dev/ttyUSB0``, ``tcp://host:11880``,
    a pty path) or a factory that opens a :class:`~scopelink.links.Link`.

    ``timeout_s`` bounds every reply (the spec's 5 s). ``guide_rate_deg_s`` is the pulse-guide
    speed. ``utc_offset_hours`` is the time zone ``set_time`` gives the hand control (it keeps
    local time; whole hours only). ``altaz_settle_timeout_s`` bounds how long a position that
    stopped short of an Alt-Az goto target still counts as slewing on firmware whose ``L``
    sticks. ``clock`` is the PC's UTC clock, used to convert the J2000 position to alt/az.
    """

    def __init__(
        self,
        link: str | LinkFactory,
        *,
        site: Site,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        limits: Limits | None = None,
        clock: Callable[[], datetime] = utc_now,
        park_position: ParkPosition | None = None,
        guide_rate_deg_s: float = DEFAULT_GUIDE_RATE_DEG_S,
        utc_offset_hours: int = 0,
        altaz_settle_timeout_s: float = 300.0,
        name: str | None = None,
    ) -> None:
        super().__init__(site=site, limits=limits, clock=clock, park_position=park_position)
        factory, name = link_factory(link, name=name, unnamed="SynScan link")
        if not 0 < guide_rate_deg_s <= 10 * SIDEREAL_RATE_DEG_S:
            raise ValueError(f"guide rate {guide_rate_deg_s}°/s must lie in (0, 10x sidereal]")
        if not -12 <= utc_offset_hours <= 14:
            raise ValueError(f"UTC offset {utc_offset_hours} h must lie in [-12, 14]")
        self.wire = SynScanWire(factory, name=name, timeout_s=timeout_s)
        self.guide_rate_deg_s = guide_rate_deg_s
        self.utc_offset_hours = utc_offset_hours
        self.altaz_settle_timeout_s = altaz_settle_timeout_s
        self.info: HandControlInfo | None = None
        """What the hand control said at connect (firmware, model, motor controller versions)."""
        self._identity = Identity("synscan", "", link=name)
        self._capabilities = Capabilities(alignment_mode=AlignmentMode.GERMAN_POLAR)
        self._connected = False
        self._aligned = False
        self._parked = False
        self._park_target: ParkPosition | None = None
        """Where the last park goto went (AtPark once it has ended there)."""
        self._tracking = TrackingMode.OFF
        self._pier_side = PierSide.UNKNOWN
        self._goto_running = False
        self._settle: SettleDetector | None = None
        self._axis_rates: dict[MountAxis, float] = {}
        self._site_mismatch = ""
        """Set when the hand control's site (``w``) is not ours: alt/az computed here would then
        disagree with where it points. Cleared by ``set_site``."""
        self._cycles_since_full_read = 0
        self._epoch_at_full_read = -1
        self._motion_epoch = 0
        """Counts gotos and aborts: a poll that overlapped one must not judge it by its L."""
        self._pulses: dict[MountAxis, asyncio.Task[None]] = {}
        self._owed = OwedStops()
        """Stops a failed exchange left unconfirmed: sent before anything else once the wire
        works again (see ``stops.py``). Kept across disconnect: the next connect sends them."""
        self._paying = False
        self._failures_at_full_read = 0
        self._reidentify = False
        """The link was lost (closed, or the device silent past ``stale_after_s``): the next
        poll opens it anew and identifies the device again before reading."""
        self._identified_on = -1
        """``wire.statistics.reconnects`` when the device was last identified: a link the wire
        reopened by itself gets the device identified again too."""
        self._reconnection = Reconnection()

    @classmethod
    async def open(cls, link: str | LinkFactory, **options: Any) -> Self:
        """Construct the driver for ``link`` and connect it; ``options`` are the constructor's
        keywords. (The constructor alone touches nothing: ``BlockingMount(SynScanMount(...))``
        connects in its own thread.)"""
        mount = cls(link, **options)
        await mount.connect()
        return mount

    # --- who, what --------------------------------------------------------------------------------

    @property
    def capabilities(self) -> Capabilities:
        return self._capabilities

    @property
    def identity(self) -> Identity:
        return self._identity

    @property
    def timeout_s(self) -> float:
        return self.wire.timeout_s

    # --- connection -------------------------------------------------------------------------------

    @property
    def engaged(self) -> bool:
        return self._connected

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

    async def _identify(self, *, reopen: bool = True) -> None:
        """Echo on a freshly opened link (``reopen``; else the wire's current one), then ``V``,
        ``m``, motor versions, ``J``, ``w``."""
        if reopen:
            await self.wire.open()
        self._identified_on = self.wire.statistics.reconnects
        version = await self._ask(GetVersion(), Version)
        if version.dialect is VersionDialect.NEXSTAR_BINARY:
            raise DeviceError(
                f"{self.wire.name} answered V like a Celestron NexStar, not a SynScan hand control"
            )
        model = await self._ask(GetModel(), Model)
        # A stale "m" reply (code + '#') must never pass for a resynchronising echo.
        self.wire.avoid_echo.add(model.code)
        motors = (
            await self._motor_version(Axis.AZM_RA),
            await self._motor_version(Axis.ALT_DEC),
        )
        self.info = HandControlInfo(version, model, motors)
        if self.info.old_firmware:
            logger.warning(
                "%s: hand control firmware %s predates the protocol spec (3.38 / 4.38.06)",
                self.wire.name,
                self.info.identity(self.wire.name).firmware,
            )
        self._aligned = (await self._ask(IsAligned(), Aligned)).aligned
        self._site_mismatch = _site_mismatch(await self._ask(GetLocation(), Location), self.site)
        if self._site_mismatch:
            logger.warning("%s: %s", self.wire.name, self._site_mismatch)
        self._identity = self.info.identity(self.wire.name)
        self._capabilities = capabilities_for(self.info)

    async def _reconnect(self) -> None:
        """Open the lost link anew (or take the one the wire reopened by itself) and identify
        the device again: it may have been switched off and on (alignment, site) or be another
        one. Owed stops go out with the first exchange that works (see ``stops.py``)."""
        lost = self._reidentify
        if lost:
            await self.wire.close()
        try:
            await self._identify(reopen=lost)
        except BaseException:
            await self.wire.close()
            raise
        if not self._connected:  # disconnected meanwhile: let go of the new link
            await self.wire.close()
            raise NotConnectedError(f"{self.wire.name} was disconnected while reconnecting")
        self._reidentify = False
        logger.warning("%s: the hand control answers on a new link: identified", self.wire.name)

    def _needs_reidentifying(self) -> bool:
        return self._reidentify or self._identified_on != self.wire.statistics.reconnects

    def _line_bytes(self) -> tuple[int, int]:
        return self.wire.statistics.bytes_sent, self.wire.statistics.bytes_received

    def _standing_problems(self) -> tuple[str, ...]:
        # An unconfirmed stop stays named while polls fail (no motion is claimed meanwhile).
        return (self._owed.describe(),) if self._owed else ()

    def _judge_link(self) -> None:
        """After a failed poll: the link is lost when it is closed, or the device has been
        silent longer than ``stale_after_s`` (a noisy line still answers its resync echoes).
        A lost link reads as not connected and is reopened by the next poll."""
        silent_s = time.monotonic() - self.wire.last_answer_s
        if self.wire.is_open and silent_s <= self.stale_after_s:
            return
        self._reidentify = True
        if self.state.connected:
            logger.warning("%s: link lost (silent for %.1f s)", self.wire.name, silent_s)
            self._publish(dataclasses.replace(self.state, connected=False))

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

    async def _motor_version(self, axis: Axis) -> tuple[int, int] | None:
        reply = await self.wire.ask(GetDeviceVersion(axis))
        if isinstance(reply, DeviceVersion):
            return reply.major, reply.minor
        return None  # a failed passthrough: that motor controller did not answer

    # --- reading ----------------------------------------------------------------------------------

    async def refresh(self) -> MountState:
        """Poll ``L`` and ``e`` (J2000 RA/Dec); ``t`` and ``p`` (equatorial mounts) around motion
        and every tenth cycle; ``J`` while unaligned. Alt/az and of-date RA/Dec are computed on
        the PC (see ``docs/drivers-synscan.md``)."""
        return await self._read_state(Priority.POLL)

    async def _read_state(self, priority: Priority) -> MountState:
        if not self._connected:
            raise NotConnectedError(f"{self.wire.name} is not connected")
        try:
            await self._reconnection.run_if(self._needs_reidentifying, self._reconnect)
        except DeviceError as error:
            self._report_problem(f"reconnecting: {error}")
            self._judge_link()
            raise
        epoch = self._motion_epoch
        failures = self.wire.statistics.failures
        # 't' and 'p' change with motion (a goto enables tracking and may flip the tube) or on the
        # keypad: read them around motion and every few cycles, not in every one (see the docs).
        full = (
            priority is Priority.COMMAND
            or self._slewing
            or epoch != self._epoch_at_full_read
            or self._cycles_since_full_read + 1 >= FULL_READ_EVERY
            # A failed exchange may have been a command the hand control carried out late.
            or self.wire.statistics.failures != self._failures_at_full_read
        )
        tracking: TrackingModeReply | None = None
        try:
            # L before e: when L says the goto has ended, the position read next is its landing.
            goto = await self._ask(IsGotoInProgress(), GotoInProgress, priority)
            position = await self._ask(GetRaDec(), Position, priority)
            read_at = self.now()
            place = _pointing(position, read_at, self.site)
            if full:
                # The astrometry (about 1 ms of CPU) runs while the hand control answers 't'.
                tracking = await self._ask(
                    GetTrackingMode(), TrackingModeReply, priority, meanwhile=place.compute
                )
                if self._capabilities.can_report_pier_side:
                    side = await self._ask(GetPointingState(), PointingState, priority)
                    self._pier_side = self._pier_side_of(side)
            if not self._aligned:
                self._aligned = (await self._ask(IsAligned(), Aligned, priority)).aligned
        except DeviceError as error:
            if not self._stop_blind_motion(error):
                self._report_problem(str(error))
            self._judge_link()
            raise
        ra, dec = place.ra_j2000_hours, place.dec_j2000_deg
        alt, az, ra_of_date, dec_of_date = place.compute()
        problems: tuple[str, ...] = (self._site_mismatch,) if self._site_mismatch else ()
        if tracking is not None:
            self._cycles_since_full_read = 0
            self._epoch_at_full_read = epoch
            self._failures_at_full_read = failures
            mode = mount_tracking(tracking.mode)
            if mode is None:
                problems += (f"unknown tracking mode {tracking.mode} reported",)
            else:
                self._tracking = mode
        else:
            self._cycles_since_full_read += 1
        mode = self._tracking
        if self._motion_epoch == epoch:
            # A goto sent while this poll waited for the wire is not over whatever L said.
            self._goto_running = self._goto_still_running(goto.in_progress, alt, az)
        if self._parked and not self._slewing and not self._arrived_at_park(alt, az):
            problems += (
                "the park goto ended away from the park position: not parked (park again, "
                "unpark, or abort)",
            )
        state = MountState(
            read_at=read_at,
            connected=True,
            ra_j2000_hours=ra,
            dec_j2000_deg=dec,
            ra_of_date_hours=ra_of_date,
            dec_of_date_deg=dec_of_date,
            alt_deg=alt,
            az_deg=az,
            pier_side=self._pier_side,
            slewing=self._slewing,
            tracking=mode,
            parked=self._arrived_at_park(alt, az),
            aligned=self._aligned,
            pulse_guiding=bool(self._pulses),
            problems=problems,
            received_s=place.received_s,
        )
        self._publish(state)
        return state

    def _arrived_at_park(self, alt: float, az: float) -> bool:
        """Parked: the park goto has ended, within ``PARK_TOLERANCE_DEG`` of where it went."""
        target = self._park_target
        if not self._parked or self._slewing or target is None:
            return False
        off = angular_separation_deg(az, alt, target.az_deg, target.alt_deg)
        return bool(off <= PARK_TOLERANCE_DEG)

    def _stop_blind_motion(self, error: DeviceError) -> bool:
        """A poll failed (twice: the retry too) while an axis turns at a rate: nobody sees where
        it goes, so its stop is owed, sent when the link returns. Gotos carry on (their target
        was checked against the limits), as does tracking. True if a stop was owed."""
        moving = {axis for axis, rate in self._axis_rates.items() if rate} | set(self._pulses)
        if not moving:
            return False
        self._owe_stops(axes=moving, cause=f"the position cannot be read while it turns: {error}")
        return True

    @property
    def _slewing(self) -> bool:
        # An unconfirmed stop means the mount may still move: say so until it is confirmed.
        return self._goto_running or any(self._axis_rates.values()) or bool(self._owed)

    def _goto_still_running(self, in_progress: bool, alt: float, az: float) -> bool:
        if not in_progress:
            self._settle = None
            return False
        if self._settle is None:
            return True
        # An Alt-Az goto on firmware whose L may stick: trust the position once it stands still.
        loop_time = asyncio.get_running_loop().time()
        return not self._settle.update(alt, az, loop_time)

    def _pier_side_of(self, reply: PointingState) -> PierSide:
        # 'E' is the normal side in the north and the flipped one in the south ("W" vice versa).
        flipped = reply.side is PointingSide.WEST
        if self.site.latitude_deg < 0:
            flipped = not flipped
        return PierSide.WEST if flipped else PierSide.EAST

    # --- gotos and syncs --------------------------------------------------------------------------

    async def _require_aligned(self, what: str) -> None:
        if not self._aligned:
            self._aligned = (await self._ask(IsAligned(), Aligned)).aligned
        if not self._aligned:
            raise NotAlignedError(
                f"the hand control is not aligned, so it would ignore the {what}: align it on the "
                "keypad first (tracking and manual slews work without alignment)"
            )

    async def _goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        await self._require_aligned("goto")
        pulsing = await self._cancel_pulses()
        with self._stops_owed_on_failure(cancel_goto=True, axes=pulsing):
            await self._ask(GotoRaDec.from_hours_degrees(ra_j2000_hours, dec_j2000_deg), Ack)
        self._goto_started(None)

    async def _goto_horizontal(self, alt_deg: float, az_deg: float) -> None:
        await self._require_aligned("goto")
        pulsing = await self._cancel_pulses()
        with self._stops_owed_on_failure(cancel_goto=True, axes=pulsing):
            await self._ask(GotoAzAlt.from_degrees(az_deg, alt_deg), Ack)
        self._goto_started((alt_deg, az_deg))

    def _goto_started(self, altaz_target: tuple[float, float] | None) -> None:
        self._axis_rates.clear()  # a goto takes over from manual motion, as on the keypad
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
            raise DeviceError(
                f"sync ignored by the hand control (more than ~7° away?): it still reports a "
                f"position {error:.2f}° from the sync target"
            )

    # --- stopping ---------------------------------------------------------------------------------

    async def _abort(self) -> None:
        """At once: ``M`` and rate 0 on both axes, ahead of everything queued and, when the stream
        is out of step, written before any resynchronisation (see ``SynScanWire.stop_at_once``).
        Then confirmed: ``M``, rate 0 on both axes (firmware up to 3.36 resumes rate motion after
        ``M``), tracking re-enabled as it was, and ``L`` checked (``M`` again if a goto still
        runs). A stop not confirmed (an error, or the caller gave up waiting) stays owed: it is
        sent again before anything else."""
        await self._cancel_pulses()
        try:
            await self._stop_at_once([CancelGoto(), *(_rate_zero(axis) for axis in MountAxis)])
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
        self._settle = None
        self._publish(dataclasses.replace(self.state, slewing=False, pulse_guiding=False))

    async def _stop_at_once(self, commands: list[AnyCommand]) -> None:
        """The first, unconfirmed, part of a stop: see ``SynScanWire.stop_at_once``. A failure
        here is left to the confirming exchanges that follow (they recover, or raise)."""
        try:
            await self.wire.stop_at_once(commands)
        except DeviceError as error:
            logger.warning("%s: a stop could not be written at once: %s", self.wire.name, error)

    async def _send_rate_zero(self, axis: MountAxis) -> None:
        reply = await self._wire_ask(_rate_zero(axis))
        if isinstance(reply, PassthroughFailed):
            logger.warning("%s: stop of the %s axis not acknowledged", self.wire.name, axis.name)

    async def _resume_tracking(self) -> None:
        """Re-send the tracking mode: on the hand control a rate slew overrides tracking."""
        if self._tracking is not TrackingMode.OFF:
            await self._ask(SetTrackingMode(synscan_tracking(self._tracking)), Ack)

    async def _stop_axis(self, axis: MountAxis) -> None:
        await self._stop_at_once([_rate_zero(axis)])
        with self._stops_owed_on_failure(axes={axis}):
            async with self.wire.exclusive():
                await self._send_rate_zero(axis)
                self._axis_rates.pop(axis, None)
                await self._resume_tracking()

    @contextlib.contextmanager
    def _stops_owed_on_failure(
        self, *, cancel_goto: bool = False, axes: set[MountAxis] | None = None
    ) -> Iterator[None]:
        """If the exchanges inside fail, owe the stops that undo them (see ``stops.py``)."""
        try:
            yield
        except DeviceError as error:
            self._owe_stops(cancel_goto=cancel_goto, axes=axes or set(), cause=str(error))
            raise

    def _owe_stops(self, *, cancel_goto: bool = False, axes: set[MountAxis], cause: str) -> None:
        self._owed.owe(cancel_goto=cancel_goto, axes=axes, cause=cause)
        logger.warning("%s: %s", self.wire.name, self._owed.describe())
        problems = (self._owed.describe(),)
        self._publish(dataclasses.replace(self.state, slewing=True, problems=problems))

    async def _pay_owed_stops(self) -> None:
        """Send the owed stops, holding the wire, before the exchange that found them owed."""
        async with self.wire.exclusive():
            if not self._owed or self._paying:
                return
            self._paying = True
            try:
                if self._owed.cancel_goto:
                    await self._ask(CancelGoto(), Ack)
                    self._owed.cancel_goto = False
                    self._motion_epoch += 1
                    self._goto_running = False
                    self._settle = None
                for axis in sorted(self._owed.axes, key=lambda axis: axis.value):
                    await self._send_rate_zero(axis)
                    self._owed.axes.discard(axis)
                    self._axis_rates.pop(axis, None)
                await self._resume_tracking()
            finally:
                self._paying = False
            logger.warning("%s: the owed stops were sent (%s)", self.wire.name, self._owed.cause)
            self._owed.clear()

    # --- manual motion ----------------------------------------------------------------------------

    async def _move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        """A variable-rate slew (0.25"/s steps); 0 stops the axis and tracking resumes."""
        self._cancel_pulse(axis)
        if rate_deg_s == 0.0:
            await self._stop_axis(axis)
        else:
            command = VariableRateSlew.from_arcsec_per_second(_AXES[axis], rate_deg_s * 3600.0)
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
                await self._ask_passthrough(FixedRateSlew(_AXES[axis], positive, speed))
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
        self._cancel_pulse(axis)
        if duration_ms == 0:
            return
        rate = sign * self.guide_rate_deg_s
        if axis is MountAxis.PRIMARY and self._tracking is not TrackingMode.OFF:
            # A rate slew replaces tracking on that axis: carry the tracking rate along.
            rate += math.copysign(SIDEREAL_RATE_DEG_S, self.site.latitude_deg)
        command = VariableRateSlew.from_arcsec_per_second(_AXES[axis], rate * 3600.0)
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

    # --- tracking, park, site, time ------------------------------------------------------------

    async def _set_tracking(self, mode: TrackingMode) -> None:
        await self._ask(SetTrackingMode(synscan_tracking(mode)), Ack)
        self._tracking = mode
        self._publish(dataclasses.replace(self.state, tracking=mode))

    async def _park(self) -> None:
        """Tracking off, then an Alt-Az goto to :attr:`park_position`; parked until unpark."""
        park = self.park_position
        self._limits.check_altaz(park.alt_deg, park.az_deg, what="park position")
        await self._require_aligned("park goto")
        pulsing = await self._cancel_pulses()
        with self._stops_owed_on_failure(cancel_goto=True, axes=pulsing):
            async with self.wire.exclusive():
                await self._ask(SetTrackingMode(synscan_tracking(TrackingMode.OFF)), Ack)
                self._tracking = TrackingMode.OFF
                await self._ask(GotoAzAlt.from_degrees(park.az_deg, park.alt_deg), Ack)
        self._parked = True
        self._park_target = park
        self._goto_started((park.alt_deg, park.az_deg))
        self._publish(dataclasses.replace(self.state, parked=False, tracking=TrackingMode.OFF))

    async def _unpark(self) -> None:
        self._parked = False
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

    # --- exchanges ----------------------------------------------------------------------------

    async def _wire_ask(
        self,
        command: AnyCommand,
        priority: Priority = Priority.COMMAND,
        *,
        meanwhile: Callable[[], object] | None = None,
    ) -> AnyReply:
        """Every exchange of the driver: owed stops go first (see ``stops.py``)."""
        if self._owed and not self._paying:
            await self._pay_owed_stops()
        return await self.wire.ask(command, priority, meanwhile=meanwhile)

    async def _ask(
        self,
        command: AnyCommand,
        expected: type[R],
        priority: Priority = Priority.COMMAND,
        *,
        meanwhile: Callable[[], object] | None = None,
    ) -> R:
        reply = await self._wire_ask(command, priority, meanwhile=meanwhile)
        if not isinstance(reply, expected):
            raise DeviceError(
                f"{self.wire.name}: {command.describe()!r} answered {reply.describe()!r}"
            )
        return reply

    async def _ask_passthrough(self, command: AnyCommand) -> None:
        reply = await self._wire_ask(command)
        if isinstance(reply, PassthroughFailed):
            raise DeviceError(
                f"{command.describe()!r}: the motor controller did not answer the hand control "
                "(failed passthrough)"
            )


def _rate_zero(axis: MountAxis) -> FixedRateSlew:
    """Rate 0 on ``axis``: stops a fixed- or variable-rate slew (see the protocol notes)."""
    return FixedRateSlew(_AXES[axis], positive=True, rate=0)


SITE_TOLERANCE_DEG = 1.0 / 60.0
"""The hand control stores its site to the arcsecond; a difference above an arcminute is real."""


def _site_mismatch(theirs: Location, ours: Site) -> str:
    """Why the hand control's site disagrees with ours, or "" when they agree."""
    longitude_gap = abs((theirs.longitude - ours.longitude_deg + 180.0) % 360.0 - 180.0)
    if (
        abs(theirs.latitude - ours.latitude_deg) <= SITE_TOLERANCE_DEG
        and longitude_gap <= SITE_TOLERANCE_DEG
    ):
        return ""
    return (
        f"the hand control's site ({theirs.latitude:.4f}°, {theirs.longitude:.4f}°) is not the "
        f"configured one ({ours.latitude_deg:.4f}°, {ours.longitude_deg:.4f}°): call set_site "
        "to send ours, or configure the hand control's"
    )


def _pointing(position: Position, read_at: datetime, site: Site) -> Pointing:
    """The reading of one ``e`` reply (a Dec read beyond the pole is the same direction at
    RA + 12 h)."""
    ra = position.ra_hours
    if position.flipped:
        ra = (ra + 12.0) % 24.0
    return Pointing(ra, position.dec_degrees, read_at, site)


def _separation_deg(ra1_hours: float, dec1: float, ra2_hours: float, dec2: float) -> float:
    return float(angular_separation_deg(ra1_hours * 15.0, dec1, ra2_hours * 15.0, dec2))
