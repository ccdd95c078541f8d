"""``SkyTrackerMount``: the Mount API over the PC <-> Sky Tracker (+ Sky Commander) line.

The Sky Tracker box moves the motors; the Sky Commander behind its bus knows where the scope
points (J2000, three decimals) and holds the current object. Position reads and object uploads
go through the bus (``Q`` ... ``q``); modes, arrows, status, guide speed and calibration are
Sky Tracker commands. Decisions where the spec is silent are in ``docs/drivers-skytracker.md``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from collections.abc import Callable
from dataclasses import replace
from datetime import datetime
from typing import Any, Self

from scopelink.astro import Site, angular_separation_deg
from scopelink.drivers.common import LinkFactory, Pointing, Reconnection, link_factory
from scopelink.links import Link, LinkError
from scopelink.mount import (
    AlignmentMode,
    Capabilities,
    DeviceError,
    GuideDirection,
    Identity,
    InvalidValueError,
    Limits,
    Mount,
    MountAxis,
    MountError,
    MountState,
    NotConnectedError,
    NotSupportedError,
    TrackingMode,
    utc_now,
)
from scopelink.mount.scheduling import Priority, WireScheduler
from scopelink.protocol.skytracker import (
    Acknowledge,
    CalibrationReply,
    Direction,
    GuideSpeedReply,
    LoadObject,
    PositionReply,
    PressDirection,
    ReadCalibration,
    ReadGuideSpeed,
    ReadPosition,
    ReadStatus,
    ReadVersion,
    Realign,
    ReleaseDirections,
    Reply,
    SelectMode,
    SetCalibration,
    SetGuideSpeed,
    StatusReply,
    TrackerCommand,
    TrackerMode,
    TrackerStatus,
    VersionReply,
)
from scopelink.protocol.skytracker.calfloat import encode_calfloat_pair

from .calibration import CalibrationFactors, CalibrationRuleError
from .exchange import (
    DEFAULT_TIMEOUT_S,
    BadReplyError,
    BusOptions,
    BusRefusedError,
    LineOutOfSyncError,
    ReplyTimeoutError,
    SkyTrackerLine,
)
from .motion import (
    UTILITY_ARROW_ARCSEC_S,
    AxisMotion,
    axis_motion,
    guide_button,
    plan_buttons,
)

__all__ = ["SkyTrackerMount", "SlewInProgressError"]

logger = logging.getLogger(__name__)

BAUDRATE = 9600
STOP_BITS = 2
"""The Sky Tracker's PC port is unbuffered: two stop bits (or paced sends) keep bytes apart."""
TRACKING_MODES = (TrackingMode.ALT_AZ, TrackingMode.SIDEREAL)
"""Both mean TRACK mode: the Sky Commander's rates follow the sky on both alt-az axes."""
_TRACKING = {TrackerMode.TRACK, TrackerMode.GUIDE}
GOTO_STATUS_POLL_S = 0.05
"""Status polls during a GOTO (by wait_for_goto, and the poller's refreshes) are this far apart."""
NOTHING_PRESSED = Direction(0)
SYNC_TOLERANCE_DEG = 0.05
"""After a sync the position read back must lie this close to the synced one (3-decimal
coordinates both ways, and the sky's drift during the read)."""


class SlewInProgressError(MountError):
    """A GOTO is running: the request would abort it (or needs the bus the GOTO keeps busy)."""


