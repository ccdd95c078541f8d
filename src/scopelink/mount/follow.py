"""Follow a moving target: goto it, then keep the custom tracking rates matched to its
ephemeris, and report the tracking error as it goes (docs/tracking.md, "The follower").

Only the public Mount API is used (``goto_equatorial``, ``wait_for_slew``, ``set_tracking``,
``set_tracking_rates``, ``states()``, ``capabilities.max_tracking_offset_arcsec_s``), so the
follower works on every mount with custom rates; the horizon guard, the limits and the Sun
zone stay in force below it. Every ``interval_s`` of the *mount's* clock it sets

    rates = mean rate of the target over the next interval + GAIN · error / interval_s

where the error is the ephemeris place minus the mount's reading: the feed-forward carries the
mount along the target, the correction closes what the mount missed (a goto's landing, a
driver's re-anchoring, the curvature of the path) — the loop is on position, nothing
accumulates.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from collections.abc import Callable
from contextlib import aclosing
from dataclasses import dataclass, field
from datetime import datetime, timedelta

from scopelink.astro import j2000_to_observed, wrap_signed_degrees
from scopelink.astro.targets import MovingTarget, SatelliteTarget, TargetError, TargetKind
from scopelink.mount.base import Mount
from scopelink.mount.errors import (
    InvalidValueError,
    LimitError,
    MountError,
    NotSupportedError,
    SunAvoidanceError,
)
from scopelink.mount.follow_plan import RATE_MARGIN, FollowError, PassPlan, plan_pass
from scopelink.mount.rates import TrackingRates, clamp_rate, root_mean_square
from scopelink.mount.slew_wait import slew_unless_stopped
from scopelink.mount.sun import SETTING as SUN_SETTING
from scopelink.mount.types import MountState, SlewTarget, TrackingMode

__all__ = [
    "ABORTED",
    "GAIN",
    "GOTO_LEAD_S",
    "MAX_DURATION_S",
    "MAX_INTERVAL_S",
    "REPORT_EVERY_S",
    "FollowError",
    "FollowReport",
    "FollowResult",
    "TargetFollower",
    "default_interval_s",
]

logger = logging.getLogger(__name__)

GAIN = 0.5
"""The share of the position error closed in one interval (a time constant of two intervals:
stable with a reading up to an interval old)."""

INTERVAL_S = {TargetKind.SATELLITE: 1.0}
"""Seconds of the mount's clock between rate updates by kind; others: ``DEFAULT_INTERVAL_S``."""

DEFAULT_INTERVAL_S = 30.0
"""The Moon's path curves by < 0.01″ from a line over 30 s. Each update restarts the Sky
Tracker's press loop (re-anchored at a reading), so fewer updates follow more closely there."""

GOTO_LEAD_S = 60.0
"""A satellite is met where it will be this many seconds (of the mount's clock) after the goto
starts: time for the slew across the sky and its settling."""

REPORT_EVERY_S = 0.5
"""The tracking error is reported at most this often (mount clock)."""

MAX_INTERVAL_S = 600.0
"""The longest interval between rate updates accepted (10 minutes: the follower checks the
limits and the Sun zone only at its updates)."""

MAX_DURATION_S = 30 * 86400.0
"""The longest ``duration_s`` accepted (30 days); longer, or not a number, is a typing error."""

TAKEN_OVER = "another goto took the mount over (another client, or a meridian flip)"
CHANGED_RATES = "the tracking rates were changed elsewhere (another client)"
ABORTED = "an abort stopped following (a stop from a front end, or the horizon guard)"


def _check_seconds(what: str, value: float | None, most: float) -> None:
    """InvalidValueError unless ``value`` is None or a number of seconds in (0, ``most``]."""
    if value is not None and not (
        isinstance(value, int | float) and math.isfinite(value) and 0.0 < value <= most
    ):
        raise InvalidValueError(f"{what} must lie in (0, {most:g}] s, not {value}")


