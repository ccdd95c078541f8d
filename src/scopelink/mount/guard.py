"""What keeps a real mount inside its limits after a command was accepted, and a dead-man.

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

The dead-man: front ends that hold a connection per client (LX200, the SynScan server,
Stellarium, the dashboard's page) run each client inside :meth:`Mount.motion_client`; a rate
motion started by that client and still running when it goes is stopped. Decisions and measured
margins are in ``docs/reliability-safety.md``.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import math
import secrets
import statistics
from collections import deque
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from contextlib import aclosing, asynccontextmanager, contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING

from scopelink.mount.budget import (
    FLAT_SLOPE,
    Base,
    Reading,
    Unseen,
    altitude_slope,
    base_from,
    blind_danger,
    has_ceiling,
    make_base,
)
from scopelink.mount.errors import DeviceError, LimitError, MountError, NotConnectedError
from scopelink.mount.sun import SETTING as SUN_SETTING
from scopelink.mount.types import AlignmentMode, MountAxis, MountState, TrackingMode

if TYPE_CHECKING:
    from scopelink.mount.base import Mount

__all__ = ["GuardSettings", "HorizonGuard", "MotionClient"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class GuardSettings:
    """How early the guard stops a motion.

    ``margin_deg`` is kept between the predicted stopping point and the limit. The guard looks
    ``reaction_polls`` poll periods ahead: one to see the next reading, the rest for the stop
    commands to reach the device. ``min_lookahead_s`` (mount clock) is the floor of that
    look-ahead for very fast links. The motors then brake: ``braking_deg_s2`` is the deceleration
    assumed (lower than any Sky-Watcher ramp we know: the simulator's EQ6 brakes at 3.3°/s², the
    Sky Tracker at 2°/s²), so the braking distance is over- rather than underestimated.

    Tracking alone moves at most 15°/h: while the tracked position is more than ``near_deg``
    (plus the margin) from every limit, the guard computes where tracking has carried it every
    ``far_check_s`` (real) seconds instead of polling the device; nearer, it polls.

    Between good readings (a noisy link) the guard budgets for the travel it cannot see: the
    time since the last good reading plus ``stop_latency_s`` (from the decision until the
    device has the stop) at the worst rate the commanded motions and ``tracking_deg_s`` allow,
    plus the braking distance; it checks that budget every ``blind_check_s``. A stop the device
    has not confirmed within ``confirm_s`` is sent again (the wait doubling up to
    ``confirm_max_s``), both axes, until it is confirmed.
    """

    margin_deg: float = 0.2
    reaction_polls: float = 4.0
    min_lookahead_s: float = 0.05
    braking_deg_s2: float = 1.5
    near_deg: float = 1.0
    far_check_s: float = 0.25
    stop_latency_s: float = 0.15
    blind_check_s: float = 0.02
    tracking_deg_s: float = 0.0045
    confirm_s: float = 1.0
    confirm_max_s: float = 8.0


class MotionClient:
    """One client of a front end (an LX200 connection, a dashboard page): the owner of the rate
    motions it starts. ``token`` names it in requests that arrive apart from its connection."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.token = secrets.token_urlsafe(12)

    def __repr__(self) -> str:
        return f"MotionClient({self.name!r})"


