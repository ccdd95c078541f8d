"""The state cache behind every front end: one poller per mount, running while anyone watches.

Front ends never wait on the wire to answer a read: they take :attr:`Mount.state`, which this
poller keeps fresh by calling ``refresh()`` back to back (no faster than ``interval_s``) for as long
as at least one watcher is registered. A failed poll keeps the last good reading, names the cause
in ``problems`` and is retried after ``retry_s``; the poller itself never dies of a device error.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager

from scopelink.mount.types import MountState

__all__ = ["StateBroadcast", "StatePoller"]

logger = logging.getLogger(__name__)


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
        waiters, self._waiters = self._waiters, set()
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
    """Calls ``refresh`` in a background task while :meth:`watching` has at least one user."""

    def __init__(
        self,
        refresh: Callable[[], Awaitable[MountState]],
        is_connected: Callable[[], bool],
        report_problem: Callable[[str], None],
        broadcast: StateBroadcast,
        *,
        interval_s: float,
        retry_s: float,
    ) -> None:
        self._refresh = refresh
        self._is_connected = is_connected
        self._report_problem = report_problem
        self._broadcast = broadcast
        self.interval_s = interval_s
        self.retry_s = retry_s
        self._watchers = 0
        self._task: asyncio.Task[None] | None = None
        self._refreshing = False
        self.polls = 0
        self.failures = 0

    @property
    def watchers(self) -> int:
        return self._watchers

    @property
    def running(self) -> bool:
        return self._task is not None and not self._task.done()

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
            with contextlib.suppress(asyncio.CancelledError):
                await task

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        last_error = ""
        while self._watchers > 0:
            started = loop.time()
            if not self._is_connected():
                await self._pause(self.retry_s)
                continue
            self._refreshing = True
            try:
                await self._refresh()
            except asyncio.CancelledError:
                raise
            except Exception as error:  # the poller must outlive any device fault
                self.failures += 1
                message = f"position poll failed: {error}"
                if message != last_error:
                    logger.warning("%s", message)
                last_error = message
                self._report_problem(message)
                if self._watchers > 0:
                    await self._pause(self.retry_s)
                continue
            finally:
                self._refreshing = False
            last_error = ""
            self.polls += 1
            if self._watchers > 0:
                await asyncio.sleep(max(0.0, self.interval_s - (loop.time() - started)))

    async def _pause(self, seconds: float) -> None:
        """Wait ``seconds``, or less if a new state (e.g. a reconnect) is published."""
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(seconds):
                await self._broadcast.changed_since(self._broadcast.version)
