"""What keeps a real mount inside its limits after a command was accepted.

``Mount.goto_*`` check the target before anything reaches the link, but a rate motion
(``move_axis``) or tracking has no end point to check: on a device that does not stop itself at
the horizon (a SynScan hand control, a Sky Tracker), they would carry the tube below the horizon or
past the altitude limit. :class:`HorizonGuard` watches the state while either runs (it holds the
state poller), predicts from the observed altitude rate where the mount will be once a stop could
take effect, and stops it before the limit:

- a rate motion heading out is aborted (``Mount.abort``: tracking carries on where the protocol
  lets it, as after any stop);
- tracking that carries the mount out (a setting star) is turned off, as OnStep and the
  simulator do: a tracking mount that keeps going drives into the ground.

A motion that starts at or beyond a limit and heads further out is refused where its direction can
be told (an alt-az mount's altitude axis; an equatorial mount's axes from hemisphere, pier side and
astrometry); elsewhere the guard stops it at the first readings.
Why the mount stopped is logged and shown in ``MountState.problems`` until the next motion command.

The guard sees the mount only through :class:`~scopelink.mount.guarded.GuardedMount`; what it
judges is :mod:`scopelink.mount.danger`'s (the readings) and :mod:`scopelink.mount.budget`'s (the
travel it cannot see). Who owns a rate motion is recorded here for the dead-man
(:mod:`scopelink.mount.deadman`). Decisions and measured margins are in
``docs/reliability-safety.md``.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import statistics
from collections import deque
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import aclosing, asynccontextmanager
from dataclasses import dataclass
from datetime import datetime

from scopelink.mount.budget import Base, Reading, Unseen, base_from, blind_danger, make_base
from scopelink.mount.danger import altitude_direction, check_move, near_limit, reading_danger
from scopelink.mount.deadman import MotionClient, current_client
from scopelink.mount.errors import DeviceError, LimitError, MountError, NotConnectedError
from scopelink.mount.guarded import GuardedMount, GuardSettings
from scopelink.mount.types import MountAxis, MountState, TrackingMode

__all__ = ["HorizonGuard", "stop_until_confirmed"]

logger = logging.getLogger(__name__)

_NOT_TRACKING = TrackingMode.OFF
"""Looked up once: an enum member's look-up costs ~80 ns on Python 3.11, and every published
state is checked against it."""


@dataclass(frozen=True, slots=True)
class _RateMotion:
    rate_deg_s: float
    owner: MotionClient | None
    since: datetime | None = None
    """Mount clock when its command was about to leave (the device may move from then on)."""
    speed_deg_s: float = 0.0
    """The speed the blind budget assumes: this rate's, or the one it replaced, if faster."""


_LATE_ANSWER_S = 0.1
"""A rate motion's command unanswered this long (a resynchronisation, a timeout) is watched
without waiting for its answer: the axis may be turning."""
_INTERVALS = 8
"""Poll intervals whose median is the typical poll period."""
_REPEAT_PAUSE_S = 0.2
"""Pause before sending again a stop that failed at once (a closed port, a refused reopen)."""