_acting_for: ContextVar[MotionClient | None] = ContextVar("scopelink_motion_client", default=None)
"""The client on whose behalf the current task moves the mount (None: nobody in particular)."""


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
    """Stops rate motions and tracking before they cross the limits of ``mount``."""

    def __init__(self, mount: Mount, settings: GuardSettings | None = None) -> None:
        self._mount = mount
        self.settings = settings or GuardSettings()
        self._motions: dict[MountAxis, _RateMotion] = {}
        self._clients: dict[str, MotionClient] = {}
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

    def check_move(self, axis: MountAxis, rate_deg_s: float, state: MountState) -> None:
        """Refuse a rate motion that starts at or beyond a limit and heads further out, where
        the direction is known (see :meth:`altitude_direction`)."""
        if rate_deg_s == 0.0 or state.alt_deg is None or state.az_deg is None:
            return
        limits = self._mount.limits
        margin = self.settings.margin_deg
        floor = limits.horizon_at(state.az_deg)
        at_floor = state.alt_deg <= floor + margin
        at_top = has_ceiling(limits) and state.alt_deg >= limits.max_altitude_deg - margin
        if not (at_floor or at_top):
            return
        direction = self.altitude_direction(axis, rate_deg_s, state)
        if direction is None:
            return  # the guard judges the motion from its first readings instead
        if direction < 0.0 and at_floor:
            raise LimitError(
                f"the mount is at altitude {state.alt_deg:.2f}°, at the configured horizon of "
                f"{floor:.2f}°, and this motion would take it lower: nothing was sent to the "
                "mount (move the other way)"
            )
        if direction > 0.0 and at_top:
            raise LimitError(
                f"the mount is at altitude {state.alt_deg:.2f}°, at the configured limit of "
                f"{limits.max_altitude_deg:.2f}°, and this motion would take it higher: nothing "
                "was sent to the mount (move the other way)"
            )

    def altitude_direction(
        self, axis: MountAxis, rate_deg_s: float, state: MountState
    ) -> float | None:
        """Whether turning ``axis`` at ``rate_deg_s`` raises (+1) or lowers (-1) the tube now;
        None where that cannot be told (conventions: :func:`budget.altitude_slope`)."""
        if self._mount.capabilities.alignment_mode is AlignmentMode.ALT_AZ:
            if axis is MountAxis.SECONDARY:
                return math.copysign(1.0, rate_deg_s)
            return None
        slope = self.altitude_slope(axis, rate_deg_s, state)
        if slope is None or abs(slope) < FLAT_SLOPE:
            return None
        return math.copysign(1.0, slope)

    def altitude_slope(self, axis: MountAxis, rate_deg_s: float, state: MountState) -> float | None:
        """Degrees of altitude per degree that ``axis`` turns in the direction of ``rate_deg_s``
        at the reading ``state`` (None where that cannot be told): see
        :func:`scopelink.mount.budget.altitude_slope`."""
        return altitude_slope(self._mount, axis, rate_deg_s, state)

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
            rate_deg_s, _acting_for.get(), previous.since if previous else self._mount.now(), speed
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
            rate_deg_s, _acting_for.get(), since or self._mount.now(), abs(rate_deg_s)
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

    # --- the dead-man ---------------------------------------------------------------------------

    @asynccontextmanager
    async def client(self, name: str) -> AsyncIterator[MotionClient]:
        """Run a front end's client inside: rate motions it starts are stopped when it goes."""
        client = MotionClient(name)
        self._clients[client.token] = client
        reset = _acting_for.set(client)
        try:
            yield client
        finally:
            with contextlib.suppress(ValueError):  # left from another context: nothing to reset
                _acting_for.reset(reset)
            del self._clients[client.token]
            await self.stop_motions_of(client)

    @contextmanager
    def acting_for(self, token: str | None) -> Iterator[MotionClient | None]:
        """Commands inside are on behalf of the client ``token`` names (if it is still here)."""
        client = self._clients.get(token) if token else None
        reset = _acting_for.set(client)
        try:
            yield client
        finally:
            _acting_for.reset(reset)

    async def stop_motions_of(self, client: MotionClient) -> None:
        """Stop the rate motions ``client`` started that nobody has changed since."""
        axes = [axis for axis, motion in self._motions.items() if motion.owner is client]
        for axis in axes:
            logger.warning(
                "%s went away while moving the %s axis: stopping it",
                client.name,
                axis.name.lower(),
            )
            try:
                await asyncio.shield(self._mount.move_axis(axis, 0.0))
            except MountError as error:
                logger.warning("stopping the %s axis failed: %s", axis.name.lower(), error)

    # --- the horizon guard --------------------------------------------------------------------

    def observe(self, state: MountState) -> None:
        """Called with every published state: start guarding when tracking is seen."""
        if not state.connected:
            self._motions.clear()
            return
        if state.tracking is not TrackingMode.OFF:
            self._wake()

    def annotate(self, state: MountState) -> MountState:
        """``state`` with the last stop's reason among its problems."""
        if self.notice and self.notice not in state.problems:
            return dataclasses.replace(state, problems=(*state.problems, self.notice))
        return state

    def _needed(self, state: MountState) -> bool:
        return state.connected and (bool(self._motions) or state.tracking is not TrackingMode.OFF)

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
        try:
            while self._needed(self._mount.state):
                if self._motions or self._near_limit(self._mount.state):
                    await self._watch_closely()
                else:
                    await self._wait_while_far()
        except asyncio.CancelledError:
            raise
        except Exception:  # the guard must never take the event loop down with it
            logger.exception("the horizon guard failed")

    def _tracked_altitude(self, state: MountState) -> float | None:
        """Where tracking has carried the last reading's sky position by now (tracking holds
        RA/Dec fixed, so this costs astrometry only, no exchange with the device)."""
        if state.ra_j2000_hours is None or state.dec_j2000_deg is None:
            return state.alt_deg
        alt, _ = self._mount.observed_altaz(state.ra_j2000_hours, state.dec_j2000_deg)
        return alt

    def _near_limit(self, state: MountState, *, factor: float = 1.0) -> bool:
        """Whether tracking may reach a limit soon: within ``near_deg`` of it (or unknown)."""
        alt = self._tracked_altitude(state)
        if alt is None or state.az_deg is None:
            return True
        limits = self._mount.limits
        near = self.settings.margin_deg + factor * self.settings.near_deg
        if self._near_sun(state, near):
            return True
        if alt - limits.horizon_at(state.az_deg) < near:
            return True
        return has_ceiling(limits) and limits.max_altitude_deg - alt < near

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
                    reason = self._danger(previous, reading, period_s, state)
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

    def _blind_danger(
        self, base: Base, now_s: float, origin: datetime, state: MountState
    ) -> str | None:
        """Why the mount must stop now because of what it may have done unseen since ``base``
        (mount-clock seconds since ``origin``), or None: see :func:`budget.blind_danger`."""
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

    def _danger(
        self, previous: Reading, reading: Reading, period_s: float, state: MountState
    ) -> str | None:
        """Why the mount must stop now, or None while it stays inside the limits."""
        settings = self.settings
        elapsed = reading.at_s - previous.at_s
        alt_rate = (reading.alt_deg - previous.alt_deg) / elapsed
        az_rate = _wrap_signed(reading.az_deg - previous.az_deg) / elapsed
        ahead_s = max(settings.min_lookahead_s, settings.reaction_polls * period_s)
        # Braking from the fastest axis rate takes axis_rate / deceleration seconds, during which
        # the altitude keeps changing at about half its present rate.
        axis_rate = max((abs(rate) for rate in self.rate_motions.values()), default=0.0)
        ahead_s += axis_rate / settings.braking_deg_s2 / 2.0
        alt_then = reading.alt_deg + alt_rate * ahead_s
        az_then = reading.az_deg + az_rate * ahead_s
        limits = self._mount.limits
        floor_now = limits.horizon_at(reading.az_deg)
        floor_then = limits.horizon_at(az_then)
        above_now = reading.alt_deg - floor_now
        above_then = alt_then - floor_then
        what = "a manual motion" if self._motions else f"{state.tracking.value} tracking"
        if above_then < settings.margin_deg and above_then < above_now:
            return (
                f"{what} was stopped at altitude {reading.alt_deg:.2f}° (azimuth "
                f"{reading.az_deg % 360.0:.1f}°): it was heading below the configured horizon of "
                f"{floor_then:.2f}°"
            )
        below_now = limits.max_altitude_deg - reading.alt_deg
        below_then = limits.max_altitude_deg - alt_then
        if has_ceiling(limits) and below_then < settings.margin_deg and below_then < below_now:
            return (
                f"{what} was stopped at altitude {reading.alt_deg:.2f}°: it was heading above "
                f"the configured limit of {limits.max_altitude_deg:.2f}°"
            )
        return self._sun_danger(reading, alt_then, az_then, ahead_s, what)

    def _sun_danger(
        self, reading: Reading, alt_then: float, az_then: float, ahead_s: float, what: str
    ) -> str | None:
        """Why a motion heading into the Sun avoidance zone must stop now (``_danger``'s
        prediction, judged against where the Sun will be then), or None."""
        try:
            zone = self._mount.sun_zone()
        except LimitError as error:  # the Sun cannot be placed: nothing can be judged safe
            return f"{what} was stopped: {error}"
        if zone is None:
            return None
        now = zone.distance_deg(reading.alt_deg, reading.az_deg)
        then = zone.distance_deg(alt_then, az_then, later_s=ahead_s)
        # Tracking closes in at most 0.5°/h (a thin Moon): the margin is for rate motions only,
        # so a target a goto was allowed to (at the zone's edge) stays tracked.
        edge = zone.radius_deg + (self.settings.margin_deg if self._motions else 0.0)
        if then < edge and then < now:
            return (
                f"{what} was stopped at altitude {reading.alt_deg:.2f}° (azimuth "
                f"{reading.az_deg % 360.0:.1f}°), {now:.1f}° from the Sun: it was heading into "
                f"the {zone.radius_deg:g}° Sun avoidance zone ({SUN_SETTING})"
            )
        return None

    def _near_sun(self, state: MountState, near_deg: float) -> bool:
        """Whether the tracked position is within ``near_deg`` of the Sun avoidance zone."""
        if state.ra_j2000_hours is None or state.dec_j2000_deg is None:
            return False
        try:
            zone = self._mount.sun_zone()
        except LimitError:
            return True
        if zone is None:
            return False
        distance = zone.distance_j2000_deg(state.ra_j2000_hours, state.dec_j2000_deg)
        return distance < zone.radius_deg + near_deg

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

        await _until_confirmed(self._mount, self.settings, stop, reason, tell)
        self._mount._publish(self._mount.state)  # show the notice now, not at the next poll


async def _until_confirmed(
    mount: Mount,
    settings: GuardSettings,
    stop: Callable[[], Awaitable[None]],
    reason: str,
    tell: Callable[[str], None],
) -> None:
    """Run ``stop`` until it returns (the device confirmed it) within ``confirm_s``, the wait
    doubling up to ``confirm_max_s``; give up only when the mount is no longer connected.
    ``tell`` gets the notice to show meanwhile."""
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
        except (MountError, TimeoutError) as error:
            why = str(error) or f"not confirmed within {wait_s:g} s"
            tell(f"{reason}; the stop is not confirmed yet, sending it again: {why}")
            logger.error("the horizon guard's stop is not confirmed: %s; again", why)
            mount._publish(mount.state)
            if not mount.state.connected:
                return
            if isinstance(error, MountError):
                await asyncio.sleep(_REPEAT_PAUSE_S)  # a fast failure (a closed port)
            wait_s = min(2.0 * wait_s, settings.confirm_max_s)


def _next_state(states: AsyncIterator[MountState]) -> Awaitable[MountState]:
    return anext(states)


def _wrap_signed(degrees: float) -> float:
    return (degrees + 180.0) % 360.0 - 180.0
