"""The state cache behind every front end: one poller per mount, running while anyone watches.

Front ends never wait on the wire to answer a read: they take :attr:`Mount.state`, which this
poller keeps fresh by calling ``refresh()`` for as long as at least one watcher is registered.

How often (the poll policy, :class:`PollPolicy`; docs/mount-api.md, "The poll policy"): at full
rate only while something needs it (a reader's :meth:`StatePoller.demand` within the last
``demand_hold_s``, a :meth:`StatePoller.holding_full_rate` holder such as a ``Mount.states()``
consumer,
or the mount's own ``full_rate_needed``: a slew, a park, a rate motion); otherwise once every
``idle_poll_s``. Even at full rate a poll starts no sooner than the previous one's bytes would
take on a line of ``max_poll_baud`` (10 bits a byte), whatever the link.

A failed poll keeps the last good reading, names the cause in ``problems`` and is retried after
``retry_s``, doubling with each failure in a row up to ``max_retry_s``; the poller itself never
dies of a device error. It polls while the mount is *engaged* (connected, or its link lost but
not disconnected): a driver's ``refresh`` reopens a lost link, so polling on is what brings it
back (docs/reliability-safety.md, "Lost and stalled devices").
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import math
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager

from scopelink.mount.errors import NotConnectedError, StaleReadingError
from scopelink.mount.types import MountState, TrackingMode

__all__ = [
    "BITS_PER_BYTE",
    "DEFAULT_DEMAND_HOLD_S",
    "DEFAULT_IDLE_POLL_S",
    "DEFAULT_MAX_POLL_BAUD",
    "DEFAULT_STALE_AFTER_S",
    "MAX_RETRY_S",
    "MAX_STALE_AFTER_S",
    "MIN_STALE_AFTER_S",
    "PollPolicy",
    "StateBroadcast",
    "StatePoller",
    "check_stale_after",
    "require_fresh",
    "without_motion_claims",
]

logger = logging.getLogger(__name__)

DEFAULT_STALE_AFTER_S = 2.0
"""A reading older than this is not served as current. Several polls of the slowest device
(a SynScan poll with its full read is ~0.1-0.3 s; a failed poll is retried after 1 s), so one
lost reply never shows; well inside the 5 s a watching client may be shown an old position."""
MIN_STALE_AFTER_S = 0.2
"""Shorter would call readings stale between two healthy polls."""
MAX_STALE_AFTER_S = 5.0
"""No setting serves a reading older than this as current while a client watches."""
MAX_RETRY_S = 2.0
"""The poller's back-off after failures in a row stops growing here: a device that comes back is
polled again within this (plus one attempt), inside the 5 s the reconnect promise gives."""

DEFAULT_IDLE_POLL_S = 1.0
"""With nothing needing more, the mount is polled once a second (as INDI does)."""
IDLE_POLL_RANGE_S = (0.1, 2.5)
"""Allowed ``idle_poll_s``: at most half the longest ``stale_after_s``."""
DEFAULT_DEMAND_HOLD_S = 2.0
"""A read raises the rate to full for this long: a client reading at least this often gets
full-rate readings; a slower one, idle-rate readings no older than ``idle_poll_s``."""
DEMAND_HOLD_RANGE_S = (0.1, 60.0)
DEFAULT_MAX_POLL_BAUD = 9600
"""The poller never moves more bytes a second (either way) than a 9600-baud line carries."""
MAX_POLL_BAUD_RANGE = (2400, 1_000_000)
"""Below 2400 baud a SynScan full read would take a quarter of a second of line time."""
BITS_PER_BYTE = 10
"""A byte on an 8N1 line: start bit, 8 data bits, stop bit."""


@dataclasses.dataclass(frozen=True, slots=True)
class PollPolicy:
    """How often the poller polls (see the module's docstring); checked on construction."""

    idle_poll_s: float = DEFAULT_IDLE_POLL_S
    demand_hold_s: float = DEFAULT_DEMAND_HOLD_S
    max_poll_baud: int = DEFAULT_MAX_POLL_BAUD

    def __post_init__(self) -> None:
        _check_range("idle_poll_s", self.idle_poll_s, IDLE_POLL_RANGE_S, "seconds")
        _check_range("demand_hold_s", self.demand_hold_s, DEMAND_HOLD_RANGE_S, "seconds")
        if isinstance(self.max_poll_baud, bool) or not isinstance(self.max_poll_baud, int):
            raise ValueError(f"max_poll_baud {self.max_poll_baud!r} must be a whole number")
        _check_range("max_poll_baud", self.max_poll_baud, MAX_POLL_BAUD_RANGE, "baud")

    @property
    def max_bytes_per_s(self) -> float:
        return self.max_poll_baud / BITS_PER_BYTE

    def idle_period_s(self, stale_after_s: float) -> float:
        """The idle poll period in force: ``idle_poll_s``, at most half of ``stale_after_s``
        (an idle mount's reading is then never older than ``stale_after_s``)."""
        return min(self.idle_poll_s, stale_after_s / 2.0)


def _check_range(name: str, value: object, bounds: tuple[float, float], unit: str) -> None:
    low, high = bounds
    number = value if isinstance(value, int | float) and not isinstance(value, bool) else None
    if number is None or not low <= number <= high:  # (nan fails both comparisons)
        raise ValueError(f"{name} {value!r} must lie in [{low:g}, {high:g}] {unit}")


def check_stale_after(seconds: float) -> float:
    """``seconds`` if it is an allowed ``stale_after_s``, else ValueError naming the range."""
    if not (isinstance(seconds, int | float) and MIN_STALE_AFTER_S <= seconds <= MAX_STALE_AFTER_S):
        raise ValueError(
            f"stale_after_s {seconds!r} must lie in [{MIN_STALE_AFTER_S:g}, "
            f"{MAX_STALE_AFTER_S:g}] seconds"
        )
    return float(seconds)


def require_fresh(
    state: MountState, stale_after_s: float, *, position: bool, name: str
) -> MountState:
    """``state`` if it may be served as current; else :class:`NotConnectedError` (the link is
    down) or :class:`StaleReadingError` (older than ``stale_after_s``), naming the reading's age
    and the last problem. ``position``: judge the coordinates' age (else the state's)."""
    age = state.position_age_s() if position else state.age_s()
    why = f": {state.problems[0]}" if state.problems else ""
    if not state.connected:
        raise NotConnectedError(
            f"the link to {name} is down (last reading {age:.1f} s old){why}; it is reopened "
            "by itself while a client watches"
        )
    if age > stale_after_s:
        what = "position" if position else "state"
        raise StaleReadingError(
            f"the last {what} reading of {name} is {age:.1f} s old, more than stale_after_s "
            f"({stale_after_s:g} s): not served as current{why or ' (no answer since)'}"
        )
    return state


def without_motion_claims(state: MountState) -> MountState:
    """``state``, claiming no motion (slewing, guiding, tracking) unless connected: nobody
    knows what a mount does while its link is down (issue #11.6)."""
    moving = state.slewing or state.pulse_guiding or state.tracking is not TrackingMode.OFF
    if moving and not state.connected:
        return dataclasses.replace(
            state, slewing=False, pulse_guiding=False, tracking=TrackingMode.OFF
        )
    return state


class StateBroadcast:
    """The latest published state and a way to wait for the next one (latest-only: a slow reader
    skips intermediate states rather than queueing them)."""

    def __init__(self, state: MountState) -> None:
        self.state = state
        self.version = 0
        self._waiters: set[asyncio.Future[None]] = set()

    def publish(self, state: MountState) -> None:
        self.state = state
        self.version += 1
        waiters = self._waiters
        if waiters:  # (no new set per poll while nobody waits)
            self._waiters = set()
            for waiter in waiters:
                if not waiter.done():
                    waiter.set_result(None)

    async def changed_since(self, version: int) -> None:
        """Return once a state newer than ``version`` has been published."""
        while self.version <= version:
            waiter: asyncio.Future[None] = asyncio.get_running_loop().create_future()
            self._waiters.add(waiter)
            try:
                await waiter
            finally:
                self._waiters.discard(waiter)


class StatePoller:
    """Calls ``refresh`` in a background task while :meth:`watching` has at least one user, at
    the rate the poll policy gives (see the module's docstring)."""

    def __init__(
        self,
        refresh: Callable[[], Awaitable[MountState]],
        is_engaged: Callable[[], bool],
        report_problem: Callable[[str], None],
        broadcast: StateBroadcast,
        *,
        interval_s: float,
        retry_s: float,
        max_retry_s: float = MAX_RETRY_S,
        policy: PollPolicy | None = None,
        full_rate_needed: Callable[[], bool] = lambda: True,
        idle_period_s: Callable[[], float] | None = None,
        line_bytes: Callable[[], tuple[int, int]] = lambda: (0, 0),
    ) -> None:
        self._refresh = refresh
        self._is_engaged = is_engaged
        self._report_problem = report_problem
        self._broadcast = broadcast
        self.interval_s = interval_s
        self.retry_s = retry_s
        self.max_retry_s = max_retry_s
        self.policy = policy or PollPolicy()
        self._full_rate_needed = full_rate_needed
        self._idle_period_s = idle_period_s or (lambda: self.policy.idle_poll_s)
        self._line_bytes = line_bytes
        self.failures_in_a_row = 0
        self._watchers = 0
        self._task: asyncio.Task[None] | None = None
        self._refreshing = False
        self._holders = 0
        self._demand_until = -math.inf
        self._wake: asyncio.Event | None = None
        self.polls = 0
        self.failures = 0
        self.line_period_s = 0.0
        """The last poll's bytes on a line of ``policy.max_poll_baud`` (seconds): no poll starts
        sooner than this after the one before."""

    @property
    def watchers(self) -> int:
        return self._watchers

    @property
    def running(self) -> bool:
        return self._task is not None and not self._task.done()

    @property
    def full_rate(self) -> bool:
        """Whether anything needs the full rate now (a holder, recent demand, the mount)."""
        if self._holders > 0 or self._full_rate_needed():
            return True
        try:
            now = asyncio.get_running_loop().time()
        except RuntimeError:
            return False
        return now < self._demand_until

    def demand(self) -> None:
        """A reader wants current readings: full rate for the next ``policy.demand_hold_s``
        (a poller waiting out its idle period polls at once)."""
        try:
            now = asyncio.get_running_loop().time()
        except RuntimeError:  # no loop, so no poller to hurry
            return
        self._demand_until = max(self._demand_until, now + self.policy.demand_hold_s)
        self.wake()

    def wake(self) -> None:
        """Re-judge the rate now (something that needs the full rate has started)."""
        if self._wake is not None:
            self._wake.set()

    @asynccontextmanager
    async def holding_full_rate(self) -> AsyncIterator[None]:
        """Poll at full rate (within the line cap) for the body of the ``async with``; the
        caller must be watching too."""
        self._holders += 1
        self.wake()
        try:
            yield
        finally:
            self._holders -= 1

    @asynccontextmanager
    async def watching(self) -> AsyncIterator[None]:
        """Keep the state fresh for the body of the ``async with``."""
        self._watchers += 1
        if not self.running:
            self._task = asyncio.create_task(self._run(), name="scopelink state poller")
        try:
            yield
        finally:
            self._watchers -= 1
            # A poll in flight is left to finish (the loop then ends by itself): cancelling it
            # mid-exchange would cost the driver a resynchronisation on its next command.
            if self._watchers == 0 and not self._refreshing:
                await self.stop()

    async def stop(self) -> None:
        task, self._task = self._task, None
        if task is not None:
            task.cancel()
            # Wait without awaiting the task itself: its own cancellation is expected, but one of
            # the caller (a shutdown) must go on to the caller, not be swallowed with it.
            await asyncio.wait([task])
            if not task.cancelled():
                task.exception()  # retrieved: the poller logs its own failures

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        self._wake = asyncio.Event()
        last_error = ""
        while self._watchers > 0:
            started = loop.time()
            if not self._is_engaged():
                await self._pause(self.retry_s)
                continue
            self._refreshing = True
            sent, received = self._line_bytes()
            try:
                await self._refresh()
            except asyncio.CancelledError:
                raise
            except Exception as error:  # the poller must outlive any device fault
                self.failures += 1
                self.failures_in_a_row += 1
                message = f"position poll failed: {error}"
                if message != last_error:
                    logger.warning("%s", message)
                last_error = message
                self._report_problem(message)
                if self._watchers > 0:
                    await self._pause(self.backoff_s())
                continue
            finally:
                self._refreshing = False
            last_error = ""
            self.failures_in_a_row = 0
            self.polls += 1
            sent_now, received_now = self._line_bytes()
            moved = max(sent_now - sent, received_now - received, 0)
            # Never longer than the idle period: a reconnect's identification (~100 bytes) must
            # not leave the reading stale before the next poll.
            idle_s = self._idle_period_s()
            self.line_period_s = min(moved / self.policy.max_bytes_per_s, idle_s)
            if self._watchers > 0:
                await self._rest(started, max(self.interval_s, self.line_period_s))

    async def _rest(self, started: float, shortest_s: float) -> None:
        """Wait until the next poll is due: ``shortest_s`` after ``started`` at full rate, the
        idle period after it otherwise (cut short when something needs the full rate)."""
        loop = asyncio.get_running_loop()
        wake = self._wake
        assert wake is not None
        while True:
            wake.clear()
            full = self.full_rate
            period = shortest_s if full else max(shortest_s, self._idle_period_s())
            left = started + period - loop.time()
            if left <= 0.0:
                return
            if full:
                await asyncio.sleep(left)
                return
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(left):
                    await wake.wait()

    def backoff_s(self) -> float:
        """The pause before the next poll after ``failures_in_a_row`` failures: ``retry_s``,
        doubling with each further failure, at most ``max_retry_s``."""
        doublings = min(max(self.failures_in_a_row - 1, 0), 16)
        return min(self.retry_s * 2.0**doublings, max(self.max_retry_s, self.retry_s))

    async def _pause(self, seconds: float) -> None:
        """Wait ``seconds``, or less if a new state (e.g. a reconnect) is published."""
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(seconds):
                await self._broadcast.changed_since(self._broadcast.version)
