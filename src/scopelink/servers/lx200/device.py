"""An LX200 handset in front of a Mount: each command as calls on the mount and one reply.

Reads answer from :attr:`Mount.state` (kept fresh by the server's ``mount.watching()``), never
waiting on the wire. A position or state the mount does not have (no reading yet, the link down,
the reading older than ``stale_after_s``) gets no reply at all: LX200 has no error reply to a
``:GR#``, and a handset that does not answer is what a client's timeout handles; a made-up or old
value would be read as the truth.

Coordinates on the wire are of date (JNow, the apparent place: what LX200
handsets and INDI use); the mount API speaks J2000, so targets are converted at the mount's time.
Motions go through the mount's public methods, so nothing below the horizon is ever commanded.

The target, the precision and the motion rate belong to one connection (a :class:`LX200Session`);
the UTC offset, like the site and time, belongs to the handset and is shared.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Awaitable, Callable
from datetime import UTC, date, datetime, time, timedelta

from scopelink.astro import PierSide, apparent_to_j2000, lst_hours
from scopelink.mount import (
    AlignmentMode,
    GuideDirection,
    LimitError,
    Mount,
    MountAxis,
    MountError,
    MountState,
    NotSupportedError,
    SunAvoidanceError,
    TrackingMode,
)
from scopelink.protocol.lx200 import (
    DATE_SET_REPLY,
    Ack,
    AnyCommand,
    Direction,
    Get,
    GotoTarget,
    Halt,
    MalformedCommand,
    Move,
    PulseGuide,
    Query,
    ReplyKind,
    SetLatitude,
    SetLocalDate,
    SetLocalTime,
    SetLongitude,
    SetRate,
    SetTargetDec,
    SetTargetRA,
    SetUtcOffset,
    SlewRate,
    SlewRefusal,
    SyncTarget,
    TogglePrecision,
    boolean_reply,
    format_altitude,
    format_azimuth,
    format_dec,
    format_ra,
    reply_kind,
    slew_reply,
    text_reply,
)
from scopelink.protocol.lx200.angles import DEGREE_SIGN, format_signed_degrees_minutes
from scopelink.servers.lx200.config import LX200Config, SyncReply

__all__ = ["LX200Handset", "LX200Session"]

logger = logging.getLogger(__name__)

_ALIGNMENT_LETTER = {
    AlignmentMode.ALT_AZ: "A",
    AlignmentMode.POLAR: "P",
    AlignmentMode.GERMAN_POLAR: "G",
}
_TRACKING_HZ = {
    TrackingMode.OFF: "00.0",
    TrackingMode.SIDEREAL: "60.1",
    TrackingMode.ALT_AZ: "60.1",
    TrackingMode.PEC: "60.1",
    TrackingMode.SOLAR: "60.0",
    TrackingMode.LUNAR: "57.9",
    TrackingMode.KING: "60.1",  # 60.08: King's rate is 0.03 % under sidereal
}
"""``:GT#``: Meade's tracking "frequency", 60.1 Hz standing for the sidereal rate."""
_GUIDE = {
    Direction.NORTH: GuideDirection.NORTH,
    Direction.SOUTH: GuideDirection.SOUTH,
    Direction.EAST: GuideDirection.EAST,
    Direction.WEST: GuideDirection.WEST,
}
MEADE_SYNC_TEXT = "Coordinates     matched.        "
READ_ONLY_TEXT = "Read-only server"
_CHANGES_THE_MOUNT = (
    GotoTarget,
    SyncTarget,
    Halt,
    Move,
    PulseGuide,
    SetLatitude,
    SetLongitude,
    SetUtcOffset,
    SetLocalTime,
    SetLocalDate,
)
"""Refused on a read-only server. Targets, rate and precision belong to the connection."""
_POSITION_QUERIES: dict[
    Query, tuple[Callable[[MountState], float | None], Callable[[float, bool, str], str]]
] = {
    Query.RA: (
        lambda state: state.ra_of_date_hours,
        lambda value, precise, _: format_ra(value, high_precision=precise),
    ),
    Query.DEC: (
        lambda state: state.dec_of_date_deg,
        lambda value, precise, sign: format_dec(value, high_precision=precise, degree_sign=sign),
    ),
    Query.ALTITUDE: (
        lambda state: state.alt_deg,
        lambda value, precise, sign: format_altitude(
            value, high_precision=precise, degree_sign=sign
        ),
    ),
    Query.AZIMUTH: (
        lambda state: state.az_deg,
        lambda value, precise, sign: format_azimuth(
            value, high_precision=precise, degree_sign=sign
        ),
    ),
}
"""Reads of the mount's position: not answered without a current reading of it."""
_STATE_QUERIES = frozenset({Query.STATUS, Query.DISTANCE_BARS, Query.TRACKING_RATE})
"""Reads of its state flags (tracking, slewing): not answered without a current state."""


