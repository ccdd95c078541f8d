"""What every part of the Sky Tracker driver stands on: construction, who the device is, the
line, and what the box last said (status, position) published as the Mount's state.

The driver is one class per concern, each building on the one before: ``base`` (this),
``connection`` (open, identify, reconnect, calibration), ``polling`` (the state), ``guiding``
(guide speeds), ``rates`` (custom tracking rates), ``mount`` (the commands).
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import Callable
from datetime import datetime

from scopelink.astro import Site
from scopelink.astro.one_position import reading_of_j2000
from scopelink.drivers.common import LinkFactory, Pointing, Reconnection, link_factory
from scopelink.mount import (
    AlignmentMode,
    Capabilities,
    DeviceError,
    Identity,
    InvalidValueError,
    Limits,
    Mount,
    MountAxis,
    MountState,
    NotConnectedError,
    NotSupportedError,
    PierSide,
    TrackingMode,
    utc_now,
)
from scopelink.mount.scheduling import Priority, WireScheduler
from scopelink.protocol.skytracker import (
    Direction,
    GuideSpeedReply,
    PositionReply,
    ReadGuideSpeed,
    ReadPosition,
    ReadStatus,
    Reply,
    SetGuideSpeed,
    StatusReply,
    TrackerCommand,
    TrackerMode,
    TrackerStatus,
)

from .exchange import DEFAULT_TIMEOUT_S, BadReplyError, BusOptions, SkyTrackerLine
from .motion import MAX_SKYTRACKER_TRACKING_OFFSET_ARCSEC_S, UTILITY_ARROW_ARCSEC_S, AxisMotion

__all__ = ["SkyTrackerBase"]

logger = logging.getLogger(__name__)

BAUDRATE = 9600

STOP_BITS = 2
"""The Sky Tracker's PC port is unbuffered: two stop bits (or paced sends) keep bytes apart."""

TRACKING_MODES = (TrackingMode.ALT_AZ, TrackingMode.SIDEREAL)
"""Both mean TRACK mode: the Sky Commander's rates follow the sky on both alt-az axes."""

LOOP_TRACKING_MODES = (TrackingMode.LUNAR, TrackingMode.SOLAR, TrackingMode.KING)
"""Sidereal plus an RA offset, by the custom-rate loop (rates.py): it needs the Sky Commander's
positions."""

BOX_TRACKING = (TrackerMode.TRACK, TrackerMode.GUIDE)
"""The box's modes that track (a tuple: read on every publish, and a tuple's ``in`` compares by
identity first, where a set would call ``Enum.__hash__``, Python code)."""

NOTHING_PRESSED = Direction(0)
_GOTO = TrackerMode.GOTO
_NOT_TRACKING = TrackingMode.OFF
_PIER_SIDE_UNKNOWN = PierSide.UNKNOWN
"""Looked up once: each look-up of an enum member costs ~80 ns (Python 3.11); every publish
asks."""


def capabilities_for(*, commander: bool) -> Capabilities:
    """What a Sky Tracker can do, with or without a Sky Commander on its bus (GOTO, syncs and
    the custom tracking rates need its positions)."""
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
        tracking_modes=frozenset(
            {TrackingMode.OFF, *TRACKING_MODES, *(LOOP_TRACKING_MODES if commander else ())}
        ),
        max_tracking_offset_arcsec_s=MAX_SKYTRACKER_TRACKING_OFFSET_ARCSEC_S if commander else 0.0,
        can_set_site=True,
        can_set_time=False,
        can_report_pier_side=False,
    )


_WITH_COMMANDER = capabilities_for(commander=True)
_WITHOUT_COMMANDER = capabilities_for(commander=False)


def pointing_of(
    reply: object, read_at: datetime, site: Site, received_s: float | None = None
) -> Pointing:
    """The reading of one Sky Commander position reply (``received_s``: when it arrived,
    :func:`time.monotonic`; default now)."""
    assert type(reply) is PositionReply  # exact: isinstance of an ABC runs Python code
    return Pointing(reply.ra_hours, reply.dec_degrees, read_at, site, received_s)


