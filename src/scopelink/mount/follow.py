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
    LimitError,
    MountError,
    NotSupportedError,
    SunAvoidanceError,
)
from scopelink.mount.follow_plan import FollowError, PassPlan, plan_pass
from scopelink.mount.slew_wait import slew_unless_stopped
from scopelink.mount.sun import SETTING as SUN_SETTING
from scopelink.mount.types import MountState, TrackingMode

__all__ = [
    "GAIN",
    "GOTO_LEAD_S",
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
"""The Moon's path curves by < 0.01″ from a line over 30 s. Each update restarts a SynScan
driver's PC loop (a transient of a few arcsec), so fewer updates follow more closely there."""

GOTO_LEAD_S = 60.0
"""A satellite is met where it will be this many seconds (of the mount's clock) after the goto
starts: time for the slew across the sky and its settling."""

REPORT_EVERY_S = 0.5
"""The tracking error is reported at most this often (mount clock)."""


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
        tail = [e for t, e in self.errors if t >= first]
        return math.sqrt(sum(e * e for e in tail) / len(tail)) if tail else math.nan


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
        self.mount = mount
        self.target = target
        self.interval_s = interval_s or default_interval_s(target.kind)
        self.on_report = on_report
        self.result = FollowResult()
        self.last: FollowReport | None = None

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
            plan = plan_pass(target, mount.limits, limit, mount.now())
            self.result.plan = plan
            return plan
        self._check_place(mount.now(), "")
        return None

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
        plan = self.check()
        mount = self.mount
        try:
            async with mount.watching():
                if plan is None:
                    start = mount.now()
                else:
                    start = max(plan.start, mount.now() + timedelta(seconds=GOTO_LEAD_S))
                    if start >= plan.end - timedelta(seconds=10):
                        raise FollowError(f"{self.target.name}: too little of the pass is left")
                    await self._wait_until(start - timedelta(seconds=GOTO_LEAD_S), stop)
                if not stop.is_set():
                    await self._goto(start, stop)
                if plan is not None and not stop.is_set():
                    await self._wait_until(start, stop)
                if stop.is_set():
                    self.result.reason = "stopped"
                    return self.result
                end = plan.end if plan is not None else None
                if duration_s is not None:
                    until = mount.now() + timedelta(seconds=duration_s)
                    end = until if end is None else min(end, until)
                await self._follow(stop, end)
        finally:
            with contextlib.suppress(MountError):
                if mount.state.connected and not mount.tracking_rates.zero:
                    await asyncio.shield(mount.set_tracking_rates(0.0, 0.0))
        return self.result

    async def _goto(self, at: datetime, stop: asyncio.Event) -> None:
        """Goto the target's place at ``at``; ``stop`` meanwhile aborts the slew."""
        ra, dec = self.target.position(at)
        await self.mount.goto_equatorial(ra, dec)
        self._report(FollowReport(self.mount.now(), "slewing", None, math.nan, math.nan, ra, dec))
        await slew_unless_stopped(self.mount, stop)

    async def _wait_until(self, deadline: datetime, stop: asyncio.Event) -> None:
        async with aclosing(self.mount.states()) as states:
            async for state in states:
                if stop.is_set() or state.read_at >= deadline:
                    return
                self._throttled(state, "waiting", 0.0, 0.0)

    async def _follow(self, stop: asyncio.Event, end: datetime | None) -> None:
        mount = self.mount
        if mount.state.tracking is not TrackingMode.SIDEREAL:
            await mount.set_tracking(TrackingMode.SIDEREAL)  # the rates are offsets from it
        next_update: datetime | None = None
        rates = (0.0, 0.0)
        async with aclosing(mount.states()) as states:
            async for state in states:
                if stop.is_set():
                    self.result.reason = "stopped"
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
                self.result.errors.append((t, error[2]))
                self._throttled(state, "following", *rates)
                if next_update is None or t >= next_update:
                    try:
                        self._check_place(t, "")
                    except LimitError as refused:
                        self.result.reason = str(refused).split(":")[0]
                        return
                    rates = self._rates(t, error)
                    await mount.set_tracking_rates(*rates)
                    next_update = t + timedelta(seconds=self.interval_s)

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
        return max(-limit, min(limit, ra)), max(-limit, min(limit, dec))

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