def default_interval_s(kind: TargetKind) -> float:
    return INTERVAL_S.get(kind, DEFAULT_INTERVAL_S)


@dataclass(frozen=True, slots=True)
class FollowReport:
    """One reading while following: the error on the sky (arcsec) between the mount and the
    ephemeris, the rates in force, and the phase ("slewing", "waiting", "following")."""

    at: datetime
    phase: str
    error_arcsec: float | None
    ra_rate_arcsec_s: float = 0.0
    dec_rate_arcsec_s: float = 0.0
    target_ra_hours: float = math.nan
    target_dec_deg: float = math.nan


@dataclass
class FollowResult:
    """How following ended, and every error measured while following (arcsec, mount clock)."""

    reason: str = ""
    errors: list[tuple[datetime, float]] = field(default_factory=list)
    plan: PassPlan | None = None

    def rms_arcsec(self, skip_s: float = 0.0) -> float:
        if not self.errors:
            return math.nan
        first = self.errors[0][0] + timedelta(seconds=skip_s)
        return root_mean_square([e for t, e in self.errors if t >= first])


class TargetFollower:
    """Goto a moving target and follow it with custom rates (module docstring)."""

    def __init__(
        self,
        mount: Mount,
        target: MovingTarget,
        *,
        interval_s: float | None = None,
        on_report: Callable[[FollowReport], None] | None = None,
    ) -> None:
        _check_seconds("the interval between rate updates", interval_s, MAX_INTERVAL_S)
        self.mount = mount
        self.target = target
        self.interval_s = interval_s or default_interval_s(target.kind)
        self.on_report = on_report
        self.result = FollowResult()
        self.last: FollowReport | None = None
        self._own_goto: SlewTarget | None = None
        """The mount's last goto when the follower began, then the follower's own goto: any
        other goto takes the mount over and ends following."""
        self._aborts = 0
        """``Mount.aborts`` when following began: any abort since ends following."""
        self._rates_set: TrackingRates | None = None
        """The rates the follower set last: other rates in force were set by someone else."""

    # --- refusals, before anything moves ------------------------------------------------------

    def check(self) -> PassPlan | None:
        """Refuse what cannot be followed (nothing moves); a satellite's pass plan."""
        mount, target = self.mount, self.target
        limit = mount.capabilities.max_tracking_offset_arcsec_s
        if limit <= 0.0 or TrackingMode.SIDEREAL not in mount.capabilities.tracking_modes:
            raise NotSupportedError("this mount cannot track at custom rates")
        if target.kind is TargetKind.SUN and mount.limits.sun_avoidance_deg > 0.0:
            raise SunAvoidanceError(
                f"tracking the Sun needs Sun avoidance off: set {SUN_SETTING} = 0 "
                "(and cover the telescope and the finder with certified solar filters first)"
            )
        if isinstance(target, SatelliteTarget):
            plan = plan_pass(target, mount.limits, limit, mount.now(), mount.sun_zone())
            self.result.plan = plan
            return plan
        self._check_place(mount.now(), "")
        self._check_rates(mount.now(), limit)
        return None

    def _check_rates(self, t: datetime, limit: float) -> None:
        """FollowError when the target moves faster than the mount's largest rate (with room
        for corrections, as for a satellite's pass): it would fall behind at the clamp."""
        rates = self.target.rate(t)
        allowed = RATE_MARGIN * limit
        for axis, value in (("RA", rates.ra_arcsec_per_s), ("Dec", rates.dec_arcsec_per_s)):
            if abs(value) > allowed:
                raise FollowError(
                    f"{self.target.name} needs {abs(value):.0f}″/s in {axis} now; this mount's "
                    f"largest rate is {limit:g}″/s ({RATE_MARGIN:.0%} of it is used, the rest "
                    "is for corrections)"
                )

    def _check_place(self, t: datetime, what: str) -> None:
        """LimitError / SunAvoidanceError when the target is outside the limits at ``t``."""
        ra, dec = self.target.position(t)
        alt, az = j2000_to_observed(ra, dec, t, self.mount.site)
        name = f"{self.target.name}{what}"
        self.mount.limits.check_altaz(alt, az, what=name)
        if self.target.kind is not TargetKind.SUN:
            zone = self.mount.sun_zone()
            if zone is not None:
                zone.check_position(alt, az, what=name)

    # --- the run ------------------------------------------------------------------------------

    async def run(
        self, stop: asyncio.Event | None = None, duration_s: float | None = None
    ) -> FollowResult:
        """Goto, then follow until ``stop`` is set, ``duration_s`` of the mount's clock has
        passed since following began, the pass ends or the target leaves the limits; the rates
        go back to zero at the end (the mount tracks at the sidereal rate)."""
        stop = stop or asyncio.Event()
        _check_seconds("the duration", duration_s, MAX_DURATION_S)
        plan = self.check()
        mount = self.mount
        self._own_goto, self._aborts = mount.target, mount.aborts
        try:
            async with mount.watching():
                if plan is None:
                    start = mount.now()
                else:
                    start = max(plan.start, mount.now() + timedelta(seconds=GOTO_LEAD_S))
                    if start >= plan.end - timedelta(seconds=10):
                        raise FollowError(f"{self.target.name}: too little of the pass is left")
                    await self._wait_until(start - timedelta(seconds=GOTO_LEAD_S), stop)
                if not stop.is_set() and not self.result.reason:
                    await self._goto(start, stop)
                if plan is not None and not stop.is_set() and not self.result.reason:
                    await self._wait_until(start, stop)
                if stop.is_set() or self.result.reason:
                    self.result.reason = self.result.reason or "stopped"
                    return self.result
                end = plan.end if plan is not None else None
                if duration_s is not None:
                    until = mount.now() + timedelta(seconds=duration_s)
                    end = until if end is None else min(end, until)
                await self._follow(stop, end)
        finally:
            # Back to zero, unless someone else has set rates since (theirs are kept).
            with contextlib.suppress(MountError):
                ours = mount.tracking_rates == self._rates_set
                if mount.state.connected and ours and not mount.tracking_rates.zero:
                    await asyncio.shield(mount.set_tracking_rates(0.0, 0.0))
        return self.result

    async def _goto(self, at: datetime, stop: asyncio.Event) -> None:
        """Goto the target's place at ``at``; ``stop`` meanwhile aborts the slew."""
        ra, dec = self.target.position(at)
        await self.mount.goto_equatorial(ra, dec)
        self._own_goto = self.mount.target
        self._report(FollowReport(self.mount.now(), "slewing", None, math.nan, math.nan, ra, dec))
        await slew_unless_stopped(self.mount, stop)

    async def _wait_until(self, deadline: datetime, stop: asyncio.Event) -> None:
        async with aclosing(self.mount.states()) as states:
            async for state in states:
                if stop.is_set() or state.read_at >= deadline:
                    return
                taken = self._taken_over(state, fresh=False)
                if taken:
                    self.result.reason = taken
                    return
                self._throttled(state, "waiting", 0.0, 0.0)

    async def _follow(self, stop: asyncio.Event, end: datetime | None) -> None:
        mount = self.mount
        if mount.state.tracking is not TrackingMode.SIDEREAL:
            await mount.set_tracking(TrackingMode.SIDEREAL)  # the rates are offsets from it
        since = mount.now()  # readings from here on show the follower's tracking mode
        next_update: datetime | None = None
        rates = (0.0, 0.0)
        async with aclosing(mount.states()) as states:
            async for state in states:
                if stop.is_set():
                    self.result.reason = "stopped"
                    return
                taken = self._taken_over(state, fresh=state.read_at >= since)
                if taken:
                    self.result.reason = taken
                    return
                if not state.connected or state.ra_j2000_hours is None:
                    continue
                t = state.read_at
                if end is not None and t >= end:
                    self.result.reason = "the pass ended" if self.result.plan else "time is up"
                    return
                if state.tracking is TrackingMode.OFF and next_update is not None:
                    problems = "; ".join(state.problems)
                    self.result.reason = "tracking was stopped" + (
                        f": {problems}" if problems else ""
                    )
                    return
                try:
                    error = self._error(state)
                except TargetError as failed:  # e.g. SGP4 cannot carry the TLE this far
                    self.result.reason = str(failed)
                    return
                if not all(math.isfinite(value) for value in error):
                    self.result.reason = self._no_number(t)
                    return
                self.result.errors.append((t, error[2]))
                self._throttled(state, "following", *rates)
                if next_update is None or t >= next_update:
                    ahead = t + timedelta(seconds=self.interval_s)
                    try:
                        if self.result.plan is None:  # a pass's plan judged its rates already
                            self._check_rates(t, mount.capabilities.max_tracking_offset_arcsec_s)
                        self._check_place(t, "")
                        if end is None or ahead <= end:  # where these rates carry the mount
                            self._check_place(ahead, f" {self.interval_s:g} s from now")
                    except InvalidValueError:  # the place is not a number
                        self.result.reason = self._no_number(ahead)
                        return
                    except LimitError as refused:
                        self.result.reason = str(refused).split(":")[0]
                        return
                    except FollowError as too_fast:  # it sped up: trailing it helps nobody
                        self.result.reason = str(too_fast)
                        return
                    rates = self._rates(t, error)
                    await mount.set_tracking_rates(*rates)
                    self._rates_set = mount.tracking_rates
                    next_update = ahead

    def _no_number(self, t: datetime) -> str:
        return (
            f"no number for {self.target.name}'s place or the mount's reading at "
            f"{t:%H:%M:%S} UTC: following stopped"
        )

    def _taken_over(self, state: MountState, *, fresh: bool) -> str | None:
        """Why following must end because someone else took over (None: nobody did): a goto
        not the follower's, rates it did not set, or another tracking mode."""
        if self.mount.target is not self._own_goto:
            return TAKEN_OVER
        if self.mount.aborts != self._aborts:
            problems = "; ".join(state.problems)
            return ABORTED + (f": {problems}" if problems else "")
        if self._rates_set is not None and self.mount.tracking_rates != self._rates_set:
            return CHANGED_RATES
        if fresh and state.tracking not in (TrackingMode.SIDEREAL, TrackingMode.OFF):
            return f"tracking was set to {state.tracking.value} elsewhere (another client)"
        return None

    def _error(self, state: MountState) -> tuple[float, float, float]:
        """(RA error in arcsec of RA, Dec error in arcsec, error on the sky in arcsec)."""
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        ra, dec = self.target.position(state.read_at)
        d_ra = wrap_signed_degrees((ra - state.ra_j2000_hours) * 15.0) * 3600.0
        d_dec = (dec - state.dec_j2000_deg) * 3600.0
        sky = math.hypot(d_ra * math.cos(math.radians(dec)), d_dec)
        return d_ra, d_dec, sky

    def _rates(self, t: datetime, error: tuple[float, float, float]) -> tuple[float, float]:
        mean = self.target.mean_rate(t, self.interval_s)
        limit = self.mount.capabilities.max_tracking_offset_arcsec_s
        ra = mean.ra_arcsec_per_s + GAIN * error[0] / self.interval_s
        dec = mean.dec_arcsec_per_s + GAIN * error[1] / self.interval_s
        return clamp_rate(ra, limit), clamp_rate(dec, limit)

    def _throttled(self, state: MountState, phase: str, ra_rate: float, dec_rate: float) -> None:
        last = self.last
        if last is not None and (state.read_at - last.at).total_seconds() < REPORT_EVERY_S:
            return
        error = None
        ra, dec = self.target.position(state.read_at)
        if state.ra_j2000_hours is not None:
            error = self._error(state)[2]
        self._report(FollowReport(state.read_at, phase, error, ra_rate, dec_rate, ra, dec))

    def _report(self, report: FollowReport) -> None:
        self.last = report
        if self.on_report is not None:
            self.on_report(report)
