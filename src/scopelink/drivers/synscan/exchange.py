"""One SynScan exchange at a time on a link: send, read the reply by its shape, recover.

:class:`SynScanWire` owns the link and the client codec. Every exchange takes a turn on the
:class:`~scopelink.mount.scheduling.WireScheduler` (user commands before polls), writes one
command and reads its reply by exact length within the timeout (the spec's 5 s by default).

After a timeout, a malformed reply or a dropped link the stream can no longer be trusted: a late
reply would be read as the answer to the next command. So the wire drains the input, resets the
codec and echoes a byte that no earlier echo used (``K`` + 0x80..0xFF, counting); everything
before that byte and ``#`` is discarded. Only then is the command tried once more: every SynScan
command is idempotent (a repeated goto, sync, rate or tracking command has the effect of one), so
the retry is safe. A link that closed is reopened through the factory first (a TCP bridge that
dropped the connection comes back transparently). When recovery fails the caller gets a
:class:`~scopelink.mount.DeviceError` naming the cause, and the next exchange recovers again.

A stop must not wait for any of that (issue #11: a corrupted reply to the resynchronising echo
held an owed stop back for the 5 s timeout, 17° of travel at full speed). :meth:`stop_at_once`
takes the link ahead of every queued exchange; an exchange that is still reading after
``STOP_GRACE_S`` (or any reading while the stream is out of step) is interrupted, fails with a
``DeviceError`` and is *not* retried (a retried slew would undo the stop); and if the stream is
out of step the stop's bytes are written at once, back to back, without reading their replies.
The caller then confirms the stop through ordinary exchanges (which resynchronise first).
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import AsyncIterator, Awaitable, Callable, Sequence
from contextlib import asynccontextmanager

from scopelink.drivers.common import LinkFactory, LinkStatistics, ReplyDeadline
from scopelink.links import Link, LinkClosedError, LinkError
from scopelink.mount import DeviceError, Priority, WireScheduler
from scopelink.protocol.synscan import (
    AnyCommand,
    AnyReply,
    ClientError,
    Echo,
    EchoReply,
    MalformedReply,
    NeedData,
    SynScanClientConnection,
    UnexpectedData,
    encode_command,
)

__all__ = ["DEFAULT_TIMEOUT_S", "STOP_GRACE_S", "SynScanWire"]

logger = logging.getLogger(__name__)

DEFAULT_TIMEOUT_S = 5.0
"""The spec: "Software drivers should be prepared to wait up to 5.0s" for a reply."""

_ECHO_VALUES = range(0x80, 0x100)
"""Resynchronisation echoes: bytes no ASCII reply contains, counted so that each is unique among
recent ones."""

_DRAIN_QUIET_S = 0.05
"""Input silent this long after a failure: the device has finished sending whatever it had."""

_ECHO_PATIENCE = 3
"""A resynchronising echo waits one timeout past the last stale byte, up to this many timeouts:
a device still sending the rest of a slow reply is alive, and answers the echo right after."""


STOP_GRACE_S = 0.1
"""A stop waits this long for an exchange in flight on a stream in step (the longest reply, 18
bytes, takes 19 ms at 9600 baud); a reply still missing by then is not worth more of the stop's
time: the exchange is interrupted."""


Reply = AnyReply | ClientError
"""What reading a reply gives: the reply, or an error event (after stale bytes were dropped)."""


class _ExchangeError(Exception):
    """One exchange went wrong; the message says how (it becomes part of a DeviceError).
    ``interrupted``: cut short by a stop, and not to be retried."""

    def __init__(self, message: str, *, interrupted: bool = False, sent: bool = True) -> None:
        super().__init__(message)
        self.interrupted = interrupted
        self.sent = sent


class SynScanWire:
    """The link to one hand control, used one exchange at a time.

    ``name`` labels errors (the link spec, e.g. ``/dev/ttyUSB0``). ``avoid_echo`` holds bytes the
    resynchronising echo must not use: a stale reply ending in such a byte and ``#`` (the model
    code of ``m``) would otherwise pass for the echo.
    """

    def __init__(
        self,
        factory: LinkFactory,
        *,
        name: str,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        scheduler: WireScheduler | None = None,
    ) -> None:
        if not timeout_s > 0:
            raise ValueError(f"timeout {timeout_s} s must be positive")
        self._factory = factory
        self.name = name
        self.timeout_s = timeout_s
        self.scheduler = scheduler or WireScheduler()
        self.statistics = LinkStatistics()
        self.avoid_echo: set[int] = set()
        self._link: Link | None = None
        self._codec = SynScanClientConnection()
        self._needs_resync = False
        self._next_echo = 0
        self._holder: asyncio.Task[object] | None = None
        self._io = WireScheduler()
        """Held while a task uses the link (one recovery and exchange, or a stop's write): a
        lock that an uncontended exchange takes without an ``await``."""
        self._deadline = ReplyDeadline()
        """Bounds the read in progress, which a stop may cut short."""
        self._stops_waiting = 0
        self._patient = False
        """The exchange in progress is a resynchronising echo (see ``_ECHO_PATIENCE``)."""
        self._received = self._parse_received
        """The link's parser (one bound method for every exchange)."""
        self.last_write_at = 0.0
        """Event-loop time at which the last command started to leave (times guide pulses)."""
        self.last_answer_s = -float("inf")
        """:func:`time.monotonic` when the device last answered an exchange (a resynchronising
        echo too): how long it has been silent, which tells a lost device from a noisy line."""

    @property
    def link(self) -> Link | None:
        """The open link, if any."""
        return self._link

    @property
    def is_open(self) -> bool:
        return self._link is not None and not self._link.closed

    async def open(self) -> None:
        """Open the link and check the stream with a unique echo."""
        async with self.scheduler.turn(Priority.COMMAND):
            await self._reopen()
            try:
                await self._resynchronise("checking the link")
            except DeviceError as error:
                # One lost echo is not a dead device: a second unique echo decides.
                logger.info("%s: %s; trying once more", self.name, error)
                await self._resynchronise("checking the link")

    async def close(self) -> None:
        """Close the link (idempotent)."""
        link, self._link = self._link, None
        self._deadline.close()
        if link is not None:
            await link.close()

    async def ask(
        self,
        command: AnyCommand,
        priority: Priority = Priority.COMMAND,
        *,
        meanwhile: Callable[[], object] | None = None,
    ) -> AnyReply:
        """Send ``command`` and return its reply; recovers once, else raises DeviceError.

        ``meanwhile`` runs right after the command has been written (again if it is re-sent): CPU
        work that then overlaps the device's answer instead of leaving the wire idle.
        """
        scheduler, io, link = self.scheduler, self._io, self._link
        if (
            not self._needs_resync
            and link is not None
            and not link.closed
            and scheduler.try_take_with(io)  # the wire free, and the link (unless a stop has it)
        ):
            # In step, open, free, nobody waiting: the first attempt right here, without the
            # recovery loop's coroutine (issue #14: CPU per command).
            failure = None
            try:
                return await self._exchange(command, meanwhile)
            except _ExchangeError as error:
                failure = error
            finally:
                if failure is None:
                    scheduler.release_with(io)
                else:
                    io.release()  # the wire stays ours for the retry: nothing slips in between
            try:
                retry = self._failed(failure, None)  # raises if it may not be retried
                return await self._ask_holding_the_wire(command, meanwhile, retry)
            finally:
                scheduler.release()
        if scheduler.try_take():  # a free wire: no queue to join
            try:
                return await self._ask_holding_the_wire(command, meanwhile)
            finally:
                scheduler.release()
        if self._holder is not None and self._holder is asyncio.current_task():
            return await self._ask_holding_the_wire(command, meanwhile)
        async with scheduler.turn(priority):
            return await self._ask_holding_the_wire(command, meanwhile)

    @asynccontextmanager
    async def exclusive(self, priority: Priority = Priority.COMMAND) -> AsyncIterator[None]:
        """Hold the wire for several exchanges of this task (an abort's ``M`` and its stops): no
        poll slips in between them."""
        if self._holder is not None and self._holder is asyncio.current_task():
            yield
            return
        async with self.scheduler.turn(priority):
            self._holder = asyncio.current_task()
            try:
                yield
            finally:
                self._holder = None

    async def _ask_holding_the_wire(
        self,
        command: AnyCommand,
        meanwhile: Callable[[], object] | None,
        failure: _ExchangeError | None = None,
    ) -> AnyReply:
        """Recover if needed, then exchange; after a ``failure`` (a first attempt that failed,
        here or in :meth:`ask`) only one attempt is left."""
        for _attempt in range(1 if failure is not None else 2):
            io = self._io
            if not io.try_take():
                await io.take(Priority.COMMAND)
            try:
                if self._needs_resync or not self.is_open:
                    await self._recover(command, failure)
                return await self._exchange(command, meanwhile)
            except _ExchangeError as error:
                failure = self._failed(error, failure)
            finally:
                io.release()
        raise AssertionError("unreachable")  # pragma: no cover - _failed raises on the second

    def _failed(self, error: _ExchangeError, failure: _ExchangeError | None) -> _ExchangeError:
        """Count a failed attempt; raise DeviceError if it may not be retried (a stop went out
        meanwhile: re-sending could undo it) or was the second; else return it (recover next)."""
        self.statistics.failures += 1
        self._needs_resync |= error.sent
        if error.interrupted:
            raise DeviceError(str(error)) from None
        logger.info("%s: %s; recovering", self.name, error)
        if failure is not None:
            raise DeviceError(f"{failure}; after recovering, again: {error}") from None
        return error

    async def stop_at_once(self, commands: Sequence[AnyCommand]) -> bool:
        """Take the link for a stop ahead of everything queued; if the stream is out of step (or
        the link closed, or an exchange had to be interrupted), write ``commands`` at once, back
        to back, without reading their replies, and return True. Return False when the stream
        is in step: the caller's ordinary exchanges (``ask``) then carry the stop, next in line.

        Either way the stop is unconfirmed until ordinary exchanges have had its replies; the
        stream is left marked for resynchronisation after a blind write. Raises DeviceError
        when the link cannot be (re)opened or written.
        """
        loop = asyncio.get_running_loop()
        self._stops_waiting += 1
        try:
            interrupted = False
            while True:
                reading = self._deadline
                if reading.active and (
                    self._needs_resync or loop.time() - reading.since >= STOP_GRACE_S
                ):
                    reading.interrupt()  # the reader fails with "a stop went first"
                    interrupted = True
                try:
                    async with asyncio.timeout(STOP_GRACE_S / 4.0):
                        await self._io.take(Priority.COMMAND)
                    break
                except TimeoutError:
                    continue  # still busy: look again whether it is reading by now
            try:
                if not interrupted and not self._needs_resync and self.is_open:
                    return False
                self._needs_resync = True
                if not self.is_open:
                    await self._reopen()
                link = self._link
                assert link is not None
                data = b"".join(encode_command(command) for command in commands)
                self.statistics.stops_at_once += 1
                self.statistics.bytes_sent += len(data)
                self.last_write_at = loop.time()
                try:
                    await link.write(data)
                except LinkClosedError as error:
                    await self.close()
                    raise DeviceError(
                        f"{self.name} closed while a stop was written: {error}"
                    ) from None
                logger.info(
                    "%s: stop written at once: %s",
                    self.name,
                    ", ".join(command.describe() for command in commands),
                )
                return True
            finally:
                self._io.release()
        finally:
            self._stops_waiting -= 1

    async def _recover(self, command: AnyCommand, failure: _ExchangeError | None) -> None:
        why = str(failure) if failure else "the previous exchange failed"
        try:
            if not self.is_open:
                try:
                    await self._reopen()
                except DeviceError as error:
                    # Name both: why the link went (closed during ...) and why it stays gone.
                    raise DeviceError(f"{why}, and {error}") from None
            await self._resynchronise(why)
        except DeviceError as error:
            raise DeviceError(f"{command.describe()!r} not sent: {error}") from None

    async def _reopen(self) -> None:
        await self.close()
        try:
            self._link = await self._factory()
        except (LinkError, OSError) as error:
            raise DeviceError(f"cannot open {self.name}: {error}") from None
        self.statistics.reconnects += 1
        self._codec = SynScanClientConnection()

    async def _resynchronise(self, why: str) -> None:
        """Drain, reset the codec and echo a byte no earlier echo used."""
        link = self._link
        assert link is not None
        self._needs_resync = True
        self.statistics.resyncs += 1
        dropped = self._codec.reset()
        try:
            with self._interruptible(None):
                dropped += await link.drain_input(_DRAIN_QUIET_S, max_seconds=self.timeout_s)
        except LinkClosedError as error:
            await self.close()
            raise DeviceError(f"{why}, and {self.name} closed: {error}") from None
        except TimeoutError:
            if not self._deadline.interrupted:  # pragma: no cover - no deadline of its own
                raise
            self.statistics.interrupted += 1
            raise DeviceError(f"{why}; resynchronising was interrupted by a stop") from None
        self._discard(dropped)
        value = self._echo_value()
        try:
            self._patient = True
            reply = await self._exchange(Echo(value))
        except _ExchangeError as error:
            if error.interrupted:
                raise DeviceError(f"{why}; resynchronising: {error}") from None
            raise DeviceError(
                f"{why}; resynchronising failed: {error} — is the hand control switched on and "
                "connected?"
            ) from None
        finally:
            self._patient = False
        if reply != EchoReply(value):  # pragma: no cover - the codec only returns this shape
            raise DeviceError(f"{why}; resynchronising got {reply.describe()!r}")
        self._needs_resync = False

    def _echo_value(self) -> int:
        for _ in _ECHO_VALUES:
            value = _ECHO_VALUES[self._next_echo % len(_ECHO_VALUES)]
            self._next_echo += 1
            if value not in self.avoid_echo:
                return value
        return _ECHO_VALUES[self._next_echo % len(_ECHO_VALUES)]  # everything avoided: any will do

    async def _exchange(
        self, command: AnyCommand, meanwhile: Callable[[], object] | None = None
    ) -> AnyReply:
        """One command and its reply within ``timeout_s``; while ``_patient`` (a resynchronising
        echo) the timeout restarts whenever stale bytes are discarded (see ``_ECHO_PATIENCE``)."""
        link = self._link
        if link is None:
            raise _ExchangeError(f"{self.name} is closed")
        if self._stops_waiting:
            raise _ExchangeError(
                f"{command.describe()!r} not sent: a stop goes first", interrupted=True, sent=False
            )
        data = self._codec.send(command)
        statistics = self.statistics
        statistics.exchanges += 1
        statistics.bytes_sent += len(data)
        deadline = self._deadline
        try:
            try:
                # Written, and the reader set up, in one call where the link can (TCP); the link
                # hands the reply's bytes to _received as they arrive, which wakes us once.
                reading: Awaitable[Reply] | None = link.write_and_read_event(data, self._received)
                if reading is None:  # a link that writes in a coroutine (serial, paced)
                    sent_at: float | None = deadline.loop.time()
                    await link.write(data)
                    if meanwhile is not None:
                        meanwhile()
                    reading = link.read_event(self._received)
                elif meanwhile is None:
                    sent_at = None  # just now: the deadline's start looks the time up
                else:
                    sent_at = deadline.loop.time()
                    try:
                        meanwhile()
                    except BaseException:
                        assert isinstance(reading, asyncio.Future)
                        reading.cancel()  # nobody will read it: later bytes stay buffered
                        raise
                # The timeout counts from here (after the write and ``meanwhile``).
                with deadline.start(self.timeout_s):
                    self.last_write_at = deadline.since if sent_at is None else sent_at
                    if self._needs_resync and self._stops_waiting > 0:
                        deadline.interrupt()  # see _interruptible (a stop came meanwhile)
                    event = await reading
                    # Not isinstance: on an ABC's subclasses it runs Python code on every reply.
                    if type(event) is MalformedReply:
                        raise _ExchangeError(f"malformed reply on {self.name}: {event.describe()}")
                self.last_answer_s = time.monotonic()
                return event  # type: ignore[return-value]  # not an error event
            except TimeoutError:
                if deadline.interrupted:
                    self.statistics.interrupted += 1
                    raise _ExchangeError(
                        f"the reply to {command.describe()!r} was abandoned: a stop went first",
                        interrupted=True,
                    ) from None
                raise _ExchangeError(
                    f"no reply to {command.describe()!r} within {self.timeout_s:g} s on {self.name}"
                ) from None
            except LinkClosedError as error:
                await self.close()
                message = f"{self.name} closed during {command.describe()!r}: {error}"
                raise _ExchangeError(message) from None
        except BaseException:
            # Cancelled or failed half way: the stream is out of step until resynchronised.
            self._needs_resync = True
            raise

    def _parse_received(self, data: bytes) -> AnyReply | ClientError | NeedData:
        """The link's parser during an exchange (called as bytes arrive): the reply, a
        malformed one, or NEED_DATA."""
        self.statistics.bytes_received += len(data)
        event = self._codec.receive_and_next_event(data)
        if type(event) is UnexpectedData:
            return self._drop_stale(event)
        return event

    def _drop_stale(self, event: UnexpectedData) -> AnyReply | ClientError | NeedData:
        """Stale bytes before the reply: dropped (see :meth:`_discard_stale`); the codec's next
        event that is not."""
        while True:
            self._discard_stale(event.data, self._patient)
            next_event = self._codec.next_event()
            if type(next_event) is not UnexpectedData:
                return next_event
            event = next_event

    def _discard_stale(self, data: bytes, patient: bool) -> None:
        """Stale bytes before the reply: dropped; a ``patient`` read (a resynchronising echo)
        then waits one more timeout from now, up to ``_ECHO_PATIENCE`` timeouts in all."""
        self._discard(data)
        if patient and not self._stops_waiting:
            deadline = self._deadline
            give_up_at = deadline.since + _ECHO_PATIENCE * self.timeout_s
            deadline.reschedule(min(deadline.loop.time() + self.timeout_s, give_up_at))

    def _interruptible(self, seconds: float | None, now: float | None = None) -> ReplyDeadline:
        """A read that times out after ``seconds`` (None: never) or when a stop interrupts it;
        either way ``TimeoutError`` leaves the ``with`` block, and ``self._deadline.interrupted``
        tells which."""
        deadline = self._deadline.start(seconds, now)
        if self._stops_waiting and self._needs_resync:
            deadline.interrupt()
        return deadline

    def _discard(self, data: bytes) -> None:
        if data:
            self.statistics.discarded_bytes += len(data)
            logger.info("%s: discarded %d stale bytes %r", self.name, len(data), data)
