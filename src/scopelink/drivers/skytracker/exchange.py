"""The PC end of a Sky Tracker line: one exchange at a time, timeouts, resync, the bus.

Every exchange takes a turn on the :class:`~scopelink.mount.scheduling.WireScheduler`, so user
commands go before background polls. A Sky Commander exchange holds one turn from ``Q`` to ``q``
(nothing else may pass while the bus is held). After a timeout or a reply that does not parse
the line is resynchronised: ``q`` (harmless when the bus is not held), then ``V`` as a sync
point: the box answers in order, so once its known version string has come back every late
reply sent before it has been read and discarded; then drain until quiet, and a fresh codec. A
late reply can never be read as the answer to a later command.

A stop does not wait for any of that (issue #11): :meth:`SkyTrackerLine.stop_at_once` writes ``q``
(ending a grant, so the next bytes reach the box; harmless otherwise) and the stop's commands at
once, ahead of the turn. A reply being waited for is abandoned (the line resynchronises before its
next exchange), and the turn in progress ends at its next command (it must not press an arrow
again after the stop): :class:`StopWentFirstError`.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Awaitable, Sequence
from dataclasses import dataclass

from scopelink.drivers.common import LinkStatistics, ReplyDeadline
from scopelink.links import Link, LinkError
from scopelink.mount import DeviceError, NotConnectedError
from scopelink.mount.scheduling import Priority, WireScheduler
from scopelink.protocol.base import NeedData
from scopelink.protocol.skytracker import (
    NEED_DATA,
    PAUSED,
    BadReply,
    BusAnswer,
    BusState,
    CommanderCommand,
    PositionReply,
    ReadVersion,
    ReleaseBus,
    Reply,
    RequestBus,
    StrayByte,
    TrackerClient,
    TrackerCommand,
    VersionReply,
)

__all__ = [
    "DEFAULT_BUS_RETRY_DELAYS_S",
    "DEFAULT_GRANT_TIMEOUT_S",
    "DEFAULT_TIMEOUT_S",
    "BadReplyError",
    "BusOptions",
    "BusRefusedError",
    "LineOutOfSyncError",
    "ReplyTimeoutError",
    "SkyTrackerLine",
    "StopWentFirstError",
]

logger = logging.getLogger(__name__)

DEFAULT_TIMEOUT_S = 1.0
"""The spec names no reply time; the longest reply (16 bytes) takes 17 ms at 9600 baud."""
DEFAULT_GRANT_TIMEOUT_S = 0.1
"""The spec: after ``Q`` the PC waits up to 100 ms for the grant ``A``."""
DEFAULT_BUS_RETRY_DELAYS_S: tuple[float, ...] = (0.05, 0.1, 0.2, 0.4, 0.8, 1.6)
"""Back-off between bus requests that were refused (NUL) or unanswered: 7 tries in ~3.2 s."""
RESYNC_QUIET_S = 0.1
"""After a fault, input is drained until the line has been quiet this long."""
RESYNC_MAX_S = 2.0
POSITION_REPLY_SIZE = PositionReply.size
_REQUEST_BUS = RequestBus()
_RELEASE_BUS = ReleaseBus()
"""The bus commands of every Sky Commander exchange, built once (frozen, so shareable)."""


class ReplyTimeoutError(DeviceError):
    """No complete reply came in time (the line has been resynchronised, or will be before the
    next exchange)."""


class LineOutOfSyncError(ReplyTimeoutError):
    """The sync point (``V``) of a resync was not answered in time: the box is silent or still
    busy with an earlier command. The next exchange tries to resynchronise again first."""


class StopWentFirstError(DeviceError):
    """A stop was written at once while this turn was in progress: the turn ends here."""


class BadReplyError(DeviceError):
    """A reply of the right length that does not fit its command (the line was resynchronised)."""


class BusRefusedError(DeviceError):
    """The Sky Tracker would not lend the Sky Commander bus within the retry schedule.

    ``refused`` counts NUL answers (a GOTO is running), ``unanswered`` requests that got no
    good answer in time.
    """

    def __init__(self, message: str, *, refused: int, unanswered: int) -> None:
        super().__init__(message)
        self.refused = refused
        self.unanswered = unanswered


@dataclass(frozen=True, slots=True)
class BusOptions:
    """Timing of the Sky Commander bus on the PC side; the defaults follow the spec (see
    ``docs/drivers-skytracker.md``). The reply timeout is the line's ``timeout_s``."""

    grant_timeout_s: float = DEFAULT_GRANT_TIMEOUT_S
    retry_delays_s: tuple[float, ...] = DEFAULT_BUS_RETRY_DELAYS_S

    def __post_init__(self) -> None:
        if self.grant_timeout_s <= 0:
            raise ValueError(f"timeouts must be positive: {self}")
        if any(delay < 0 for delay in self.retry_delays_s):
            raise ValueError(f"bus retry delays must not be negative: {self}")


