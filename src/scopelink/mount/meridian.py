"""Meridian limits of German equatorial mounts (issue #15 part 3).

On a German mount the tube sits on one side of the pier. Tracking turns the polar axis west at
the sidereal rate, so a tube on the **west** side of the pier (looking east, ``PierSide.WEST``)
follows its target across the meridian with the counterweight rising, towards the pier; a tube
on the **east** side (looking west) moves away from the meridian. The limits, in degrees of hour
angle past the meridian:

- ``limits.meridian_west_deg``: how far west of the meridian a target may be followed with the
  tube on the west side of the pier (tracking stops there, or flips with ``limits.auto_flip``);
- ``limits.meridian_east_deg``: how far east of the meridian a target may be pointed at with the
  tube on the east side (counterweight up; tracking moves it away from this limit).

The same in both hemispheres (the pier side as :func:`scopelink.astro.destination_side_of_pier`).
A goto picks the side on which tracking lasts ``limits.min_track_minutes`` before the limit
(:func:`plan_goto_side`), and :class:`MeridianWatch` stops tracking at the limit, or flips: a goto
to the same position through the checked ``Mount.goto_equatorial`` (horizon, Sun, limits), with
tracking turned off first, so that a flip that fails leaves tracking off. Decisions, and what each
device can enforce: ``docs/meridian.md``.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from scopelink.astro import (
    SIDEREAL_RATE_DEG_S,
    PierSide,
    altaz_to_hadec,
    destination_side_of_pier,
    hour_angle_hours,
    j2000_to_apparent,
    lst_hours,
)
from scopelink.mount.errors import LimitError, MountError
from scopelink.mount.guard import stop_until_confirmed
from scopelink.mount.guarded import GuardedMount, GuardSettings
from scopelink.mount.limits import Limits
from scopelink.mount.types import AlignmentMode, Capabilities, MountState, TrackingMode

__all__ = [
    "FLIP_TIMEOUT_S",
    "MeridianMount",
    "MeridianStatus",
    "MeridianWatch",
    "applies",
    "hour_angle_of_altaz",
    "hour_angle_of_j2000",
    "meridian_status",
    "minutes_left",
    "past_meridian_deg",
    "plan_goto_side",
    "side_problem",
]

logger = logging.getLogger(__name__)

TRACKING_DEG_PER_MIN = SIDEREAL_RATE_DEG_S * 60.0
"""How fast tracking carries the hour angle (degrees a minute, ~0.25)."""
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

_SIDE_NAMES = {PierSide.EAST: "east", PierSide.WEST: "west", PierSide.UNKNOWN: "unknown"}


def applies(capabilities: Capabilities) -> bool:
    """Whether the meridian limits apply: German equatorial mounts only (alt-az, fork and the
    Sky Tracker have no counterweight to run into the pier)."""
    return capabilities.alignment_mode is AlignmentMode.GERMAN_POLAR


def past_meridian_deg(ha_hours: float, side: PierSide) -> float | None:
    """How far past the meridian (degrees of hour angle) the tube points on ``side``: positive
    with the counterweight up. None when the side is unknown.

    Only the meridian above the pole is judged: an hour angle more than 6 h past it counts from
    the other way round (a tube below the pole is up to 18 h of tracking short of the limit)."""
    if side is PierSide.WEST:
        return 15.0 * (ha_hours if ha_hours <= 6.0 else ha_hours - 24.0)
    if side is PierSide.EAST:
        return -15.0 * (ha_hours if ha_hours >= -6.0 else ha_hours + 24.0)
    return None


def _limit_deg(limits: Limits, side: PierSide) -> float:
    return limits.meridian_west_deg if side is PierSide.WEST else limits.meridian_east_deg


def _setting(side: PierSide) -> str:
    return "limits.meridian_west_deg" if side is PierSide.WEST else "limits.meridian_east_deg"


def minutes_left(limits: Limits, ha_hours: float, side: PierSide) -> float | None:
    """Minutes of tracking before the tube on ``side`` reaches its meridian limit (0 at or past
    it; infinite on the east side, which tracking carries away from its limit); None when the
    side is unknown."""
    if side is PierSide.EAST:
        return math.inf
    past = past_meridian_deg(ha_hours, side)
    if past is None:
        return None
    return max(limits.meridian_west_deg - past, 0.0) / TRACKING_DEG_PER_MIN


def side_problem(limits: Limits, ha_hours: float, side: PierSide, *, tracking: bool) -> str | None:
    """Why the tube must not go to ``side`` for a target at ``ha_hours`` (past the limit, or,
    when it will track, reaching it within ``limits.min_track_minutes``), or None."""
    past = past_meridian_deg(ha_hours, side)
    if past is None:
        return None
    name, limit = _SIDE_NAMES[side], _limit_deg(limits, side)
    if past > limit:
        return (
            f"on the {name} side of the pier it would point {past:.1f}° past the meridian, "
            f"beyond {_setting(side)} ({limit:g}°)"
        )
    left = minutes_left(limits, ha_hours, side)
    if tracking and left is not None and left < limits.min_track_minutes:
        return (
            f"on the {name} side of the pier tracking would reach the meridian limit in "
            f"{left:.0f} min, less than limits.min_track_minutes ({limits.min_track_minutes:g})"
        )
    return None


def _other(side: PierSide) -> PierSide:
    return PierSide.EAST if side is PierSide.WEST else PierSide.WEST


def plan_goto_side(
    limits: Limits,
    ha_hours: float,
    predicted: PierSide,
    *,
    can_choose: bool,
    tracking: bool = True,
    leave: PierSide | None = None,
) -> PierSide | None:
    """The pier side a goto to a target at ``ha_hours`` must ask for, or None when the side
    the device picks by itself (``predicted``) will do.

    The device's side is kept unless it is past the limit or (``tracking``) reaches it within
    ``min_track_minutes``; then the other side, if it is no worse. Raises ``LimitError`` naming
    the setting when no side is allowed, or when another side is needed and the device cannot be
    told which (``can_choose`` False: a SynScan hand control picks its side itself). ``leave``:
    the side an automatic flip leaves, never chosen.
    """
    if predicted is PierSide.UNKNOWN:
        predicted = destination_side_of_pier(ha_hours)
    problem = side_problem(limits, ha_hours, predicted, tracking=tracking)
    if predicted is leave:
        problem = f"a meridian flip must leave the {_SIDE_NAMES[predicted]} side of the pier"
    if problem is None:
        return None
    wanted = _other(predicted)
    if side_problem(limits, ha_hours, wanted, tracking=tracking) is not None:
        # Neither side tracks min_track_minutes: the one within the limits that tracks longer.
        allowed = [
            side
            for side in (predicted, wanted)
            if side is not leave and side_problem(limits, ha_hours, side, tracking=False) is None
        ]
        if not allowed:
            other = side_problem(limits, ha_hours, wanted, tracking=False)
            raise LimitError(f"the target is out of reach: {problem}; {other}: nothing was sent")
        best = max(allowed, key=lambda side: minutes_left(limits, ha_hours, side) or 0.0)
        if best is predicted:
            return None
        wanted = best
    if not can_choose:
        raise LimitError(
            f"this mount picks the pier side of a goto itself and {problem}: nothing was sent "
            "to the mount (wait until the target is past the meridian, or change the setting)"
        )
    return wanted


def hour_angle_of_j2000(
    mount: GuardedMount, ra_j2000_hours: float, dec_j2000_deg: float
) -> tuple[float, float]:
    """Hour angle (hours) and declination of date of a J2000 position at the mount's now."""
    now = mount.now()
    ra, dec = j2000_to_apparent(ra_j2000_hours, dec_j2000_deg, now)
    return hour_angle_hours(lst_hours(now, mount.site.longitude_deg), ra), dec