class HorizonGuard:
    """Stops rate motions and tracking before they cross the limits of ``mount``;
    ``show_notice`` publishes the state again, so a new :attr:`notice` is seen at once."""

    def __init__(
        self,
        mount: GuardedMount,
        settings: GuardSettings | None = None,
        *,
        show_notice: Callable[[], None],
    ) -> None:
        self._mount = mount
        self.settings = settings or GuardSettings()
        self._show_notice = show_notice
        self._motions: dict[MountAxis, _RateMotion] = {}
        self._task: asyncio.Task[None] | None = None
        self._poke: asyncio.Event | None = None
        """Set by a new rate motion while the guard waits far from the limits."""
        self.notice = ""
        """Why the guard last stopped the mount ("" once a new motion command was accepted)."""
        self.stops = 0
        """How many times the guard stopped a motion (for health displays and tests)."""

    # --- what is moving, and for whom -------------------------------------------------------------

    @property
    def enabled(self) -> bool:
        return not self._mount.stops_itself_at_limits

    @property
    def running(self) -> bool:
        return self._task is not None and not self._task.done()

    @property
    def rate_motions(self) -> dict[MountAxis, float]:
        """The rate motions commanded through ``move_axis`` and not stopped since."""
        return {axis: motion.rate_deg_s for axis, motion in self._motions.items()}

    def axes_of(self, client: MotionClient) -> list[MountAxis]:
        """The axes whose rate motion ``client`` started and nobody has changed since."""
        return [axis for axis, motion in self._motions.items() if motion.owner is client]

    def check_move(self, axis: MountAxis, rate_deg_s: float, state: MountState) -> None:
        """Refuse a rate motion that starts at or beyond a limit and heads further out, where
        the direction is known (see :func:`scopelink.mount.danger.check_move`)."""
        check_move(self._mount, self.settings, axis, rate_deg_s, state)

    async def check_move_now(self, axis: MountAxis, rate_deg_s: float) -> None:
        """:meth:`check_move` on the mount's cached state; a refusal stands only on a fresh
        reading (the cache may be old: the mount may have moved back inside since)."""
        try:
            self.check_move(axis, rate_deg_s, self._mount.state)
        except LimitError:
            self.check_move(axis, rate_deg_s, await self._mount.refresh())

    def altitude_direction(
        self, axis: MountAxis, rate_deg_s: float, state: MountState
    ) -> float | None:
        """Whether turning ``axis`` at ``rate_deg_s`` raises (+1) or lowers (-1) the tube now;
        None where that cannot be told (:func:`scopelink.mount.danger.altitude_direction`)."""
        return altitude_direction(self._mount, axis, rate_deg_s, state)

    @asynccontextmanager
    async def starting(self, axis: MountAxis, rate_deg_s: float) -> AsyncIterator[None]:
        """Around the command that starts a rate motion: the motion is watched from before its
        command leaves (a reply that takes a resynchronisation may come seconds after the axis
        started to turn). If the command fails before reaching the device (refused, not
        supported) the previous motion stands again; after a DeviceError, or if the caller gives
        up, the device may be moving: the motion stays watched until a stop is confirmed."""
        if rate_deg_s == 0.0 or not self.enabled:
            yield
            self.motion_commanded(axis, rate_deg_s)
            return
        previous = self._motions.get(axis)
        speed = abs(rate_deg_s)
        if previous is not None:
            speed = max(speed, previous.speed_deg_s)
        self._motions[axis] = _RateMotion(
            rate_deg_s, current_client(), previous.since if previous else self._mount.now(), speed
        )
        # Watching begins with the answer, as before, unless the answer is late: polls started
        # with the command would only compete with it for the wire.
        late = asyncio.get_running_loop().call_later(_LATE_ANSWER_S, self._watch_now)
        try:
            yield
        except MountError as error:
            if isinstance(error, DeviceError):
                self._watch_now()  # it may be turning
            elif previous is None:  # nothing reached the device
                self._motions.pop(axis, None)
            else:
                self._motions[axis] = previous
            raise
        except BaseException:
            self._watch_now()  # given up (cancelled) on the way: it may be turning
            raise
        finally:
            late.cancel()
        self.motion_commanded(axis, rate_deg_s)

    def _watch_now(self) -> None:
        if self._poke is not None:
            self._poke.set()
        self._wake()

    def motion_commanded(self, axis: MountAxis, rate_deg_s: float) -> None:
        """``move_axis`` reached the device: remember the motion and its owner, and watch it."""
        if rate_deg_s == 0.0:
            self._motions.pop(axis, None)
            return
        started = self._motions.get(axis)
        since = started.since if started is not None else None
        self._motions[axis] = _RateMotion(
            rate_deg_s, current_client(), since or self._mount.now(), abs(rate_deg_s)
        )
        self.notice = ""
        if self._poke is not None:
            self._poke.set()
        self._wake()

    def motions_stopped(self) -> None:
        """Every rate motion ended (abort, a goto taking over, park, disconnect)."""
        self._motions.clear()

    def goto_started(self) -> None:
        """A goto takes over from manual motion, and supersedes the last stop's notice."""
        self.motions_stopped()
        self.command_accepted()

    def command_accepted(self) -> None:
        """A new motion command (goto, tracking on) supersedes the last stop's notice."""
        self.notice = ""

    # --- the horizon guard --------------------------------------------------------------------

    def observe(self, state: MountState) -> None:
        """Called with every published state: start guarding when tracking is seen."""
        if not state.connected:
            self._motions.clear()
            return
        if state.tracking is not _NOT_TRACKING:
            self._wake()

    def annotate(self, state: MountState) -> MountState:
        """``state`` with the last stop's reason among its problems."""
        if self.notice and self.notice not in state.problems:
            return dataclasses.replace(state, problems=(*state.problems, self.notice))
        return state

    def _needed(self, state: MountState) -> bool:
        return state.connected and (bool(self._motions) or state.tracking is not _NOT_TRACKING)

    def _wake(self) -> None:
        if not self.enabled:
            return
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:  # published outside a loop (a test setting state up): nothing moves
            return
        if self.running and self._task is not None and self._task.get_loop() is loop:
            return
        # (A task left pending in a loop that has since closed never finishes: start afresh.)
        self._task = loop.create_task(self._run(), name="scopelink horizon guard")

    async def close(self) -> None:
        task, self._task = self._task, None
        if task is not None:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task

    async def _run(self) -> None:
        while self._needed(self._mount.state):
            try:
                if self._motions or self._near_limit(self._mount.state):
                    await self._watch_closely()
                else:
                    await self._wait_while_far()
            except asyncio.CancelledError:
                raise
            except Exception:
                # Never take the event loop down, and never stop watching while a motion or
                # tracking needs it: a bug met once (in a driver, say) must not leave it unwatched.
                logger.exception("the horizon guard failed; watching again")
                await asyncio.sleep(_REPEAT_PAUSE_S)

    async def _wait_while_far(self) -> None:
        """Tracking far from every limit: check the tracked altitude a few times a second, with
        no exchange with the device, until it comes near a limit or a rate motion starts."""
        poke = self._poke = asyncio.Event()  # created here: bound to the running loop
        try:
            while not self._motions and self._needed(self._mount.state):
                if self._near_limit(self._mount.state):
                    return
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(self.settings.far_check_s):
                        await poke.wait()
                poke.clear()
        finally:
            self._poke = None

    async def _watch_closely(self) -> None:
        """Keep the poller running and judge every new reading until the mount is far from the
        limits again with no rate motion; between readings, stop the mount before the travel
        it could have made unseen (the blind budget) could reach a limit."""
        mount = self._mount
        previous: Reading | None = None
        intervals: deque[float] = deque(maxlen=_INTERVALS)
        origin = mount.now()
        # A reading from before the watch (the cache may be minutes old) would spoil both the
        # rate and the poll period: judge from fresh readings only.
        ignore_until_s = 0.0
        plausible_deg_s = 2.0 * mount.capabilities.max_axis_rate_deg_s + 1.0
        base: Base | None = None
        """The last good reading: where the blind budget starts from."""
        async with aclosing(mount.states()) as states:
            upcoming: asyncio.Task[MountState] | None = None
            try:
                while True:
                    if upcoming is None:
                        upcoming = asyncio.ensure_future(_next_state(states))
                    done, _ = await asyncio.wait({upcoming}, timeout=self.settings.blind_check_s)
                    if not done:
                        state = mount.state
                        if not self._needed(state):
                            return
                        if base is None or base.rates != self.rate_motions:
                            # No good reading since the watch (or the last stop) began, or the
                            # motions changed since: the budget starts from what is known.
                            base = base_from(self._mount, self.rate_motions, state, origin, base)
                            if base is None:
                                continue
                        now_s = (mount.now() - origin).total_seconds()
                        reason = self._blind_danger(base, now_s, origin, state)
                        if reason is not None:
                            await self._stop(state, reason)
                            ignore_until_s = (mount.now() - origin).total_seconds()
                            previous = base = None
                        continue
                    state = upcoming.result()
                    upcoming = None
                    if not self._needed(state):
                        return
                    if not self._motions and not self._near_limit(state, factor=2.0):
                        return
                    if state.alt_deg is None or state.az_deg is None:
                        continue
                    reading = Reading(
                        (state.read_at - origin).total_seconds(), state.alt_deg, state.az_deg
                    )
                    if self._motions and base is not None and reading.same_place(base.reading):
                        # Not a new reading but the last one published again with a new time (a
                        # poll that read the status only, a command's state): a turning axis
                        # moves every good reading.
                        continue
                    if previous is None or reading.at_s <= previous.at_s:
                        if base is None or reading.at_s > base.reading.at_s:
                            base = make_base(self._mount, self.rate_motions, reading, state)
                        if reading.at_s > ignore_until_s:
                            previous = previous or reading
                        continue
                    elapsed = reading.at_s - previous.at_s
                    if abs(reading.alt_deg - previous.alt_deg) > plausible_deg_s * elapsed:
                        previous = reading  # a garbled reading or a jump: judge from the next one
                        continue
                    base = make_base(self._mount, self.rate_motions, reading, state)
                    if reading.at_s <= ignore_until_s:
                        previous = None
                        continue
                    # The typical poll period: a gap (a reply lost) is the blind budget's part.
                    intervals.append(elapsed)
                    period_s = statistics.median(intervals)
                    readings = (previous, reading)
                    reason = reading_danger(
                        mount,
                        self.settings,
                        self.rate_motions,
                        readings,
                        period_s=period_s,
                        state=state,
                    )
                    previous = reading
                    if reason is None:
                        reason = self._blind_danger(base, reading.at_s, origin, state)
                    if reason is None:
                        continue
                    await self._stop(state, reason)
                    # Readings until the stop has taken effect still show the braking motion.
                    ignore_until_s = (mount.now() - origin).total_seconds() + period_s
                    previous = base = None
            finally:
                if upcoming is not None:
                    upcoming.cancel()
                    with contextlib.suppress(asyncio.CancelledError, StopAsyncIteration):
                        await upcoming

    def _near_limit(self, state: MountState, *, factor: float = 1.0) -> bool:
        return near_limit(self._mount, self.settings, state, factor=factor)

    def _blind_danger(
        self, base: Base, now_s: float, origin: datetime, state: MountState
    ) -> str | None:
        """Why the mount must stop now because of what it may have done unseen since ``base``
        (mount-clock seconds since ``origin``), or None: see
        :func:`scopelink.mount.budget.blind_danger`."""
        motions = [
            Unseen(axis, motion.speed_deg_s, self._moving_s(motion, base.reading, now_s, origin))
            for axis, motion in self._motions.items()
        ]
        return blind_danger(self._mount, self.settings, motions, base, now_s=now_s, state=state)

    def _moving_s(
        self, motion: _RateMotion, reading: Reading, now_s: float, origin: datetime
    ) -> float:
        """How long ``motion`` may have turned unseen: since ``reading`` (or its command, if
        later) until the stop takes effect."""
        since_s = reading.at_s
        if motion.since is not None:
            since_s = max(since_s, (motion.since - origin).total_seconds())
        return max(now_s - since_s, 0.0) + self.settings.stop_latency_s

    async def _stop(self, state: MountState, reason: str) -> None:
        """Stop the mount, and repeat the stop until the device has confirmed it (or the mount
        is no longer connected): a lost or garbled reply must not leave it running."""
        logger.warning("%s", reason)
        self.notice = reason
        self.stops += 1

        async def stop() -> None:
            if self._motions:
                await self._mount.abort()
            elif state.tracking is not TrackingMode.OFF:
                await self._mount.set_tracking(TrackingMode.OFF)

        def tell(notice: str) -> None:
            self.notice = notice

        await stop_until_confirmed(
            self._mount, self.settings, stop, reason, tell=tell, show_notice=self._show_notice
        )
        self._show_notice()  # now, not at the next poll


