"""What stops tracking at the meridian limit of a German mount, or flips (issue #15 part 3).

The judgement is :mod:`scopelink.mount.meridian`'s; this module runs it while the mount tracks
and acts: tracking off (the horizon guard's stop, repeated until confirmed), then, with
``limits.auto_flip``, a goto to the same position through the checked ``Mount.goto_equatorial``.
Decisions: ``docs/meridian.md``.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import time
from collections.abc import Callable
from typing import Protocol

from scopelink.astro import PierSide
from scopelink.mount.errors import LimitError, MountError
from scopelink.mount.guard import stop_until_confirmed
from scopelink.mount.guarded import GuardedMount, GuardSettings
from scopelink.mount.meridian import (
    SIDE_NAMES,
    MeridianStatus,
    applies,
    meridian_status,
    setting_of,
)
from scopelink.mount.types import MountState, TrackingMode

__all__ = ["FLIP_TIMEOUT_S", "MeridianMount", "MeridianWatch"]

logger = logging.getLogger(__name__)

_NOT_TRACKING = TrackingMode.OFF
"""Looked up once: an enum member's look-up costs ~80 ns on Python 3.11, and every published
state is checked against it."""

FLIP_TIMEOUT_S = 600.0
"""Longest (real) wait for an automatic flip's slew to land before it counts as failed."""
_CHECK_S = 0.25
"""The watch computes the hour angle this often (real seconds; astrometry only, no exchange)."""
_LEAD_S = 0.5
"""The watch acts this long (real seconds at the measured clock rate) before the limit: its own
check period plus the time a stop takes to reach the device."""

_MOVED_BACK_HOURS = 0.01
"""How far (hour angle, 9′) the tube must be moved back east from where tracking was stopped at
the limit before tracking may start again there."""
_SETTLE_WAIT_S = 2.0
"""How long (real) the watch waits at a time for a reading of the tube at rest after a goto."""


class MeridianMount(GuardedMount, Protocol):
    """What the watch needs of a mount besides the guard's view: the checked goto of a flip."""

    async def goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None: ...

    async def wait_for_slew(self, timeout_s: float | None = None) -> MountState: ...