class LX200Handset:
    """The state shared by every connection: the mount, the configuration and the UTC offset."""

    def __init__(self, mount: Mount, config: LX200Config | None = None) -> None:
        self.mount = mount
        self.config = config or LX200Config()
        self.utc_offset_hours = self.config.utc_offset_hours
        """Meade's sign: hours to add to local time to get UTC."""
        self.read_only = False
        """Refuse every command that would change the mount, the site, the time or the offset."""

    def session(self) -> LX200Session:
        return LX200Session(self)

    def local_now(self) -> datetime:
        """The mount's clock as local time (naive), by the handset's UTC offset."""
        utc = self.mount.now().astimezone(UTC)
        return (utc - timedelta(hours=self.utc_offset_hours)).replace(tzinfo=None)

    def utc_of_local(self, local: datetime) -> datetime:
        return (local + timedelta(hours=self.utc_offset_hours)).replace(tzinfo=UTC)


class LX200Session:
    """One client's conversation: answers each command with the bytes the handset sends back."""

    def __init__(self, handset: LX200Handset) -> None:
        self.handset = handset
        self.high_precision = handset.config.high_precision
        self.rate = SlewRate.SLEW
        self.target_ra_hours: float | None = None
        self.target_dec_deg: float | None = None
        self.degree_sign = DEGREE_SIGN
        """The degree sign in this connection's replies: the one it last wrote itself in a
        ``:Sd``/``:St``/``:Sg`` (0xDF or ``*``), Meade's 0xDF before that."""

    @property
    def mount(self) -> Mount:
        return self.handset.mount

    def _follow_the_client(self, command: AnyCommand) -> None:
        """Answer in the form the client writes: its degree sign (``:Sd``/``:St``/``:Sg``) and
        its precision (``:Sr``/``:Sd`` with or without seconds)."""
        if isinstance(command, SetTargetDec | SetLatitude | SetLongitude) and command.degree_sign:
            self.degree_sign = command.degree_sign
        if isinstance(command, SetTargetRA | SetTargetDec) and command.high_precision is not None:
            self.high_precision = command.high_precision

    async def answer(self, command: AnyCommand | MalformedCommand) -> bytes:
        """Carry out ``command`` and return its reply (``b""`` when it has none)."""
        if isinstance(command, MalformedCommand):
            logger.info("%s", command.describe())
            return boolean_reply(False) if reply_kind(command) is ReplyKind.CHAR else b""
        self._follow_the_client(command)
        if self.handset.read_only and isinstance(command, _CHANGES_THE_MOUNT):
            return self._refuse_read_only(command)
        match command:
            case Ack():
                mode = self.mount.capabilities.alignment_mode
                return _ALIGNMENT_LETTER[mode].encode("ascii")
            case Get(what):
                text = self._read(what)
                return b"" if text is None else text_reply(text)
            case TogglePrecision():
                self.high_precision = not self.high_precision
                return b""
            case SetTargetRA(ra, _):
                self.target_ra_hours = ra
                return boolean_reply(True)
            case SetTargetDec(dec, _, _):
                self.target_dec_deg = dec
                return boolean_reply(True)
            case GotoTarget():
                return await self._goto()
            case SyncTarget():
                return await self._sync()
            case Halt(direction):
                await self._halt(direction)
                return b""
            case Move(direction):
                await self._move(direction)
                return b""
            case PulseGuide(direction, duration_ms):
                await self._quietly(
                    f"guide pulse {direction.name.lower()} {duration_ms} ms",
                    self.mount.pulse_guide(_GUIDE[direction], duration_ms),
                )
                return b""
            case SetRate(rate):
                self.rate = rate
                return b""
            case SetLatitude() | SetLongitude():
                return boolean_reply(await self._set_site(command))
            case SetUtcOffset(hours):
                self.handset.utc_offset_hours = hours
                return boolean_reply(True)
            case SetLocalTime(hour, minute, second):
                day = self.handset.local_now().date()
                return boolean_reply(await self._set_clock(day, time(hour, minute, second)))
            case SetLocalDate(month, day, year):
                time_of_day = self.handset.local_now().time().replace(microsecond=0)
                ok = await self._set_clock(date(year, month, day), time_of_day)
                return DATE_SET_REPLY if ok else boolean_reply(False)

    def _refuse_read_only(self, command: AnyCommand) -> bytes:
        """Each command's own refusal: a goto's ``1<reason>#``, a sync's reason text, a set's
        ``0``; motions have no reply, so they are ignored (and logged)."""
        logger.info("read-only: %s refused", type(command).__name__)
        match command:
            case GotoTarget():
                return slew_reply(SlewRefusal.OTHER, READ_ONLY_TEXT)
            case SyncTarget():
                status = self.handset.config.sync_reply is SyncReply.STATUS
                return text_reply(f"1{READ_ONLY_TEXT}" if status else READ_ONLY_TEXT)
            case Halt() | Move() | PulseGuide():
                return b""
        return boolean_reply(False)

    # --- reads ----------------------------------------------------------------------------------

    def _current(self, *, position: bool) -> MountState | None:
        """The state if it may be served as current, else None (logged at debug level)."""
        try:
            return self.mount.fresh_state(position=position)
        except MountError as error:
            logger.debug("no current reading to answer with: %s", error)
            return None

    def _read(self, what: Query) -> str | None:
        """The text of a ``:G..#`` reply; None: no reply (no current reading to give)."""
        precise, degree = self.high_precision, self.degree_sign
        position = _POSITION_QUERIES.get(what)
        if position is not None:
            read, text = position
            current = self._current(position=True)
            value = None if current is None else read(current)
            return None if value is None else text(value, precise, degree)
        if what in _STATE_QUERIES and self._current(position=False) is None:
            return None
        state = self.mount.state
        match what:
            case Query.TARGET_RA:
                target = self.target_ra_hours or 0.0
                return format_ra(target, high_precision=precise)
            case Query.TARGET_DEC:
                target_dec = self.target_dec_deg or 0.0
                return format_dec(target_dec, high_precision=precise, degree_sign=degree)
            case Query.SIDEREAL_TIME:
                return format_ra(lst_hours(self.mount.now(), self.mount.site.longitude_deg))
            case Query.LOCAL_TIME:
                return self.handset.local_now().strftime("%H:%M:%S")
            case Query.LOCAL_TIME_12H:
                return self.handset.local_now().strftime("%I:%M:%S")
            case Query.DATE:
                return self.handset.local_now().strftime("%m/%d/%y")
            case Query.LATITUDE:
                latitude = self.mount.site.latitude_deg
                return format_signed_degrees_minutes(latitude, degree_sign=degree)
            case Query.LONGITUDE:
                west = -self.mount.site.longitude_deg
                return format_signed_degrees_minutes(west, degree_digits=3, degree_sign=degree)
            case Query.UTC_OFFSET:
                return f"{self.handset.utc_offset_hours:+05.1f}"
            case Query.TIME_FORMAT:
                return "24"
            case Query.TRACKING_RATE:
                return _TRACKING_HZ[state.tracking]
            case Query.SITE_1_NAME | Query.SITE_2_NAME | Query.SITE_3_NAME | Query.SITE_4_NAME:
                return self.handset.config.site_name
            case Query.PRODUCT:
                return self.handset.config.product
            case Query.FIRMWARE_NUMBER:
                return self.handset.config.firmware
            case Query.FIRMWARE_DATE:
                return self.handset.config.firmware_date
            case Query.FIRMWARE_TIME:
                return self.handset.config.firmware_time
            case Query.FIRMWARE_FULL:
                return f"{self.handset.config.product} {self.handset.config.firmware}"
            case Query.STATUS:
                return self._status(state)
            case Query.DISTANCE_BARS:
                return "\x7f" if state.slewing else ""
        return None  # pragma: no cover - every query is matched above

    def _status(self, state: MountState) -> str:
        """``:GW#``: mount type, tracking (``T``/``N``) and alignment (``1``/``0``)."""
        mode = _ALIGNMENT_LETTER[self.mount.capabilities.alignment_mode]
        tracking = "N" if state.tracking is TrackingMode.OFF else "T"
        return f"{mode}{tracking}{'1' if state.aligned else '0'}"

    # --- motion ---------------------------------------------------------------------------------

    def _target_j2000(self) -> tuple[float, float] | None:
        if self.target_ra_hours is None or self.target_dec_deg is None:
            return None
        return apparent_to_j2000(self.target_ra_hours, self.target_dec_deg, self.mount.now())

    async def _goto(self) -> bytes:
        target = self._target_j2000()
        if target is None:
            return slew_reply(SlewRefusal.OTHER, "No target: send :Sr and :Sd first")
        try:
            await self.mount.goto_equatorial(*target)
        except SunAvoidanceError as exc:
            logger.warning("goto refused: %s", exc)
            return slew_reply(SlewRefusal.OTHER, "Too close to the Sun")
        except LimitError as exc:
            logger.warning("goto refused: %s", exc)
            below = "below" in str(exc)
            if below:
                return slew_reply(SlewRefusal.BELOW_HORIZON, "Object below horizon")
            return slew_reply(SlewRefusal.OTHER, "Object beyond the altitude limit")
        except MountError as exc:
            logger.warning("goto refused: %s", exc)
            return slew_reply(SlewRefusal.OTHER, str(exc))
        return slew_reply(None)

    async def _sync(self) -> bytes:
        target = self._target_j2000()
        status = self.handset.config.sync_reply is SyncReply.STATUS
        if target is None:
            reason = "No target: send :Sr and :Sd first"
            return text_reply(f"1{reason}" if status else reason)
        try:
            await self.mount.sync_equatorial(*target)
        except MountError as exc:
            logger.warning("sync refused: %s", exc)
            return text_reply(f"1{exc}"[:41] if status else str(exc)[:32])
        return text_reply("0" if status else MEADE_SYNC_TEXT)

    async def _halt(self, direction: Direction | None) -> None:
        if direction is None:
            await self._quietly("abort", self.mount.abort())
            return
        axis, _ = self._axis_and_sign(direction)
        await self._quietly(f"stop {direction.name.lower()}", self.mount.move_axis(axis, 0.0))

    async def _move(self, direction: Direction) -> None:
        axis, sign = self._axis_and_sign(direction)
        rate = self.handset.config.rate_deg_s(
            self.rate, self.mount.capabilities.max_axis_rate_deg_s
        )
        await self._quietly(
            f"move {direction.name.lower()}", self.mount.move_axis(axis, sign * rate)
        )

    def _axis_and_sign(self, direction: Direction) -> tuple[MountAxis, float]:
        """Which axis turns, and which way, to move the tube towards ``direction`` on the sky.

        Equatorial: west is the primary axis forwards in the northern hemisphere, north the
        secondary forwards unless a German mount is flipped (tube on the far side of the pier).
        Alt-az: west turns the azimuth up, north raises the altitude.
        """
        mode = self.mount.capabilities.alignment_mode
        if mode is AlignmentMode.ALT_AZ:
            hemisphere = 1.0
            flipped = False
        else:
            hemisphere = 1.0 if self.mount.site.latitude_deg >= 0.0 else -1.0
            normal = PierSide.EAST if hemisphere > 0 else PierSide.WEST
            side = self.mount.state.pier_side
            flipped = mode is AlignmentMode.GERMAN_POLAR and side not in (normal, PierSide.UNKNOWN)
        if direction in (Direction.EAST, Direction.WEST):
            return MountAxis.PRIMARY, hemisphere if direction is Direction.WEST else -hemisphere
        sign = -hemisphere if flipped else hemisphere
        return MountAxis.SECONDARY, sign if direction is Direction.NORTH else -sign

    async def _quietly(self, what: str, action: Awaitable[None]) -> None:
        """Await ``action``; a refusal is logged (these commands have no reply to carry it)."""
        try:
            await action
        except MountError as exc:
            logger.warning("%s refused: %s", what, exc)

    # --- site and time --------------------------------------------------------------------------

    async def _set_site(self, command: SetLatitude | SetLongitude) -> bool:
        site = self.mount.site
        if isinstance(command, SetLatitude):
            new_site = dataclasses.replace(site, latitude_deg=command.latitude_deg)
        else:
            new_site = dataclasses.replace(site, longitude_deg=command.east_longitude_deg)
        try:
            await self.mount.set_site(new_site)
        except (MountError, ValueError) as exc:
            logger.warning("site change refused: %s", exc)
            return False
        return True

    async def _set_clock(self, day: date, time_of_day: time) -> bool:
        utc = self.handset.utc_of_local(datetime.combine(day, time_of_day))
        try:
            await self.mount.set_time(utc)
        except NotSupportedError as exc:
            # The handset keeps the offset; the mount keeps its own clock. Not the client's fault.
            logger.info("time not passed on: %s", exc)
        except MountError as exc:
            logger.warning("time change refused: %s", exc)
            return False
        return True
