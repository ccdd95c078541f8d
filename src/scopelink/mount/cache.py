"""The state cache of a mount: its last published state, kept fresh by a background poller.

Reads come from :attr:`StateCache.state`, which the poller (:mod:`scopelink.mount.polling`)
keeps fresh while anyone is inside :meth:`StateCache.watching` (or iterating
:meth:`StateCache.states`), at the rate the poll policy gives. A driver publishes what it reads
with ``_publish``; a poll that fails publishes the last good reading again with the problem
(``_report_problem``). ``Mount`` builds its checked commands on top.
"""

from __future__ import annotations

import asyncio
import dataclasses
from collections.abc import AsyncGenerator, Callable
from contextlib import AbstractAsyncContextManager, aclosing
from datetime import datetime

from scopelink.mount.device import MountDevice
from scopelink.mount.errors import InvalidValueError
from scopelink.mount.polling import (
    DEFAULT_STALE_AFTER_S,
    PollPolicy,
    StateBroadcast,
    StatePoller,
    check_stale_after,
    require_fresh,
    without_motion_claims,
)
from scopelink.mount.types import MountState

__all__ = ["StateCache"]


class StateCache(MountDevice):
    """The last known state of a device, and the poller that keeps it fresh.

    ``poll_interval_s`` is the shortest time between two polls: 0 for a device on a wire (the
    line cap paces it), more for mounts whose refresh costs only CPU (which poll at that rate
    whenever watched: there is no line to spare).
    """

    poll_interval_s: float = 0.0
    poll_retry_s: float = 1.0
    refresh_uses_wire: bool = True
    """Whether :meth:`refresh` costs a round trip to a device (front ends then answer from
    :attr:`state` while the poller runs, instead of refreshing per request)."""

    def __init__(self, *, clock: Callable[[], datetime]) -> None:
        self._clock = clock
        self._broadcast = StateBroadcast(MountState(read_at=clock()))
        self._stale_after_s = DEFAULT_STALE_AFTER_S
        self._poller = StatePoller(
            self.refresh,
            lambda: self.engaged,
            self._report_problem,
            self._broadcast,
            interval_s=self.poll_interval_s,
            retry_s=self.poll_retry_s,
            full_rate_needed=self._full_rate_needed,
            idle_period_s=lambda: self._poller.policy.idle_period_s(self._stale_after_s),
            line_bytes=self._line_bytes,
        )

    def now(self) -> datetime:
        """The mount's notion of the current UTC time (a simulated mount may run its own clock)."""
        return self._clock()

    @property
    def state(self) -> MountState:
        """The last known state, without waiting on the wire."""
        return self._broadcast.state

    def _publish(self, state: MountState) -> None:
        """Make ``state`` the current one (claiming no motion while not connected)."""
        if not state.connected:
            state = without_motion_claims(state)
        self._broadcast.publish(state)

    def _report_problem(self, problem: str) -> None:
        """Publish the last good reading again, with ``problem`` saying why it is not fresh
        (and the driver's standing problems, e.g. an unconfirmed stop, after it)."""
        standing = tuple(p for p in self._standing_problems() if p != problem)
        self._publish(dataclasses.replace(self.state, problems=(problem, *standing)))

    def _standing_problems(self) -> tuple[str, ...]:
        """Problems that outlast a failed poll (none by default)."""
        return ()

    # --- the state cache ------------------------------------------------------------------------

    @property
    def stale_after_s(self) -> float:
        """An older reading (seconds) is not served as current (0.2-5 s, default 2 s)."""
        return self._stale_after_s

    @stale_after_s.setter
    def stale_after_s(self, seconds: float) -> None:
        self._stale_after_s = check_stale_after(seconds)

    @property
    def engaged(self) -> bool:
        """Connected, or a driver's link lost since (its poller reopens it) until disconnect."""
        return self.state.connected

    def fresh_state(self, *, position: bool = True) -> MountState:
        """The cache if it may be served as current, else the error saying why (see
        :func:`~scopelink.mount.polling.require_fresh`); ``position``: judge its age.
        A reader: the poller runs at full rate for the next ``poll_policy.demand_hold_s``."""
        self._poller.demand()
        name = self.identity.model or "the mount"
        return require_fresh(self.state, self._stale_after_s, position=position, name=name)

    async def current_state(self, *, position: bool = True) -> MountState:
        """A fresh state at the lowest cost: the cache while the poller keeps it fresh over a
        wire (as :meth:`fresh_state` allows), else a refresh (exact, for a simulated mount)."""
        if self.refresh_uses_wire and self._poller.running and self.engaged:
            return self.fresh_state(position=position)
        return await self.refresh()

    def watching(self) -> AbstractAsyncContextManager[None]:
        """Keep :attr:`state` fresh inside ``async with``: polled at the rate the poll policy
        gives (idle unless a reader, a slew or the guard needs more)."""
        return self._poller.watching()

    @property
    def poll_policy(self) -> PollPolicy:
        """How often the poller polls: idle period, how long a read raises the rate, the line
        cap (see :mod:`scopelink.mount.polling` and docs/mount-api.md)."""
        return self._poller.policy

    @poll_policy.setter
    def poll_policy(self, policy: PollPolicy) -> None:
        if not isinstance(policy, PollPolicy):
            raise InvalidValueError(f"a poll policy is a PollPolicy, not {policy!r}")
        self._poller.policy = policy
        self._poller.wake()

    def _full_rate_needed(self) -> bool:
        """Whether the mount itself needs full-rate polls: it slews (a goto, a park, a rate
        motion, an unconfirmed stop), guides, or is on its way to park; always for a mount
        whose refresh costs no wire (its ``poll_interval_s`` paces it). Here: slews or guides
        (``Mount`` adds parking and rate motions)."""
        if not self.refresh_uses_wire:
            return True
        return self.state.slewing or self.state.pulse_guiding

    def _line_bytes(self) -> tuple[int, int]:
        """Bytes (sent, received) on the link so far: the poller keeps each poll's within the
        line cap. (0, 0) where nothing is counted."""
        return (0, 0)

    def _motion_commanded(self) -> None:
        """A command that moves the mount goes out (called before it is sent, so one that fails
        half-way is watched too): poll at full rate from now (its slewing state then keeps the
        rate up) rather than at the end of an idle period."""
        self._poller.demand()

    @property
    def poller(self) -> StatePoller:
        """The background poller (its counters and watchers, for health displays)."""
        return self._poller

    async def states(self) -> AsyncGenerator[MountState, None]:
        """Each newly published state, starting with the current one; watches while iterating.
        A slow consumer skips states rather than queueing them."""
        async with self.watching(), self._poller.holding_full_rate():
            version = self._broadcast.version
            yield self.state
            while True:
                await self._broadcast.changed_since(version)
                version = self._broadcast.version
                yield self.state

    async def wait_for(
        self, predicate: Callable[[MountState], bool], timeout_s: float | None = None
    ) -> MountState:
        """The first state (current or later) satisfying ``predicate``; ``TimeoutError`` after
        ``timeout_s`` seconds."""
        async with asyncio.timeout(timeout_s), aclosing(self.states()) as states:
            async for state in states:
                if predicate(state):
                    return state
        raise AssertionError("unreachable: states() never ends")  # pragma: no cover
