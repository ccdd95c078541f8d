"""Taking turns on a wire: one exchange at a time, user commands before background polls.

A serial line carries one command and its reply at a time. The state poller keeps the line busy
while anyone watches, so a user's goto or abort must not queue behind a backlog of polls: waiting
commands are granted the line before waiting polls, and within one priority the order is
first come, first served.
"""

from __future__ import annotations

import asyncio
import enum
import heapq
import itertools
from types import TracebackType

__all__ = ["Priority", "WireScheduler"]


class Priority(enum.IntEnum):
    """Lower values are served first."""

    COMMAND = 0
    POLL = 1


class WireScheduler:
    """Grants the wire to one holder at a time, by priority, then arrival order."""

    def __init__(self) -> None:
        self._busy = False
        self._waiting: list[tuple[int, int, asyncio.Future[None]]] = []
        """Waiters by priority and arrival; never non-empty while the wire is free (whoever
        releases it hands it to the first waiter still waiting)."""
        self._arrivals = itertools.count()

    @property
    def busy(self) -> bool:
        """Whether someone holds the wire now."""
        return self._busy

    def waiting(self, priority: Priority | None = None) -> int:
        """How many are queued (at ``priority``, or in all)."""
        return sum(
            1
            for level, _, future in self._waiting
            if not future.done() and (priority is None or level == priority)
        )

    def turn(self, priority: Priority) -> _Turn:
        """Hold the wire for the body of the ``async with``; cancelled waiters leave the queue."""
        return _Turn(self, priority)

    def try_take(self) -> bool:
        """Take the wire now if it is free and nobody waits (then :meth:`release` it); False
        otherwise. The queue-less turn of an uncontended wire, without an ``await``."""
        if self._busy:  # nobody waits for a free wire (see _waiting)
            return False
        self._busy = True
        return True

    def try_take_with(self, inner: WireScheduler) -> bool:
        """Take this wire and ``inner`` (a lock its holders take inside their turn, such as a
        driver's link) now if both are free (then :meth:`release_with` them); False otherwise,
        having taken neither. The uncontended turn of the common case in one call (issue #14:
        CPU per command)."""
        if self._busy or inner._busy:  # nobody waits for a free one (see _waiting)
            return False
        self._busy = inner._busy = True
        return True

    def release_with(self, inner: WireScheduler) -> None:
        """Pass ``inner`` on, then this wire (after :meth:`try_take_with`)."""
        inner.release()
        self.release()

    async def take(self, priority: Priority) -> None:
        """Wait for the wire (then :meth:`release` it); a cancelled wait leaves the queue."""
        if not self.try_take():
            await self._acquire(priority)

    def release(self) -> None:
        """Pass the wire on (after :meth:`try_take` or :meth:`take`)."""
        if self._waiting:
            self._release()
        else:  # nobody waits (the common case): one attribute, no loop
            self._busy = False

    async def _acquire(self, priority: Priority) -> None:
        if not self._busy:
            self._busy = True
            return
        future: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        heapq.heappush(self._waiting, (int(priority), next(self._arrivals), future))
        try:
            await future
        except asyncio.CancelledError:
            if future.done() and not future.cancelled():
                # Granted and cancelled in the same step: pass the turn on.
                self._release()
            raise

    def _release(self) -> None:
        while self._waiting:
            _, _, future = heapq.heappop(self._waiting)
            if not future.done():
                future.set_result(None)  # the wire passes directly to this waiter
                return
        self._busy = False


class _Turn:
    """``async with scheduler.turn(priority)`` (a class, not a generator: it runs per command)."""

    __slots__ = ("_priority", "_scheduler")

    def __init__(self, scheduler: WireScheduler, priority: Priority) -> None:
        self._scheduler = scheduler
        self._priority = priority

    async def __aenter__(self) -> None:
        await self._scheduler.take(self._priority)

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self._scheduler._release()