async def stop_until_confirmed(
    mount: GuardedMount,
    settings: GuardSettings,
    stop: Callable[[], Awaitable[None]],
    reason: str,
    *,
    tell: Callable[[str], None],
    show_notice: Callable[[], None],
) -> None:
    """Run ``stop`` until it returns (the device confirmed it) within ``confirm_s``, the wait
    doubling up to ``confirm_max_s``; give up only when the mount is no longer connected.
    ``tell`` gets the notice to show meanwhile (``show_notice`` shows it)."""
    wait_s = settings.confirm_s
    while True:
        try:
            async with asyncio.timeout(wait_s):
                await stop()
            tell(reason)
            return
        except NotConnectedError as error:
            tell(f"{reason}; stopping it FAILED: {error}")
            logger.error("the horizon guard could not stop the mount: %s", error)
            return
        except Exception as error:  # a driver's bug must not end the stopping either
            if not isinstance(error, MountError | TimeoutError):
                logger.exception("the horizon guard's stop failed unexpectedly; again")
            why = str(error) or f"not confirmed within {wait_s:g} s"
            tell(f"{reason}; the stop is not confirmed yet, sending it again: {why}")
            logger.error("the horizon guard's stop is not confirmed: %s; again", why)
            show_notice()
            if not mount.state.connected:
                return
            if not isinstance(error, TimeoutError):
                await asyncio.sleep(_REPEAT_PAUSE_S)  # a fast failure (a closed port)
            wait_s = min(2.0 * wait_s, settings.confirm_max_s)


def _next_state(states: AsyncIterator[MountState]) -> Awaitable[MountState]:
    return anext(states)