class SkyTrackerLine:
    """Exchanges with the Sky Tracker (and, through its bus, the Sky Commander) on ``link``."""

    def __init__(
        self,
        link: Link,
        *,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        bus: BusOptions | None = None,
        scheduler: WireScheduler | None = None,
    ) -> None:
        if not timeout_s > 0:
            raise ValueError(f"timeout {timeout_s} s must be positive")
        self.link = link
        self.timeout_s = timeout_s
        self.bus = bus or BusOptions()
        self.scheduler = scheduler or WireScheduler()
        self._client = TrackerClient()
        self.statistics = LinkStatistics()
        """Counters of this line (``commands_sent`` since the link opened: the Sky Tracker's
        ``S`` rule counts them)."""
        self._interrupted = False
        self._sync_marker: bytes | None = None
        """The box's version reply, once read: the answer the resync's ``V`` waits for."""
        self._commander_behind = False
        """A Sky Commander exchange failed: it may still owe replies (see _catch_up_commander)."""
        self.last_answer_s = time.monotonic()
        """:func:`time.monotonic` when the box last answered a command (or the line opened):
        how long it has been silent, which tells a lost box from a noisy line."""
        self._writing = WireScheduler()
        """Held while bytes are written: a stop never lands inside another command's bytes
        (first come, first served: every writer takes it at ``Priority.COMMAND``). A scheduler
        rather than an ``asyncio.Lock``: its free case takes no coroutine (issue #14)."""
        self._deadline = ReplyDeadline()
        """Bounds the reply being waited for, which a stop may abandon."""
        self._parse = self._parse_reply
        """The reply parser, bound once (each exchange hands it to the link)."""
        self._stops = 0
        """Stops written at once so far; a turn that began before the last one ends."""
        self._turn_stops = 0

    # --- Sky Tracker commands ----------------------------------------------------------------

    async def ask(
        self, command: TrackerCommand, priority: Priority = Priority.COMMAND
    ) -> Reply | None:
        """One Sky Tracker command and its reply (None for a command without one)."""
        scheduler = self.scheduler
        if scheduler.try_take():  # a free wire: no queue to join (the common case)
            try:
                self._turn_stops = self._stops
                return await self._exchange(command, self.timeout_s)
            finally:
                scheduler.release()
        async with scheduler.turn(priority):
            self._turn_stops = self._stops
            return await self._exchange(command, self.timeout_s)

    async def ask_sequence(
        self, commands: Sequence[TrackerCommand], priority: Priority = Priority.COMMAND
    ) -> list[Reply | None]:
        """Several Sky Tracker commands in one turn (e.g. ``b`` then the arrows still held)."""
        async with self.scheduler.turn(priority):
            self._turn_stops = self._stops
            return [await self._exchange(c, self.timeout_s) for c in commands]

    # --- Sky Commander commands through the bus ----------------------------------------------

    async def commander(
        self,
        commands: Sequence[CommanderCommand],
        priority: Priority = Priority.COMMAND,
        *,
        retry_delays_s: Sequence[float] | None = None,
    ) -> list[Reply | None]:
        """``Q``, the commands, ``q`` in one turn; the replies of the commands.

        A refused (NUL) or unanswered request is retried after each delay of the schedule, the
        wire free for others meanwhile; then :class:`BusRefusedError`.
        """
        delays = self.bus.retry_delays_s if retry_delays_s is None else retry_delays_s
        refused = unanswered = 0
        retried_commands = False
        attempt = 0
        scheduler = self.scheduler
        while attempt <= len(delays):
            if attempt:
                await asyncio.sleep(delays[attempt - 1])
            attempt += 1
            # The turn as scheduler.turn() takes it, without its context manager's coroutines
            # when the wire is free (every poll's position passes here, issue #14).
            if not scheduler.try_take():
                await scheduler.take(priority)
            try:
                self._turn_stops = self._stops
                try:  # the bus request (inline: every poll's position passes here)
                    answer = await self._exchange(_REQUEST_BUS, self.bus.grant_timeout_s)
                except (ReplyTimeoutError, BadReplyError) as error:
                    logger.info("bus request failed: %s", error)
                    unanswered += 1  # no (good) answer: the line was resynchronised
                    continue
                assert type(answer) is BusAnswer  # exact: isinstance of an ABC runs Python code
                if not answer.granted:
                    refused += 1
                    self.statistics.bus_refusals += 1
                    continue
                try:
                    if self._commander_behind:
                        await self._catch_up_commander()
                    replies: list[Reply | None] = []
                    for command in commands:
                        replies.append(await self._exchange(command, self.timeout_s))
                    return replies
                except (ReplyTimeoutError, BadReplyError) as error:
                    # Loading an object, realigning on it and reading the position can all be
                    # repeated: one more try (the resync has ended any partial line).
                    if retried_commands:
                        raise
                    retried_commands = True
                    attempt -= 1
                    logger.info("Sky Commander exchange failed, trying once more: %s", error)
                finally:
                    await self._release_bus()
            finally:
                scheduler.release()
        waited = sum(delays)
        what = ", ".join(c.describe() for c in commands)
        if refused:
            cause = (
                f"refused {refused} time(s) (NUL: a GOTO is running; wait for it or abort it)"
                + (f", unanswered {unanswered} time(s)" if unanswered else "")
            )
        else:
            cause = (
                f"no answer to 'Q' within {self.bus.grant_timeout_s * 1000:.0f} ms, "
                f"{unanswered} time(s)"
            )
        raise BusRefusedError(
            f"the Sky Tracker on {self.link.name} did not lend the Sky Commander bus for "
            f"{what!r} in {attempt + 1} request(s) over {waited:.2f} s: {cause}",
            refused=refused,
            unanswered=unanswered,
        )

    async def stop_at_once(self, commands: Sequence[TrackerCommand]) -> None:
        """Write ``q`` and ``commands`` (commands without replies: ``b``, ``U``) now, ahead of
        the turn and of any resynchronisation; a reply being waited for is abandoned. The stop
        is unconfirmed: the caller reads the status back through ordinary exchanges."""
        self._stops += 1
        self._deadline.interrupt()
        data = ReleaseBus().encode() + b"".join(command.encode() for command in commands)
        try:
            async with self._writing.turn(Priority.COMMAND):
                await self.link.write(data)
        except LinkError as error:
            self._interrupted = True
            raise NotConnectedError(f"the link {self.link.name} failed: {error}") from error
        self.statistics.commands_sent += 1 + len(commands)
        self.statistics.stops_at_once += 1
        logger.info(
            "stop written at once: %s", ", ".join(command.describe() for command in commands)
        )

    async def _catch_up_commander(self) -> None:
        """Inside a grant, after a failed Sky Commander exchange: ask for a position (``\r``)
        and read its 16-byte reply and on until quiet. The Sky Commander answers in order, so
        whatever it still owed (a late reply, the resync's position) comes first and is
        discarded with it; only then may the next reply be taken as the answer to a command.
        Replies it sends while the bus is released never reach the PC (the box keeps them)."""
        self._flush_strays()
        async with self._writing.turn(Priority.COMMAND):
            await self.link.write(b"\r")
        self.statistics.commands_sent += 1
        received = b""
        try:
            async with asyncio.timeout(self.timeout_s):
                while len(received) < POSITION_REPLY_SIZE:
                    received += await self.link.read()
        except TimeoutError:
            raise ReplyTimeoutError(
                f"the Sky Commander behind {self.link.name} has not answered since an earlier "
                f"fault: no reply to a position request within "
                f"{self.timeout_s * 1000:.0f} ms (is its cable to the Sky Tracker "
                "plugged in?)"
            ) from None
        except LinkError as error:
            self._interrupted = True
            raise NotConnectedError(f"the link {self.link.name} failed: {error}") from error
        received += await self.link.drain_input(RESYNC_QUIET_S, RESYNC_MAX_S)
        if len(received) > POSITION_REPLY_SIZE:
            logger.info("the Sky Commander caught up: discarded %s", received.hex(" "))
        self._commander_behind = False

    async def _release_bus(self) -> None:
        if self.link.closed:
            return
        # If the link went away, the box takes the bus back when its PC link ends. (A try, not
        # contextlib.suppress: that is an object and two calls on every poll.)
        try:
            await self._exchange(_RELEASE_BUS, self.timeout_s)
        except (LinkError, NotConnectedError):
            return

    # --- one exchange ------------------------------------------------------------------------

    async def _exchange(
        self, command: TrackerCommand | CommanderCommand, reply_within_s: float
    ) -> Reply | None:
        if self._interrupted:
            if not await self.resync():
                raise LineOutOfSyncError(
                    f"cannot send {command.describe()!r}: the line {self.link.name} is not back "
                    "in sync after an earlier fault (no answer to the 'V' sync point within "
                    f"{self.timeout_s * 1000:.0f} ms): is the Sky Tracker busy or "
                    "off?"
                )
            self._interrupted = False
        if self._stops != self._turn_stops and not isinstance(command, ReleaseBus):
            raise StopWentFirstError(
                f"{command.describe()!r} not sent: a stop was written meanwhile"
            )
        if self._client.has_data:  # bytes before the command was sent: strays
            self._flush_strays()
        data = self._client.send(command)
        deadline = self._deadline
        deadline.interrupted = False
        link = self.link
        try:
            if command.reply is None:
                await self._write(data)
                return None
            # Written, and the reply's reader set up, in one call where the link can (TCP) and
            # no stop is being written: the link hands the reply's bytes to _parse_reply as they
            # arrive and wakes this task once, with the reply (issue #14: CPU per command).
            reading: Awaitable[Reply | BadReply] | None = (
                None if self._writing.busy else link.write_and_read_event(data, self._parse)
            )
            if reading is None:  # a link that writes in a coroutine (serial, paced), or a stop
                await self._write(data)
                reading = link.read_event(self._parse)
            else:
                self.statistics.commands_sent += 1
            with deadline.start(reply_within_s):
                event = await reading
        except TimeoutError:
            self._client.abandon_reply()
            if deadline.interrupted:
                self._interrupted = True  # resynchronised before the next exchange
                raise ReplyTimeoutError(
                    f"the reply to {command.describe()!r} was abandoned: a stop went first"
                ) from None
            await self._resync_after_fault()
            raise ReplyTimeoutError(
                f"no reply to {command.describe()!r} within {reply_within_s * 1000:.0f} ms on "
                f"{self.link.name}: is the Sky Tracker on, at 9600 baud, and the cable plugged in?"
            ) from None
        except LinkError as error:
            self._client.abandon_reply()
            self._interrupted = True
            raise NotConnectedError(f"the link {self.link.name} failed: {error}") from error
        except asyncio.CancelledError:
            # Cancelled mid-exchange (e.g. the poller stopped): the reply may still come, so the
            # next exchange resynchronises first.
            self._client.abandon_reply()
            self._interrupted = True
            raise
        self.last_answer_s = time.monotonic()  # an answer, if perhaps a garbled one
        if type(event) is BadReply:
            await self._resync_after_fault()
            raise BadReplyError(f"bad reply on {self.link.name}: {event.describe()}")
        if self._sync_marker is None and isinstance(event, VersionReply):
            self._sync_marker = event.encode()
        return event  # type: ignore[return-value]  # a reply: not NEED_DATA, not BadReply

    async def _write(self, data: bytes) -> None:
        """Write one command's bytes in the write turn (a stop never lands inside them)."""
        # The write turn taken and released by hand: ``async with`` adds coroutines to every
        # exchange (issue #14).
        writing = self._writing
        if not writing.try_take():
            await writing.take(Priority.COMMAND)
        try:
            await self.link.write(data)
        finally:
            writing.release()
        self.statistics.commands_sent += 1

    def _parse_reply(self, data: bytes) -> Reply | BadReply | NeedData:
        """The reader the link feeds a reply's bytes to (in the transport's call): the reply once
        complete (or BadReply), NEED_DATA until then. Never raises (the link's rule for a
        parser). While a reply is awaited the codec takes every byte as the reply's, so the
        stray-byte branch is a guard, not a path: strays are flushed before each command."""
        client = self._client
        client.receive_data(data)
        while True:
            event = client.next_event()
            if type(event) is StrayByte:  # exact: the events derive from an ABC
                self._note_stray(event)
                continue
            assert event is not PAUSED  # a client never pauses
            return event  # type: ignore[return-value]  # not a StrayByte, not PAUSED

    def _flush_strays(self) -> None:
        while (event := self._client.next_event()) is not NEED_DATA:
            if isinstance(event, StrayByte):
                self._note_stray(event)

    def _note_stray(self, event: StrayByte) -> None:
        self.statistics.stray_bytes += 1
        logger.info("ignored %s", event.describe())

    async def _resync_after_fault(self) -> None:
        """Resync; if the sync point was not answered, the next exchange tries again first."""
        if not await self.resync():
            self._interrupted = True

    async def resync(self) -> bool:
        """Release the bus (in case), send the ``V`` sync point and read up to its answer,
        drain late bytes until quiet, start a fresh codec.

        Returns False when the sync point was not answered within the reply timeout (the box is
        silent or still busy): late replies may still come, so the line is not to be trusted.
        Before the version is known (during connect) only the drain is done.
        """
        self.statistics.resyncs += 1
        held = self._client.bus is BusState.HELD
        self._client = TrackerClient()
        discarded = b""
        synced = True
        try:
            if held:
                # Still inside the grant: CR ends any partial 'L' line the Sky Commander holds
                # (bytes lost on the unbuffered port); without one it asks for a position, whose
                # reply is drained here, before 'q', so it cannot reach the box's own next poll.
                async with self._writing.turn(Priority.COMMAND):
                    await self.link.write(b"\r")
                discarded += await self.link.drain_input(RESYNC_QUIET_S, RESYNC_MAX_S)
                # Still behind if it is slow (its replies may come in a later grant).
                self._commander_behind = True
            async with self._writing.turn(Priority.COMMAND):
                await self.link.write(ReleaseBus().encode())
            self.statistics.commands_sent += 1 + held
            if self._sync_marker is not None:
                # The box answers in order: a reply it is late with comes before the answer to
                # this 'V'. A quiet drain alone would let a reply later than the drain through,
                # to be read as the answer to the next command.
                async with self._writing.turn(Priority.COMMAND):
                    await self.link.write(ReadVersion().encode())
                self.statistics.commands_sent += 1
                received, synced = await self._read_through(self._sync_marker)
                discarded += received
            discarded += await self.link.drain_input(RESYNC_QUIET_S, RESYNC_MAX_S)
        except LinkError as error:
            raise NotConnectedError(f"the link {self.link.name} failed: {error}") from error
        if discarded:
            logger.info("resync discarded %s", discarded.hex(" "))
        if not synced:
            logger.warning("no answer to the sync point 'V' on %s: not in sync", self.link.name)
        return synced

    async def _read_through(self, marker: bytes) -> tuple[bytes, bool]:
        """Read until ``marker`` has come (True), or the reply timeout passes (False)."""
        received = b""
        try:
            async with asyncio.timeout(self.timeout_s):
                while marker not in received:
                    received += await self.link.read()
        except TimeoutError:
            return received, False
        return received, True