def hour_angle_of_altaz(mount: GuardedMount, alt_deg: float, az_deg: float) -> tuple[float, float]:
    """Hour angle (hours) and declination of an observed altitude and azimuth."""
    return altaz_to_hadec(alt_deg, az_deg, mount.site.latitude_deg)


@dataclass(frozen=True, slots=True)
class MeridianStatus:
    """Where the tube stands against its meridian limit (``minutes_left``: None while not
    tracking, infinite on the side tracking carries away from the limit)."""

    side: PierSide
    hour_angle_hours: float
    past_deg: float
    limit_deg: float
    minutes_left: float | None


def meridian_status(mount: GuardedMount, state: MountState) -> MeridianStatus | None:
    """The tube's standing against its meridian limit, or None where the limits do not apply
    or the reading lacks the pier side or the position."""
    side = state.pier_side
    ra = state.ra_of_date_hours
    if not applies(mount.capabilities) or side is PierSide.UNKNOWN or ra is None:
        return None
    tracking = state.tracking is not TrackingMode.OFF and not state.parked
    # Tracking holds RA: the hour angle grows with the clock. Standing still, the tube's hour
    # angle is the reading's.
    when = mount.now() if tracking else state.read_at
    ha = hour_angle_hours(lst_hours(when, mount.site.longitude_deg), ra)
    past = past_meridian_deg(ha, side)
    assert past is not None  # the side is known
    left = minutes_left(mount.limits, ha, side) if tracking else None
    return MeridianStatus(side, ha, past, _limit_deg(mount.limits, side), left)


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
            and state.tracking is not TrackingMode.OFF
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
        side = _SIDE_NAMES[status.side]
        reason = (
            f"tracking was stopped {status.past_deg:.1f}° past the meridian on the {side} side "
            f"of the pier: the meridian limit ({_setting(status.side)} {status.limit_deg:g}°)"
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
                f"{_SIDE_NAMES[landed.pier_side]} side of the pier, tracking "
                f"{landed.tracking.value}), tracking is off"
            )
            return
        self.flips += 1
        self.notice = ""
        logger.warning("meridian flip: now on the %s side", _SIDE_NAMES[landed.pier_side])
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