class SkyTrackerBase(Mount):
    """The Sky Tracker driver's construction, identity and line (see :class:`SkyTrackerMount`)."""

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
        self._derived: tuple[Pointing | None, tuple[float, float, float, float]] = (
            None,
            (math.nan,) * 4,
        )
        """:attr:`_position` and its alt/az and RA/Dec of date (``astro.one_position``'s one
        pass), computed once per reading: every state published until the next keeps them."""
        self._guide_speeds = (120, 120)
        """The box's ``K`` speeds (azimuth, elevation) as last set or read."""
        self._pulse_speeds = (120, 120)
        self._held: dict[MountAxis, AxisMotion] = {}
        self._loop_presses: dict[MountAxis, AxisMotion] = {}
        """The custom-rate loop's arrows now (rates.py): tracking, not slewing."""
        self._loop_on = False
        """The custom-rate loop runs: the arrows it presses (even those a status read catches
        on their way to being released) are tracking, not a slew."""
        self._pulses: dict[MountAxis, tuple[Direction, asyncio.Task[None]]] = {}
        self._rest_mode: TrackerMode | None = None
        """The mode to return to when the last arrow is released."""
        self._buttons = asyncio.Lock()
        self._tracking_choice = TrackingMode.ALT_AZ
        self._problems: tuple[str, ...] = ()
        self._loop_problems: tuple[str, ...] = ()
        """The custom-rate loop's (rates.py): kept across polls, until the loop starts again."""
        self._goto_status_at = -math.inf
        self._engaged = False
        """connect() succeeded and disconnect() was not called since: a lost link is reopened."""
        self._link_lost = False
        """The box was silent past ``stale_after_s`` on an open line: reopen before polling."""
        self._status_at = (self.now(), time.monotonic())
        """When the last status byte arrived: (mount clock, :func:`time.monotonic`)."""
        self._reconnection = Reconnection()

    @property
    def capabilities(self) -> Capabilities:
        # Read on every publish (the pointing correction asks the alignment mode): one object
        # per value of the one thing it depends on, so it can never be stale.
        return _WITH_COMMANDER if self._commander_present is not False else _WITHOUT_COMMANDER

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

    @property
    def engaged(self) -> bool:
        return self._engaged

    def _line_bytes(self) -> tuple[int, int]:
        link = self._line.link if self._line is not None else None
        return (link.bytes_written, link.bytes_read) if link is not None else (0, 0)

    async def _read_agreed(
        self,
        line: SkyTrackerLine,
        command: TrackerCommand,
        priority: Priority = Priority.COMMAND,
        *,
        first: Reply | None = None,
        expected: Reply | None = None,
        known: Callable[[], Reply | None] | None = None,
    ) -> Reply:
        """The reply to ``command``, trusted: the status byte, the two ``k`` bytes and the ``s``
        floats have no redundancy (a garbled one still reads as some value), so a reply that is
        not ``expected`` (or with nothing expected) is read again until two readings in a row
        agree, at most three readings; then :class:`BadReplyError`.

        ``known`` gives the driver's own record of the value *now*, asked after each reading:
        the status the driver's own presses and releases left (each confirmed by an ``R`` in
        its turn), which may change between two readings of this check. A reading equal to it
        is trusted as ``expected`` is (docs/drivers-skytracker.md, "The status check")."""

        def trusted(reply: Reply) -> bool:
            return (expected is not None and reply == expected) or (
                known is not None and reply == known()
            )

        reply = first if first is not None else await line.ask(command, priority)
        assert reply is not None
        if trusted(reply):
            return reply
        for _ in range(2):
            again = await line.ask(command, priority)
            assert again is not None
            if again == reply or trusted(again):
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

    async def _read_position(
        self, line: SkyTrackerLine, priority: Priority, *, retry: bool
    ) -> Pointing:
        (reply,) = await line.commander(
            [ReadPosition()], priority, retry_delays_s=None if retry else ()
        )
        self._position = pointing_of(reply, self.now(), self.site)
        return self._position

    def _note_status(self, reply: object, received_s: float | None = None) -> None:
        """Record a status reply that arrived at ``received_s`` (:func:`time.monotonic`;
        default now)."""
        assert type(reply) is StatusReply  # exact: isinstance of an ABC runs Python code
        status = reply.status
        self._status = status
        self._mode = status.mode
        self._status_at = (self._clock(), time.monotonic() if received_s is None else received_s)

    def _publish_now(self) -> MountState:
        position = self._position
        status = self._status
        pulses = self._pulses
        # The arrows as plain ints: IntFlag arithmetic costs a microsecond per operation, and
        # this runs on every poll.
        pulsing = 0
        if pulses:
            for direction, _ in pulses.values():
                pulsing |= int(direction)
        if self._loop_on and not self._held:  # arrows pressed now are the loop's (or pulses)
            pulsing = ~0
        pressed = int(status.directions) if status is not None else 0
        line = self._line
        read_at, received_s = self._status_at
        if position is None:
            ra = dec = ra_of_date = dec_of_date = alt = az = position_received_s = None
        else:
            ra, dec = position.ra_j2000_hours, position.dec_j2000_deg
            derived = self._derived
            if derived[0] is not position:  # a new reading (or its site changed): once each
                where = reading_of_j2000(ra, dec, position.read_at, position.site)
                derived = self._derived = (position, where)
            alt, az, ra_of_date, dec_of_date = derived[1]
            position_received_s = position.received_s
        mode = self._mode
        # Positional, in MountState's field order (mypy checks each argument's type, and
        # tests/drivers/test_driver_skytracker_publish.py each field's value): a class called
        # with keywords builds a dict of them first (~0.5 µs a poll).
        state = MountState(
            read_at,
            line is not None and not line.link.closed and not self._link_lost,  # connected
            ra,
            dec,
            ra_of_date,
            dec_of_date,
            alt,
            az,
            _PIER_SIDE_UNKNOWN,
            mode is _GOTO or (pressed & ~pulsing) != 0,  # slewing
            self._tracking_choice if mode in BOX_TRACKING else _NOT_TRACKING,
            False,  # parked
            True,  # aligned
            len(pulses) != 0,  # pulse_guiding
            self._problems + self._loop_problems,
            received_s,
            position_received_s,
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
        replies = await line.ask_sequence([*commands, *confirm])
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

    async def _set_guide_speeds(self, speeds: tuple[int, int]) -> None:
        line = self._require_line()
        await line.ask(SetGuideSpeed(*speeds))
        reply = await self._read_agreed(line, ReadGuideSpeed(), expected=GuideSpeedReply(*speeds))
        assert isinstance(reply, GuideSpeedReply)
        self._guide_speeds = (reply.azimuth_arcsec_per_s, reply.elevation_arcsec_per_s)
        if self._guide_speeds != speeds:
            raise DeviceError(f"the Sky Tracker kept guide speed {reply} after 'K' {speeds}")

    def _cancel_pulses(self) -> None:
        for _, task in self._pulses.values():
            task.cancel()
        self._pulses.clear()