class SkyTrackerMount(Mount):
    """A Sky Tracker box (with its Sky Commander) on a link.

    ``link`` is a link spec as for :func:`scopelink.links.open_link` (``/dev/ttyUSB0``,
    ``tcp://HOST:PORT``, a pty path): serial ports are opened 9600 8N2, links without a UART
    get paced sends (11 bit-times per byte). Or a coroutine function returning an open link,
    used as it is (wrap it in :func:`scopelink.links.paced` yourself if it has no UART).
    ``guide_speed_arcsec_s`` sets the ``K`` speed used by pulse guiding (default: the box's).
    """

    poll_interval_s = 0.0
    """Background polls may run back to back (within the poll policy's line cap)."""

    def __init__(
        self,
        link: str | LinkFactory,
        *,
        site: Site,
        limits: Limits | None = None,
        clock: Callable[[], datetime] = utc_now,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        bus: BusOptions | None = None,
        guide_speed_arcsec_s: int | None = None,
        name: str | None = None,
    ) -> None:
        super().__init__(site=site, limits=limits, clock=clock)
        if guide_speed_arcsec_s is not None and not 1 <= guide_speed_arcsec_s <= 255:
            raise InvalidValueError(f"guide speed {guide_speed_arcsec_s} arcsec/s is not 1-255")
        if not timeout_s > 0:
            raise ValueError(f"timeout {timeout_s} s must be positive")
        self._open, self.spec = link_factory(
            link,
            name=name,
            unnamed="Sky Tracker link",
            baudrate=BAUDRATE,
            stopbits=STOP_BITS,
            pace=True,
        )
        self.timeout_s = timeout_s
        """Bounds every reply (the spec names none; see ``DEFAULT_TIMEOUT_S``)."""
        self.bus = bus or BusOptions()
        self.scheduler = WireScheduler()
        self._line: SkyTrackerLine | None = None
        self._wanted_guide_speed = guide_speed_arcsec_s
        self._version = ""
        self._commander_present: bool | None = None
        self._mode: TrackerMode | None = None
        self._status: TrackerStatus | None = None
        self._position: Pointing | None = None
        self._guide_speeds = (120, 120)
        """The box's ``K`` speeds (azimuth, elevation) as last set or read."""
        self._pulse_speeds = (120, 120)
        self._held: dict[MountAxis, AxisMotion] = {}
        self._pulses: dict[MountAxis, tuple[Direction, asyncio.Task[None]]] = {}
        self._rest_mode: TrackerMode | None = None
        """The mode to return to when the last arrow is released."""
        self._buttons = asyncio.Lock()
        self._tracking_choice = TrackingMode.ALT_AZ
        self._problems: tuple[str, ...] = ()
        self._goto_status_at = -math.inf
        self._engaged = False
        """connect() succeeded and disconnect() was not called since: a lost link is reopened."""
        self._link_lost = False
        """The box was silent past ``stale_after_s`` on an open line: reopen before polling."""
        self._status_at = (self.now(), time.monotonic())
        """When the last status byte arrived: (mount clock, :func:`time.monotonic`)."""
        self._reconnection = Reconnection()

    @classmethod
    async def open(
        cls,
        link: str | LinkFactory,
        *,
        calibration: CalibrationFactors | None = None,
        **options: Any,
    ) -> Self:
        """Construct the driver for ``link`` and connect it, writing ``calibration`` first if
        given; ``options`` are the constructor's keywords."""
        mount = cls(link, **options)
        await mount.connect(calibration=calibration)
        return mount

    # --- who and what ----------------------------------------------------------------------------

    @property
    def capabilities(self) -> Capabilities:
        commander = self._commander_present is not False
        return Capabilities(
            alignment_mode=AlignmentMode.ALT_AZ,
            can_goto=commander,
            can_goto_altaz=False,
            can_sync=commander,
            can_park=False,
            can_set_park=False,
            can_pulse_guide=True,
            can_move_axis=(True, True),
            max_axis_rate_deg_s=UTILITY_ARROW_ARCSEC_S / 3600.0,
            tracking_modes=frozenset({TrackingMode.OFF, *TRACKING_MODES}),
            can_set_site=True,
            can_set_time=False,
            can_report_pier_side=False,
        )

    @property
    def identity(self) -> Identity:
        model = "Sky Tracker"
        if self._commander_present:
            model += " + Sky Commander"
        return Identity("skytracker", model, firmware=self._version.strip(), link=self.spec)

    @property
    def commander_present(self) -> bool | None:
        """Whether a Sky Commander answered on the bus at connect (None: not known)."""
        return self._commander_present

    @property
    def tracker_mode(self) -> TrackerMode | None:
        """The box's mode as last read or set (None for a flag mix outside the spec's table)."""
        return self._mode

    @property
    def line(self) -> SkyTrackerLine:
        """The open line (for diagnostics: counters of resyncs and stray bytes)."""
        if self._line is None:
            raise NotConnectedError(f"the Sky Tracker on {self.spec} is not connected")
        return self._line

    # --- connection ------------------------------------------------------------------------------

    @property
    def engaged(self) -> bool:
        return self._engaged

    async def connect(self, *, calibration: CalibrationFactors | None = None) -> None:
        """Open the link and identify: ``V``, ``k``, ``R`` and a position read through the bus.

        With ``calibration``, ``S`` is sent first of all (the box takes it only as the first
        command after power-on): a refusal raises :class:`CalibrationRuleError`, not connected.
        A lost link (see :meth:`refresh`) is opened anew.
        """
        if self._engaged and calibration is None:  # connected, or lost: reopen it now
            await self._reconnection.run_if(self._needs_reconnect, self._reconnect)
            return
        if self._line is not None:
            if not self._line.link.closed and not self._link_lost:
                return
            await self._drop_line()  # the link went away under us: open it again
        await self._open_and_identify(calibration)
        self._engaged = True

    def _needs_reconnect(self) -> bool:
        return self._line is None or self._line.link.closed or self._link_lost

    def _line_bytes(self) -> tuple[int, int]:
        link = self._line.link if self._line is not None else None
        return (link.bytes_written, link.bytes_read) if link is not None else (0, 0)

    async def _drop_line(self) -> None:
        line, self._line = self._line, None
        if line is not None:
            with contextlib.suppress(LinkError):
                await line.link.close()

    async def _reconnect(self) -> None:
        """Open the lost link anew and identify the box again (it may have been switched off
        and on): arrows left pressed by the broken link are released (see connect)."""
        await self._drop_line()
        await self._open_and_identify(None)
        if not self._engaged:  # disconnected meanwhile: let go of the new line
            await self._drop_line()
            self._publish_now()
            raise NotConnectedError(f"the Sky Tracker on {self.spec} was disconnected meanwhile")
        logger.warning("the Sky Tracker on %s answers again: reconnected", self.spec)

    async def _open_and_identify(self, calibration: CalibrationFactors | None) -> None:
        link = await self._open_link()
        line = SkyTrackerLine(
            link, timeout_s=self.timeout_s, bus=self.bus, scheduler=self.scheduler
        )
        self._line = line
        self._held.clear()
        self._cancel_pulses()  # a new line presses no arrow: no pulse is under way on it
        self._rest_mode = None
        try:
            if calibration is not None:
                await self._write_calibration_first(line, calibration)
            self._version = await self._read_version(line)
            speeds = await self._read_agreed(line, ReadGuideSpeed())
            assert isinstance(speeds, GuideSpeedReply)
            self._guide_speeds = (speeds.azimuth_arcsec_per_s, speeds.elevation_arcsec_per_s)
            if self._wanted_guide_speed is not None:
                await self._set_guide_speeds((self._wanted_guide_speed,) * 2)
            self._pulse_speeds = self._guide_speeds
            self._note_status(await self._read_agreed(line, ReadStatus()))
            await self._release_orphaned_arrows(line)
            await self._detect_commander(line)
        except BaseException:
            self._line = None
            with contextlib.suppress(LinkError):
                await link.close()
            raise
        self._problems = ()
        self._link_lost = False
        self._publish_now()

    async def _release_orphaned_arrows(self, line: SkyTrackerLine) -> None:
        """``b`` when the box reports arrows pressed: a motion started over a link that broke
        (or by another program) that nobody on this connection can stop any more. The hand
        box's own arrows stay pressed while its user holds them."""
        assert self._status is not None
        if not self._status.directions:
            return
        logger.warning("arrows still pressed at connect (%s): releasing them", self._status)
        replies = await line.tracker_sequence([ReleaseDirections(), ReadStatus()])
        self._note_status(await self._read_agreed(line, ReadStatus(), first=replies[-1]))

    async def _read_agreed(
        self,
        line: SkyTrackerLine,
        command: TrackerCommand,
        priority: Priority = Priority.COMMAND,
        *,
        first: Reply | None = None,
        expected: Reply | None = None,
    ) -> Reply:
        """The reply to ``command``, trusted: the status byte, the two ``k`` bytes and the ``s``
        floats have no redundancy (a garbled one still reads as some value), so a reply that is
        not ``expected`` (or with nothing expected) is read again until two readings in a row
        agree, at most three readings; then :class:`BadReplyError`."""
        reply = first if first is not None else await line.tracker(command, priority)
        assert reply is not None
        if expected is not None and reply == expected:
            return reply
        for _ in range(2):
            again = await line.tracker(command, priority)
            assert again is not None
            if again == reply or (expected is not None and again == expected):
                if again != reply:
                    logger.info(
                        "garbled reply to %s: %s, then %s", command.describe(), reply, again
                    )
                return again
            reply = again
        raise BadReplyError(
            f"three different replies in a row to {command.describe()!r} on {line.link.name}: "
            "the line garbles replies, or they come late (check the cable, 9600 baud, the stop "
            "bits)"
        )

    @staticmethod
    async def _read_version(line: SkyTrackerLine) -> str:
        """``V``, asked twice if need be: a probe by another program (e.g. a SynScan driver's
        ``K`` echo) can leave the box inside a ``K`` or ``S`` frame that swallows the first
        ``V`` as payload; once that frame is complete (or dropped), ``V`` is answered."""
        try:
            reply = await line.tracker(ReadVersion())
        except (ReplyTimeoutError, BadReplyError) as error:
            logger.info("no version on the first try, asking again: %s", error)
            reply = await line.tracker(ReadVersion())
            # The first answer may only have been late, and so read as the second's: now that
            # the version is known, the resync's sync point reads past any answer still due.
            if not await line.resync():
                raise LineOutOfSyncError(
                    f"the Sky Tracker on {line.link.name} answered 'V' only late and then "
                    "not the sync point: is it busy or off?"
                ) from error
        assert isinstance(reply, VersionReply)
        return reply.text

    async def _open_link(self) -> Link:
        try:
            return await self._open()
        except LinkError as error:
            raise NotConnectedError(f"cannot open the Sky Tracker's link: {error}") from error

    async def _detect_commander(self, line: SkyTrackerLine) -> None:
        if self._mode is TrackerMode.GOTO:
            self._commander_present = None  # the bus is refused during a GOTO; it needs one
            return
        try:
            await self._read_position(line, Priority.COMMAND, retry=False)
        except ReplyTimeoutError as error:
            logger.warning("no Sky Commander on the bus: %s", error)
            self._commander_present = False
            return
        except BusRefusedError:
            self._commander_present = None
            return
        self._commander_present = True

    async def disconnect(self) -> None:
        """Release the arrows, abort a GOTO (``U``), close the link. Tracking keeps running."""
        self._engaged = False
        self._link_lost = False
        line = self._line
        if line is None:
            self._publish_now()
            return
        self._cancel_pulses()
        self._held.clear()
        try:
            if line.link.closed:
                raise NotConnectedError(f"the link {line.link.name} is closed")
            commands: list[TrackerCommand] = [ReleaseDirections()]
            if self._mode is TrackerMode.GOTO:
                commands.append(SelectMode(TrackerMode.UTILITY))
            # The status read makes sure the box has taken them before the link closes.
            await line.tracker_sequence([*commands, ReadStatus()])
        except (MountError, LinkError) as error:
            logger.info("could not stop motion before disconnecting: %s", error)
        finally:
            self._line = None
            with contextlib.suppress(LinkError):
                await line.link.close()
            self._publish(replace(self.state, connected=False))

    # --- calibration -----------------------------------------------------------------------------

    async def read_calibration(self) -> CalibrationFactors:
        """``s``: the motor calibration factors (always allowed)."""
        reply = await self._read_agreed(self._require_line(), ReadCalibration())
        assert isinstance(reply, CalibrationReply)
        return CalibrationFactors(reply.azimuth_factor, reply.elevation_factor)

    async def write_calibration(self, factors: CalibrationFactors) -> None:
        """``S``: store calibration factors in the box's EEPROM.

        The box takes ``S`` only as the first command after it is switched on, and once. Call
        this *instead of* :meth:`connect` (it connects, sending ``S`` first); once connected,
        the rule forbids it and :class:`CalibrationRuleError` is raised without sending anything.
        """
        if self._line is not None:
            raise CalibrationRuleError(
                f"the Sky Tracker takes 'S' only as the first command after it is switched on, "
                f"and only once; {self._line.statistics.commands_sent} commands have been sent on "
                "this connection. Disconnect, switch the Sky Tracker off and on, then call "
                "write_calibration() before connect()"
            )
        await self.connect(calibration=factors)

    async def _write_calibration_first(
        self, line: SkyTrackerLine, factors: CalibrationFactors
    ) -> None:
        if line.statistics.commands_sent:
            raise CalibrationRuleError("'S' must be the first command on the line")
        command = SetCalibration(factors.azimuth_factor, factors.elevation_factor)
        try:
            reply = await line.tracker(command)
        except (ReplyTimeoutError, BadReplyError) as error:
            # A refused 'S' gets no reply; so does one whose 'A' was lost. 's' tells them apart.
            logger.info("no good acknowledgement of 'S' (%s): reading the factors back", error)
            # The version is not known yet, so the resync had no sync point: a late 'A' could
            # be read as the first byte of the factors. A whole reply timeout of quiet first.
            try:
                await line.link.drain_input(self.timeout_s, 2 * self.timeout_s)
            except LinkError as link_error:
                raise NotConnectedError(f"the link {line.link.name} failed: {link_error}") from None
            stored = await self._read_agreed(line, ReadCalibration())
            assert isinstance(stored, CalibrationReply)
            wanted = encode_calfloat_pair(command.azimuth_factor, command.elevation_factor)
            if encode_calfloat_pair(stored.azimuth_factor, stored.elevation_factor) == wanted:
                logger.info("'S' was taken (its acknowledgement was lost)")
                return
            raise CalibrationRuleError(
                f"the Sky Tracker did not acknowledge 'S' nor take it ({error}; it still holds "
                f"factors {stored.azimuth_factor:g}, {stored.elevation_factor:g}): it takes "
                "calibration only as the first command after it is switched on, and once, so "
                "something talked to it since power-on (an earlier connection?), or 'S' was lost "
                "on the line: switch it off and on and try again"
            ) from None
        if not isinstance(reply, Acknowledge):
            raise DeviceError(f"unexpected reply to 'S': {reply}")

    # --- reading ---------------------------------------------------------------------------------

    async def refresh(self) -> MountState:
        """``R`` status; then, unless a GOTO keeps the bus, the position through the bus.

        A lost link (closed, or the box silent longer than ``stale_after_s``) reads as not
        connected; while engaged, the next refresh opens it anew and identifies the box again.
        """
        try:
            await self._reconnection.run_if(
                lambda: self._engaged and self._needs_reconnect(), self._reconnect
            )
        except (MountError, LinkError) as error:
            self._problems = (f"reconnecting: {error}",)
            self._link_lost = True
            self._publish_now()
            raise
        line = self._require_line()
        if self._mode is TrackerMode.GOTO:
            # During a GOTO a poll is one status byte (the bus is refused): back-to-back polls
            # would read it hundreds of times a second; GOTO_STATUS_POLL_S apart is plenty.
            since = time.monotonic() - self._goto_status_at
            if since < GOTO_STATUS_POLL_S:
                await asyncio.sleep(GOTO_STATUS_POLL_S - since)
        try:
            self._note_status(await self._read_status(line, Priority.POLL))
            self._goto_status_at = time.monotonic()
            if self._mode is not TrackerMode.GOTO and self._commander_present is not False:
                await self._poll_position(line)
        except (DeviceError, NotConnectedError) as error:
            self._problems = (str(error),)
            silent_s = time.monotonic() - line.last_answer_s
            if line.link.closed or silent_s > self.stale_after_s:
                # The link is gone (or the box silent): so is the connection, until reopened.
                if not self._link_lost:
                    logger.warning("the Sky Tracker on %s is lost: %s", self.spec, error)
                self._link_lost = True
            self._publish_now()
            raise
        self._problems = ()
        return self._publish_now()

    async def _poll_position(self, line: SkyTrackerLine) -> None:
        """The position for a poll: one immediate retry after a garbled or missing grant; a
        refusal means a GOTO began since the status read (the position is then kept)."""
        try:
            (reply,) = await line.commander([ReadPosition()], Priority.POLL, retry_delays_s=(0.0,))
        except BusRefusedError as error:
            if error.unanswered:
                raise
            self._mode = TrackerMode.GOTO
            return
        self._position = _pointing(reply, self.now(), self.site)

    async def read_position(self) -> tuple[float, float]:
        """J2000 (RA hours, Dec degrees) from the Sky Commander now, backing off on refusals."""
        position = await self._read_position(self._require_line(), Priority.COMMAND, retry=True)
        self._publish_now()
        return position.ra_j2000_hours, position.dec_j2000_deg

    async def _read_position(
        self, line: SkyTrackerLine, priority: Priority, *, retry: bool
    ) -> Pointing:
        (reply,) = await line.commander(
            [ReadPosition()], priority, retry_delays_s=None if retry else ()
        )
        self._position = _pointing(reply, self.now(), self.site)
        return self._position

    async def read_status(self) -> TrackerStatus:
        """``R``: the box's mode flags and pressed arrows now."""
        self._note_status(await self._read_status(self._require_line(), Priority.COMMAND))
        assert self._status is not None
        return self._status

    async def _read_status(self, line: SkyTrackerLine, priority: Priority) -> Reply:
        """``R``; a status other than the last one is read again (the byte has no redundancy)."""
        last = StatusReply(self._status) if self._status is not None else None
        return await self._read_agreed(line, ReadStatus(), priority, expected=last)

    async def wait_for_goto(self, timeout_s: float | None = None) -> MountState:
        """Poll ``R`` until the GOTO bit clears (TRACK follows), then refresh everything."""
        async with asyncio.timeout(timeout_s):
            while (await self.read_status()).mode is TrackerMode.GOTO:  # noqa: ASYNC110
                await asyncio.sleep(GOTO_STATUS_POLL_S)
        return await self.refresh()

    def _note_status(self, reply: object) -> None:
        assert isinstance(reply, StatusReply)
        self._status = reply.status
        self._mode = reply.status.mode
        self._status_at = (self.now(), time.monotonic())

    def _publish_now(self) -> MountState:
        position = self._position
        status = self._status
        pulsing = Direction(0)
        for direction, _ in self._pulses.values():
            pulsing |= direction
        pressed = status.directions if status is not None else Direction(0)
        line = self._line
        read_at, received_s = self._status_at
        state = MountState(
            read_at=read_at,
            connected=line is not None and not line.link.closed and not self._link_lost,
            ra_j2000_hours=position.ra_j2000_hours if position else None,
            dec_j2000_deg=position.dec_j2000_deg if position else None,
            ra_of_date_hours=position.ra_of_date_hours if position else None,
            dec_of_date_deg=position.dec_of_date_deg if position else None,
            alt_deg=position.alt_deg if position else None,
            az_deg=position.az_deg if position else None,
            slewing=self._mode is TrackerMode.GOTO or bool(pressed & ~pulsing),
            tracking=self._tracking_choice if self._mode in _TRACKING else TrackingMode.OFF,
            parked=False,
            aligned=True,
            pulse_guiding=bool(self._pulses),
            problems=self._problems,
            received_s=received_s,
            position_received_s=position.received_s if position else None,
        )
        self._publish(state)
        return state

    async def _send_confirmed(
        self,
        commands: list[TrackerCommand],
        *,
        mode: TrackerMode,
        pressed: Direction = NOTHING_PRESSED,
        speeds: tuple[int, int] | None = None,
    ) -> None:
        """Send commands without replies, then read back what they set (``R``, and ``k`` after
        ``K``) in the same turn: a command lost on the unbuffered line becomes a clear error."""
        line = self._require_line()
        confirm: list[TrackerCommand] = [ReadStatus()]
        if speeds is not None:
            confirm.append(ReadGuideSpeed())
        replies = await line.tracker_sequence([*commands, *confirm])
        status = replies[len(commands)]
        assert isinstance(status, StatusReply)
        if status.status.mode is not mode or pressed & ~status.status.directions:
            status = await self._read_agreed(line, ReadStatus(), first=status)
        self._note_status(status)
        assert self._status is not None
        if speeds is not None:
            reply = replies[-1]
            wanted = GuideSpeedReply(*speeds)
            reply = await self._read_agreed(line, ReadGuideSpeed(), first=reply, expected=wanted)
            assert isinstance(reply, GuideSpeedReply)
            self._guide_speeds = (reply.azimuth_arcsec_per_s, reply.elevation_arcsec_per_s)
        sent = " ".join(c.encode().decode("latin-1") for c in commands)
        if self._mode is not mode or pressed & ~self._status.directions:
            raise DeviceError(
                f"after {sent!r} the Sky Tracker reports {self._status}, not {mode.name} with "
                f"{pressed!r} pressed: was a command lost on the line?"
            )
        if speeds is not None and self._guide_speeds != speeds:
            raise DeviceError(
                f"after {sent!r} the Sky Tracker keeps guide speeds {self._guide_speeds}, "
                f"not {speeds}"
            )

    # --- goto and sync ---------------------------------------------------------------------------

    async def _goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """``U`` if a GOTO runs (re-target), ``Q`` ``L99 ...`` ``q``, then ``G``."""
        line = self._require_commander()
        await self._release_all_buttons()
        # UTILITY first: it ends a GOTO under way (the box ignores 'G' during one), and makes
        # the status after 'G' tell a lost 'G' (still UTILITY) from a GOTO that ended at once
        # (TRACK).
        await line.tracker(SelectMode(TrackerMode.UTILITY))
        self._mode = TrackerMode.UTILITY
        (reply,) = await line.commander([LoadObject.current(ra_j2000_hours, dec_j2000_deg)])
        if not isinstance(reply, Acknowledge):
            raise DeviceError(f"the Sky Commander did not acknowledge the object: {reply}")
        # 'G' has no reply: the status tells that the box took it (GOTO, or TRACK at once when
        # already on target). A lost 'G' (unbuffered port) is sent once more.
        for _ in range(2):
            replies = await line.tracker_sequence([SelectMode(TrackerMode.GOTO), ReadStatus()])
            self._note_status(replies[-1])
            if self._mode in (TrackerMode.GOTO, *_TRACKING):
                break
        if self._mode not in (TrackerMode.GOTO, *_TRACKING):
            raise DeviceError(
                f"the Sky Tracker did not start the GOTO (status {self._status}): was 'G' lost "
                "on the line?"
            )
        self._publish_now()

    def _check_sync_now(self, state: MountState) -> None:
        if self._mode is TrackerMode.GOTO:
            raise SlewInProgressError(
                "cannot sync during a GOTO: the Sky Tracker lends no bus while it slews; "
                "wait for the GOTO to end or abort it"
            )
        super()._check_sync_now(state)

    async def _sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """``Q`` ``L99 ...`` ``N`` ``q``: realign the Sky Commander on this position."""
        line = self._require_commander()
        self._check_sync_now(self.state)
        # 'N' has no reply: the position read back tells whether the realign took. Realigning
        # can be repeated, so a lost 'N' (the port is unbuffered) gets a second try.
        off_by = 0.0
        for _ in range(2):
            load, _ = await line.commander(
                [LoadObject.current(ra_j2000_hours, dec_j2000_deg), Realign()]
            )
            if not isinstance(load, Acknowledge):
                raise DeviceError(f"the Sky Commander did not acknowledge the object: {load}")
            after = await self._read_position(line, Priority.COMMAND, retry=True)
            self._publish_now()
            off_by = angular_separation_deg(
                after.ra_j2000_hours * 15.0,
                after.dec_j2000_deg,
                ra_j2000_hours * 15.0,
                dec_j2000_deg,
            )
            if off_by <= SYNC_TOLERANCE_DEG:
                return
            logger.info("realign did not take (%.3f° off): once more", off_by)
        raise DeviceError(
            f"the Sky Commander did not realign: it reads {off_by:.3f}° from the synced "
            "position after 'N', twice (is 'N' lost on the line?)"
        )

    async def _set_site(self, site: Site) -> None:
        """The box keeps no site: only the PC-side alt/az of the last reading changes."""
        position = self._position
        if position is not None:
            self._position = position.at_site(site)
            self._publish_now()

    def _require_line(self) -> SkyTrackerLine:
        if self._line is None:
            raise NotConnectedError(f"the Sky Tracker on {self.spec} is not connected")
        return self._line

    def _require_commander(self) -> SkyTrackerLine:
        line = self._require_line()
        if self._commander_present is False:
            raise NotSupportedError(
                "no Sky Commander answered on the Sky Tracker's bus at connect: goto and sync "
                "need it (check the cable between the two, then reconnect)"
            )
        return line

    # --- abort and tracking ----------------------------------------------------------------------

    async def _abort(self) -> None:
        """Release every arrow; ``U`` ends a GOTO (motors ramp down, UTILITY mode). Written at
        once first (``q``, ``b``, and ``U`` during a GOTO: see ``SkyTrackerLine.stop_at_once``),
        then confirmed in an ordinary turn by reading the status back."""
        line = self._require_line()
        self._cancel_pulses()
        self._held.clear()
        at_once: list[TrackerCommand] = [ReleaseDirections()]
        if self._mode is TrackerMode.GOTO:
            at_once.append(SelectMode(TrackerMode.UTILITY))
        try:
            await line.stop_at_once(at_once)
        except NotConnectedError as error:  # the confirming turn below says what is wrong
            logger.warning("a stop could not be written at once: %s", error)
        commands: list[TrackerCommand] = [ReleaseDirections()]
        mode = self._mode
        if mode is TrackerMode.GOTO:
            mode = TrackerMode.UTILITY
            commands.append(SelectMode(mode))
        elif self._rest_mode is not None and self._rest_mode is not mode:
            mode = self._rest_mode
            commands.append(SelectMode(mode))
        self._rest_mode = None
        await self._send_confirmed(commands, mode=mode or TrackerMode.UTILITY)
        # The abort is done; a failed read afterwards is only a stale state (named in problems).
        with contextlib.suppress(DeviceError):
            await self.refresh()

    async def _set_tracking(self, mode: TrackingMode) -> None:
        """TRACK (``T``) for sidereal/alt-az tracking; OFF is UTILITY (``U``), motors held."""
        self._require_line()
        if self._mode is TrackerMode.GOTO:
            raise SlewInProgressError(
                "a GOTO is running and ends in tracking by itself; changing tracking now would "
                "abort it (use abort() to stop it)"
            )
        if self._held or self._pulses:
            raise InvalidValueError("stop moving the axes before changing tracking")
        target = TrackerMode.UTILITY if mode is TrackingMode.OFF else TrackerMode.TRACK
        if mode is not TrackingMode.OFF:
            self._tracking_choice = mode
        await self._send_confirmed([SelectMode(target)], mode=target)
        self._publish_now()

    async def standby(self) -> None:
        """``B``: cut the motor drive to save battery (a GOTO is aborted first with ``U``)."""
        self._require_line()
        self._cancel_pulses()
        self._held.clear()
        commands: list[TrackerCommand] = [ReleaseDirections()]
        if self._mode is TrackerMode.GOTO:
            commands.append(SelectMode(TrackerMode.UTILITY))
        commands.append(SelectMode(TrackerMode.STANDBY))
        self._rest_mode = None
        await self._send_confirmed(commands, mode=TrackerMode.STANDBY)
        self._publish_now()

    async def set_guide_speed(self, azimuth_arcsec_s: int, elevation_arcsec_s: int) -> None:
        """``K`` (confirmed with ``k``): the guide speed of pulses and GUIDE-mode arrows."""
        for value in (azimuth_arcsec_s, elevation_arcsec_s):
            if not 1 <= value <= 255:
                raise InvalidValueError(f"guide speed {value} arcsec/s is not 1-255")
        self._require_line()
        self._pulse_speeds = (azimuth_arcsec_s, elevation_arcsec_s)
        async with self._buttons:
            await self._set_guide_speeds(self._pulse_speeds)

    async def _set_guide_speeds(self, speeds: tuple[int, int]) -> None:
        line = self._require_line()
        await line.tracker(SetGuideSpeed(*speeds))
        reply = await self._read_agreed(line, ReadGuideSpeed(), expected=GuideSpeedReply(*speeds))
        assert isinstance(reply, GuideSpeedReply)
        self._guide_speeds = (reply.azimuth_arcsec_per_s, reply.elevation_arcsec_per_s)
        if self._guide_speeds != speeds:
            raise DeviceError(f"the Sky Tracker kept guide speed {reply} after 'K' {speeds}")

    # --- arrows: move_axis and pulse_guide ----------------------------------------------------

    async def _move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        """Press the arrow of the nearest supported rate (see motion.py); 0 releases it."""
        self._refuse_during_goto("moving an axis")
        motion = axis_motion(axis, rate_deg_s)
        if motion is not None:
            if axis in self._pulses:
                raise InvalidValueError(f"the {axis.name.lower()} axis is pulse guiding")
            other = self._held.get(_other(axis))
            if other is not None and other.mode is not motion.mode:
                raise InvalidValueError(
                    f"the box moves both axes in one mode: the other axis moves in "
                    f"{other.mode.name}, this rate needs {motion.mode.name}; stop it first"
                )
            if self._pulses and motion.mode is not TrackerMode.GUIDE:
                raise InvalidValueError("a guide pulse is running: wait for it to end")
            self._held[axis] = motion
        else:
            self._held.pop(axis, None)
        await self._apply_buttons()

    async def _pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        """GUIDE mode (``D``) at the ``K`` speed, press the arrow, release after the duration.

        Returns at once; :attr:`MountState.pulse_guiding` is true until the pulse ends.
        """
        self._refuse_during_goto("pulse guiding")
        if self._mode not in _TRACKING:
            raise NotSupportedError(
                "the Sky Tracker guides only while tracking (its arrows slew at 4°/s in UTILITY "
                "mode): start tracking first"
            )
        axis, button = guide_button(direction)
        held = self._held.get(axis)
        if held is not None:
            raise InvalidValueError(f"the {axis.name.lower()} axis is moving: stop it first")
        if any(m.mode is not TrackerMode.GUIDE for m in self._held.values()):
            raise InvalidValueError("an axis moves at a TRACK or UTILITY rate: stop it first")
        if duration_ms == 0:
            return
        previous = self._pulses.pop(axis, None)
        if previous is not None:
            previous[1].cancel()
        task = asyncio.create_task(self._end_pulse(axis, duration_ms / 1000.0))
        self._pulses[axis] = (button, task)
        try:
            await self._apply_buttons()
        except BaseException:
            task.cancel()
            self._pulses.pop(axis, None)
            raise

    async def _end_pulse(self, axis: MountAxis, duration_s: float) -> None:
        await asyncio.sleep(duration_s)
        entry = self._pulses.get(axis)
        if entry is None or entry[1] is not asyncio.current_task():
            return
        del self._pulses[axis]
        try:
            await self._apply_buttons()
        except (MountError, LinkError) as error:
            logger.warning("could not end a guide pulse: %s", error)
            self._problems = (f"could not end a guide pulse: {error}",)
            self._publish_now()

    def _cancel_pulses(self) -> None:
        for _, task in self._pulses.values():
            task.cancel()
        self._pulses.clear()

    def _refuse_during_goto(self, what: str) -> None:
        if self._mode is TrackerMode.GOTO:
            raise SlewInProgressError(
                f"a GOTO is running: {what} would abort it (the box ignores arrows during a "
                "GOTO); wait for it to end or abort() it first"
            )

    async def _release_all_buttons(self) -> None:
        self._cancel_pulses()
        if self._held:
            self._held.clear()
            await self._apply_buttons()

    async def _apply_buttons(self) -> None:
        """Send the mode, ``K`` and arrows that the held motions and pulses call for, in one turn.

        ``b`` releases every arrow, so the arrows still wanted are pressed again after it.
        """
        async with self._buttons:
            self._require_line()
            plan = plan_buttons(
                self._held,
                {axis: button for axis, (button, _) in self._pulses.items()},
                pulse_speeds_arcsec_s=self._pulse_speeds,
                mode=self._mode,
                rest_mode=self._rest_mode,
            )
            self._rest_mode = plan.rest_mode
            commands: list[TrackerCommand] = []
            change_speeds = plan.guide_speeds_arcsec_s != self._guide_speeds
            if change_speeds:
                commands.append(SetGuideSpeed(*plan.guide_speeds_arcsec_s))
            if plan.mode is not self._mode:
                commands.append(SelectMode(plan.mode))
            commands.append(ReleaseDirections())
            commands += [PressDirection(direction) for direction in plan.pressed]
            await self._send_confirmed(
                commands,
                mode=plan.mode,
                pressed=plan.all_pressed,
                speeds=plan.guide_speeds_arcsec_s if change_speeds else None,
            )
            self._publish_now()


def _other(axis: MountAxis) -> MountAxis:
    return MountAxis.SECONDARY if axis is MountAxis.PRIMARY else MountAxis.PRIMARY


def _pointing(reply: object, read_at: datetime, site: Site) -> Pointing:
    """The reading of one Sky Commander position reply."""
    assert isinstance(reply, PositionReply)
    return Pointing(reply.ra_hours, reply.dec_degrees, read_at, site)