class MeridianWatch:
    """Stops tracking at the meridian limit, or flips (``limits.auto_flip``).

    Like the horizon guard's far watch it needs no exchange with the device: tracking holds RA,
    so the hour angle follows from the last reading and the clock, checked every 0.25 s (real).
    It acts half a second (real, at the measured rate of the mount's clock) before the limit.
    It runs on every German mount, the simulator included: the limit is the user's, not the
    device's own mechanical one.
    """

    def __init__(
        self, mount: MeridianMount, settings: GuardSettings, *, show_notice: Callable[[], None]
    ) -> None:
        self._mount = mount
        self._settings = settings
        self._show_notice = show_notice
        self._task: asyncio.Task[None] | None = None
        self.notice = ""
        """Why tracking was last stopped at the meridian (shown in ``state.problems``)."""
        self.stops = 0
        self.flips = 0
        self._fresh_after = mount.now()
        self.leaving: PierSide | None = None
        """The side an automatic flip under way leaves (a goto then never lands on it)."""
        self._stopped: tuple[PierSide, float] | None = None
        """The side and hour angle where the watch last stopped tracking at the limit."""
        """The side an automatic flip under way leaves (a goto then never lands on it)."""

    def observe(self, state: MountState) -> None:
        """Called with every published state: start watching when tracking is seen."""
        if self._needed(state):
            self._wake()

    def annotate(self, state: MountState) -> MountState:
        """``state`` with the last meridian stop among its problems."""
        if self.notice and self.notice not in state.problems:
            return _with_problem(state, self.notice)
        return state

    def command_accepted(self) -> None:
        """A new goto or tracking command supersedes the last stop's notice; readings from
        before it (or of the slew) say nothing about where tracking now carries the tube."""
        self.notice = ""
        self._fresh_after = self._mount.now()

    def goto_started(self) -> None:
        """A goto moves the tube away from where tracking was stopped."""
        self.command_accepted()
        self._stopped = None

    def check_tracking(self, state: MountState) -> None:
        """Refuse to start tracking that would carry the tube further past the west limit, or
        from where the watch stopped it at the limit (until a goto or a motion moves it back)."""
        status = meridian_status(self._mount, _tracking(state))
        if status is None:
            return
        stopped = self._stopped
        at_stop = (
            stopped is not None
            and status.side is stopped[0]
            and status.hour_angle_hours > stopped[1] - _MOVED_BACK_HOURS
        )
        if status.minutes_left == 0.0 or at_stop:
            raise LimitError(
                f"the tube is {status.past_deg:.1f}° past the meridian on the west side of the "
                f"pier, at limits.meridian_west_deg ({status.limit_deg:g}°): tracking would carry "
                "it into the pier; nothing was sent (goto the target again: it lands on the "
                "east side)"
            )

    def _needed(self, state: MountState) -> bool:
        return (
            state.connected
            and state.tracking is not _NOT_TRACKING
            and applies(self._mount.capabilities)
        )

    def _wake(self) -> None:
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:  # published outside a loop (a test setting state up)
            return
        task = self._task
        if task is not None and not task.done() and task.get_loop() is loop:
            return
        self._task = loop.create_task(self._run(), name="scopelink meridian watch")

    async def _run(self) -> None:
        mount = self._mount
        rate = 1.0  # mount seconds per real second, measured between checks
        last: tuple[float, float] | None = None
        while self._needed(mount.state):
            try:
                real, clock = time.monotonic(), mount.now().timestamp()
                if last is not None and real - last[0] > 0.05:
                    rate = max((clock - last[1]) / (real - last[0]), 0.0)
                last = (real, clock)
                state = await self._settled_state()
                _raise_if_cancelled()
                if state is None:
                    continue
                status = meridian_status(mount, state)
                left = None if status is None else status.minutes_left
                if status is not None and left is not None and left * 60.0 <= rate * _LEAD_S:
                    await self._at_limit(state, status)
                    last = None
                    continue
            except asyncio.CancelledError:
                raise
            except Exception:  # never leave tracking unwatched because of one bug
                logger.exception("the meridian watch failed; watching again")
            _raise_if_cancelled()
            await asyncio.sleep(_CHECK_S)

    async def _settled_state(self) -> MountState | None:
        """The last reading if it shows the tube tracking after the last goto's slew; else the
        next such reading (the poller runs meanwhile), or None after a while (to look again)."""
        state = self._mount.state
        if not state.slewing and state.read_at >= self._fresh_after:
            return state
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(_SETTLE_WAIT_S):
                async with contextlib.aclosing(self._mount.states()) as states:
                    async for state in states:
                        if not self._needed(state):
                            return None
                        if not state.slewing and state.read_at >= self._fresh_after:
                            return state
        return None

    async def _at_limit(self, state: MountState, status: MeridianStatus) -> None:
        side = SIDE_NAMES[status.side]
        reason = (
            f"tracking was stopped {status.past_deg:.1f}° past the meridian on the {side} side "
            f"of the pier: the meridian limit ({setting_of(status.side)} {status.limit_deg:g}°)"
        )
        self._stopped = (status.side, status.hour_angle_hours)
        await self._stop(reason)
        if not self._mount.limits.auto_flip:
            return
        ra, dec = state.ra_j2000_hours, state.dec_j2000_deg
        if ra is None or dec is None:
            return
        try:
            self.leaving = status.side
            try:
                await self._mount.goto_equatorial(ra, dec)
            finally:
                self.leaving = None
            landed = await self._mount.wait_for_slew(timeout_s=FLIP_TIMEOUT_S)
        except (MountError, TimeoutError) as error:
            why = str(error) or f"it did not land within {FLIP_TIMEOUT_S:g} s"
            await self._stop(f"{reason}; the automatic flip failed ({why}), tracking is off")
            return
        if landed.pier_side is status.side or landed.tracking is TrackingMode.OFF:
            await self._stop(
                f"{reason}; the automatic flip failed (the mount is on the "
                f"{SIDE_NAMES[landed.pier_side]} side of the pier, tracking "
                f"{landed.tracking.value}), tracking is off"
            )
            return
        self.flips += 1
        self.notice = ""
        logger.warning("meridian flip: now on the %s side", SIDE_NAMES[landed.pier_side])
        self._show_notice()

    async def _stop(self, reason: str) -> None:
        """Turn tracking off, repeated until the device confirms (the guard's stop)."""
        logger.warning("%s", reason)
        self.notice = reason
        self.stops += 1

        async def stop() -> None:
            await self._mount.set_tracking(TrackingMode.OFF)

        def tell(notice: str) -> None:
            self.notice = notice

        await stop_until_confirmed(
            self._mount, self._settings, stop, reason, tell=tell, show_notice=self._show_notice
        )
        self._show_notice()


def _raise_if_cancelled() -> None:
    """End the watch if it was cancelled while inside ``states()``: leaving it stops the poller,
    which swallows a cancellation that arrives meanwhile (``Poller.stop`` suppresses
    ``CancelledError`` while it awaits the poll task)."""
    task = asyncio.current_task()
    if task is not None and task.cancelling():
        raise asyncio.CancelledError


def _tracking(state: MountState) -> MountState:
    """``state`` as if tracking (to judge where tracking would carry it from now)."""
    if state.tracking is not TrackingMode.OFF:
        return state
    return dataclasses.replace(state, tracking=TrackingMode.SIDEREAL)


def _with_problem(state: MountState, problem: str) -> MountState:
    return dataclasses.replace(state, problems=(*state.problems, problem))
