"""Custom tracking rates on a Sky Tracker: timed guide presses in a closed loop (docs/tracking.md).

The box tracks what the Sky Commander tells it (the sky's motion at the scope's position: a
fixed J2000 point) and takes no rate. In GUIDE mode (``D``) an arrow adds the ``K`` speed
(1-255 arcsec/s of the axis, per axis) to that tracking. So while custom rates are in force
(or lunar, solar, King tracking, which are sidereal plus an RA offset), the driver works out
the target's motion in azimuth and altitude against a fixed point, and presses the arrows for
part of every period (:mod:`.presses`) to give that offset on average, corrected from every
position the Sky Commander reports: a proportional loop on the error between the reading and
the target integrated from where the loop started, so drift is corrected, never accumulated.
The presses are rate motions the horizon guard watches; any other motion command ends the
loop; a guide pulse is added to it (its axis pressed at the pulse speed, the target moved
along).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from collections.abc import Callable
from contextlib import aclosing
from dataclasses import replace
from datetime import datetime, timedelta

from scopelink.astro import Site, j2000_to_observed, observed_to_j2000, wrap_signed_degrees
from scopelink.drivers.common import Pointing
from scopelink.links import LinkError
from scopelink.mount import GuideDirection, MountAxis, MountError, TrackingMode
from scopelink.mount.rates import (
    GuideShifts,
    RateLoopStatistics,
    TrackingRates,
    clamp_rate,
    pulse_joining_loop,
)
from scopelink.mount.scheduling import Priority
from scopelink.protocol.skytracker import Direction

from .base import BOX_TRACKING, LOOP_TRACKING_MODES
from .guiding import SkyTrackerGuiding
from .motion import GUIDE_SPEED_MAX_ARCSEC_S, AxisMotion, guide_button
from .presses import PRESS_PERIOD_S, AxisPress, plan_press

__all__ = [
    "FEED_FORWARD_STEP_S",
    "LOOP_GAIN_PER_S",
    "LOOP_INTEGRAL_GAIN",
    "LOOP_MODES",
    "MAX_CORRECTION_ARCSEC_S",
    "SkyTrackerRates",
]

logger = logging.getLogger(__name__)

LOOP_GAIN_PER_S = 0.1
"""The loop's proportional gain (mount clock): a mean error of E arcsec over a press period adds
0.1·E arcsec/s (a 10 s time constant). Low, because the Sky Commander reports RA in steps of
0.001 h (54″ of RA): the loop averages the steps instead of chasing each."""

LOOP_INTEGRAL_GAIN = LOOP_GAIN_PER_S**2 / 4.0
"""Integral gain (per s²; critically damped with the proportional one): the mean rate the
presses give falls short of the planned one by a fraction of an arcsec/s (the commands' time on
the line, the box's 0.5 s tracking updates), which a proportional loop alone would leave as a
steady lag of that rate over its gain."""

MAX_CORRECTION_ARCSEC_S = 30.0
"""The correction never exceeds this on an axis (arcsec/s of the axis)."""

FEED_FORWARD_STEP_S = 10.0
"""The target's offset rate in azimuth and altitude is a finite difference over this (mount s)."""

LOOP_MODES = frozenset(LOOP_TRACKING_MODES)
"""The tracking modes that are this loop even without custom rates (the box tracks sidereal)."""


_POSITIVE_BUTTONS = frozenset({Direction.UP, Direction.RIGHT})


def _altaz(ra_hours: float, dec_deg: float, when: datetime, site: Site) -> tuple[float, float]:
    alt, az = j2000_to_observed(ra_hours, dec_deg, when, site)
    return float(alt), float(az)


class SkyTrackerRates(SkyTrackerGuiding):
    """Custom tracking rates by timed presses (module docstring); the commands build on it."""

    _rate_loop: asyncio.Task[None] | None = None
    _loop_taken = False
    """Another motion command is on its way: no press of the loop's may follow it."""
    _loop_joining = False
    """A guide pulse (or the loop's own first presses) goes through the checked motion path."""
    _loop_shifts: GuideShifts | None = None
    _loop_start: datetime | None = None
    _loop_clock_ratio = 1.0
    """Mount seconds per real second, measured while the loop runs (pulses are timed on the PC)."""
    _loop_corrections: dict[MountAxis, float] = {}  # noqa: RUF012 - replaced, never mutated
    _loop_guarded: dict[MountAxis, float] = {}  # noqa: RUF012 - what the guard was told
    _loop_offsets_now: dict[MountAxis, float] = {}  # noqa: RUF012 - replaced every period
    _loop_integral: dict[MountAxis, float] = {}  # noqa: RUF012 - per loop, replaced at start
    _loop_integrated_at: datetime | None = None
    rate_loop_statistics: RateLoopStatistics | None = None
    """The running (or last) loop's errors: None before the first."""

    # --- what the commands (mount.py) provide ---------------------------------------------------

    async def _apply_buttons(self, still: Callable[[], bool] | None = None) -> bool:
        raise NotImplementedError

    # --- the loop's life ------------------------------------------------------------------------

    @property
    def custom_rates_running(self) -> bool:
        """Whether the PC loop presses the arrows now."""
        task = self._rate_loop
        return task is not None and not task.done() and not self._loop_taken

    def _motion_commanded(self) -> None:
        super()._motion_commanded()
        if self._rate_loop is not None and not self._loop_joining:
            # Its arrows stay in _loop_presses: the command taking over releases them ('b').
            self._loop_taken = True

    async def _set_tracking_rates(self, rates: TrackingRates) -> None:
        await self._end_rate_loop()
        await self._start_rate_loop(rates)

    def _loop_wanted(self, rates: TrackingRates) -> TrackingRates | None:
        """The rates the loop must give now (the mode's RA offset added); None: no loop."""
        mode = self._tracking_choice
        if self._mode not in BOX_TRACKING or self._commander_present is False:
            return None
        if rates.zero and mode not in LOOP_MODES:
            return None
        return rates.plus_mode(mode) if mode in LOOP_MODES else rates

    async def _start_rate_loop(self, rates: TrackingRates | None = None) -> None:
        """Start the loop if tracking is on (no GOTO) and rates or a loop mode call for it."""
        wanted = self._loop_wanted(self.tracking_rates if rates is None else rates)
        if wanted is None or self._held or self._pulses:
            return
        position = await self._read_position(
            self._require_commander(), Priority.COMMAND, retry=True
        )
        self._publish_now()
        self._loop_taken = False
        self._loop_problems = ()
        self._loop_presses.clear()
        self._loop_shifts = GuideShifts()
        self._loop_start = position.read_at
        self._loop_corrections = {}
        self._loop_guarded = {}
        self._loop_integral = {}
        self._loop_integrated_at = None
        self._loop_offsets_now = {}
        self._loop_clock_ratio = 1.0
        statistics = RateLoopStatistics(
            started_at=position.read_at,
            anchor=(position.ra_j2000_hours, position.dec_j2000_deg),
        )
        self.rate_loop_statistics = statistics
        # The first presses are checked again (and watched) as they start, in the loop; a
        # refusal here is the caller's one-line LimitError, and no loop starts.
        for press in self._plan_period(self._feed_forward(wanted, position.read_at)):
            self._guard.check_move(press.axis, press.rate_deg_s, self.state)
        self._loop_on = True
        self._rate_loop = asyncio.create_task(
            self._run(wanted, statistics), name="sky tracker custom tracking rates"
        )

    async def _end_rate_loop(self) -> None:
        """Stop the loop (rates zeroed, a tracking change, a disconnect): its arrows released."""
        task, self._rate_loop = self._rate_loop, None
        self._loop_problems = ()  # a command of the user's: what the loop said is over
        if task is None:
            return
        self._loop_taken = True
        self._loop_on = False
        if task is not asyncio.current_task():
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
        await self._hand_back()

    async def _hand_back(self) -> None:
        """Release the loop's arrows (if nothing else took them over): the box's own tracking.
        The guard forgets the loop's presses, not a motion that took an axis over."""
        for axis, rate in self._loop_guarded.items():
            if axis not in self._held and self._guard.rate_motions.get(axis) == rate:
                self._guard.motion_commanded(axis, 0.0)
        self._loop_guarded = {}
        # 'b' even when no press is recorded: a release the loop was sending when it was stopped
        # may not have gone out (its turn found the loop no longer in charge).
        self._loop_presses.clear()
        if self._line is None or self._line.link.closed or self._held or self._pulses:
            return  # a command that holds arrows now has released the loop's ('b') first
        with contextlib.suppress(MountError, LinkError):
            await self._apply_buttons()  # 'b' (harmless during a GOTO: it ignores arrows)

    # --- guide pulses join the loop -------------------------------------------------------------

    async def pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        """As :meth:`Mount.pulse_guide`; while the loop runs the pulse is added to it: its axis
        is pressed at the pulse speed for the duration, and the loop's target moves with it."""
        if await pulse_joining_loop(self, super().pulse_guide, direction, duration_ms):
            self._shift_for_pulse(direction, duration_ms / 1000.0)

    def _pulse_with_loop(self, axis: MountAxis, button: Direction) -> AxisMotion | None:
        """A pulse on an axis the loop drives: one press at the pulse speed plus the loop's own
        rate there (whole arcsec/s; the other way if the sum is negative); None: no press."""
        speeds = self._pulse_speeds
        speed = speeds[0] if axis is MountAxis.PRIMARY else speeds[1]
        sign = 1.0 if button in _POSITIVE_BUTTONS else -1.0
        press = plan_press(axis, sign * speed + self._loop_offsets_now.get(axis, 0.0), speed)
        if press is None:
            return None
        combined = max(1, min(GUIDE_SPEED_MAX_ARCSEC_S, round(press.speed_arcsec_s * press.duty)))
        return replace(press, speed_arcsec_s=combined, duty=1.0).motion

    def _shift_for_pulse(self, direction: GuideDirection, duration_s: float) -> None:
        """Move the loop's target by the pulse: its axis rate at the scope's position, in J2000."""
        shifts, start, position = self._loop_shifts, self._loop_start, self._position
        if shifts is None or start is None or position is None or duration_s <= 0.0:
            return
        axis, button = guide_button(direction)
        speeds = self._pulse_speeds
        speed = (speeds[0] if axis is MountAxis.PRIMARY else speeds[1]) / 3600.0
        sign = 1.0 if button in _POSITIVE_BUTTONS else -1.0
        now = self.now()
        alt, az = _altaz(position.ra_j2000_hours, position.dec_j2000_deg, now, self.site)
        moved = (
            (alt + sign * speed, az) if axis is MountAxis.SECONDARY else (alt, az + sign * speed)
        )
        ra0, dec0 = observed_to_j2000(alt, az, now, self.site)
        ra1, dec1 = observed_to_j2000(moved[0], moved[1], now, self.site)
        ra_rate = wrap_signed_degrees((float(ra1) - float(ra0)) * 15.0) / 15.0
        t = (now - start).total_seconds()
        shifts.add(
            axis.value, t, duration_s * self._clock_ratio(), ra_rate, float(dec1) - float(dec0)
        )
        if self.rate_loop_statistics is not None:
            self.rate_loop_statistics.pulses += 1

    def _clock_ratio(self) -> float:
        return self._loop_clock_ratio

    # --- the loop -------------------------------------------------------------------------------

    def _loop_still_ours(self) -> bool:
        return (
            not self._loop_taken
            and self._line is not None
            and not self._link_lost
            and self._mode in BOX_TRACKING
        )

    def _target_at(
        self, rates: TrackingRates, when: datetime, shifted_at: datetime | None = None
    ) -> tuple[float, float]:
        """The target at ``when``, moved by the guide pulses as at ``shifted_at`` (``when``)."""
        statistics, start, shifts = self.rate_loop_statistics, self._loop_start, self._loop_shifts
        assert statistics is not None
        assert statistics.anchor is not None
        assert start is not None
        t = (when - start).total_seconds()
        t_shift = t if shifted_at is None else (shifted_at - start).total_seconds()
        ra_shift, dec_shift = shifts.at(t_shift) if shifts is not None else (0.0, 0.0)
        ra0, dec0 = statistics.anchor
        return ra0 + rates.ra_hours_per_s * t + ra_shift, dec0 + rates.dec_deg_per_s * t + dec_shift

    def _feed_forward(self, rates: TrackingRates, when: datetime) -> dict[MountAxis, float]:
        """Arcsec/s of each axis the target moves against a fixed point of the sky (which the
        box's own tracking follows) at ``when``; not a pulse's rate (its own press gives it)."""
        later = when + timedelta(seconds=FEED_FORWARD_STEP_S)
        alt_a, az_a = _altaz(*self._target_at(rates, when), later, self.site)
        alt_b, az_b = _altaz(*self._target_at(rates, later, when), later, self.site)
        return {
            MountAxis.PRIMARY: wrap_signed_degrees(az_b - az_a) * 3600.0 / FEED_FORWARD_STEP_S,
            MountAxis.SECONDARY: (alt_b - alt_a) * 3600.0 / FEED_FORWARD_STEP_S,
        }

    def _reading_error(
        self, rates: TrackingRates, position: Pointing
    ) -> tuple[float, float, float]:
        """The target minus a reading, in arcsec of the azimuth and altitude axes, and on the
        sky, at the reading's time."""
        when = position.read_at
        alt_t, az_t = _altaz(*self._target_at(rates, when), when, self.site)
        alt_r, az_r = _altaz(position.ra_j2000_hours, position.dec_j2000_deg, when, self.site)
        az_error = wrap_signed_degrees(az_t - az_r) * 3600.0
        alt_error = (alt_t - alt_r) * 3600.0
        sky = math.hypot(az_error * math.cos(math.radians(alt_r)), alt_error)
        return az_error, alt_error, sky

    async def _collect_errors(
        self, rates: TrackingRates, statistics: RateLoopStatistics, sink: list[tuple[float, float]]
    ) -> None:
        """The error of every new reading (the poller runs at full rate meanwhile)."""
        last: datetime | None = None
        async with aclosing(self.states()) as states:
            async for _ in states:
                position = self._position
                if position is None or (last is not None and position.read_at <= last):
                    continue
                last = position.read_at
                az_error, alt_error, sky = self._reading_error(rates, position)
                sink.append((az_error, alt_error))
                statistics.add_error(sky)

    def _wanted_offsets(
        self, rates: TrackingRates, errors: list[tuple[float, float]]
    ) -> dict[MountAxis, float]:
        """Arcsec/s of each axis to add to the box's tracking: the feed-forward plus a PI
        correction on the mean error of the readings since the last period (averaging the Sky
        Commander's 0.001 h steps and the presses' ripple); without a new reading, the last
        period's correction."""
        now = self.now()
        offsets = self._feed_forward(rates, now)
        if errors:
            count = len(errors)
            mean = (sum(e[0] for e in errors) / count, sum(e[1] for e in errors) / count)
            errors.clear()
            last, self._loop_integrated_at = self._loop_integrated_at, now
            dt = (now - last).total_seconds() if last is not None else 0.0
            limit = MAX_CORRECTION_ARCSEC_S
            corrections = {}
            for axis, error in zip((MountAxis.PRIMARY, MountAxis.SECONDARY), mean, strict=True):
                integral = self._loop_integral.get(axis, 0.0) + error * dt
                integral = clamp_rate(integral, limit / LOOP_INTEGRAL_GAIN)
                self._loop_integral[axis] = integral
                wanted = LOOP_GAIN_PER_S * error + LOOP_INTEGRAL_GAIN * integral
                corrections[axis] = clamp_rate(wanted, limit)
            self._loop_corrections = corrections
        for axis, correction in self._loop_corrections.items():
            offsets[axis] += correction
        return offsets

    async def _run(self, rates: TrackingRates, statistics: RateLoopStatistics) -> None:
        loop = asyncio.get_running_loop()
        first = True
        started_real, started_mount = loop.time(), self.now()
        errors: list[tuple[float, float]] = []
        collector = asyncio.create_task(self._collect_errors(rates, statistics, errors))
        try:
            period_start = loop.time()
            while self._loop_still_ours() and not collector.done():
                elapsed_real = loop.time() - started_real
                if elapsed_real > 2.0:
                    self._loop_clock_ratio = (
                        self.now() - started_mount
                    ).total_seconds() / elapsed_real
                presses = self._plan_period(self._wanted_offsets(rates, errors))
                if not await self._press_period(presses, statistics, period_start, first):
                    break
                first = False
                period_start += PRESS_PERIOD_S
                await asyncio.sleep(max(0.0, period_start - loop.time()))
        except (MountError, LinkError) as error:
            if not self._loop_taken:
                logger.warning("%s: custom tracking rates: %s", self.spec, error)
                self._loop_problems = (f"custom tracking rates stopped: {error}",)
        finally:
            collector.cancel()
            with contextlib.suppress(asyncio.CancelledError, MountError, LinkError):
                await collector
            if self._rate_loop is asyncio.current_task():
                self._rate_loop = None
                self._loop_on = False
                if self._tracking_choice in LOOP_MODES and self._loop_taken:
                    self._tracking_choice = TrackingMode.SIDEREAL  # the box tracks by itself
                with contextlib.suppress(MountError, LinkError):
                    await asyncio.shield(self._hand_back())
            self._publish_now()

    def _plan_period(self, offsets: dict[MountAxis, float]) -> list[AxisPress]:
        self._loop_offsets_now = dict(offsets)
        presses = []
        for index, axis in enumerate((MountAxis.PRIMARY, MountAxis.SECONDARY)):
            current = self._guide_speeds[index]
            press = plan_press(axis, offsets[axis], current)
            if press is not None:
                presses.append(press)
        saturated = any(press.saturated for press in presses)
        self._loop_problems = (
            (
                f"custom tracking rates need more than the box's {GUIDE_SPEED_MAX_ARCSEC_S}″/s "
                "guide speed on an axis (near the zenith?): the scope falls behind",
            )
            if saturated
            else ()
        )
        return presses

    async def _press_period(
        self,
        presses: list[AxisPress],
        statistics: RateLoopStatistics,
        period_start: float,
        first: bool,
    ) -> bool:
        """Press the arrows of one period and release each after its duty; False once the
        loop is no longer in charge."""
        loop = asyncio.get_running_loop()
        pressed_axes = {press.axis for press in presses}
        if first:
            for press in presses:
                if not await self._first_press(press):
                    return False
        else:
            if not self._loop_still_ours():
                return False
            for press in presses:
                self._loop_presses[press.axis] = press.motion
            for axis in (MountAxis.PRIMARY, MountAxis.SECONDARY):
                if axis not in pressed_axes:
                    self._loop_presses.pop(axis, None)
            if not await asyncio.shield(self._apply_buttons(self._loop_still_ours)):
                return False
            for axis in (MountAxis.PRIMARY, MountAxis.SECONDARY):  # the guard watches them
                rate = next((p.rate_deg_s for p in presses if p.axis is axis), 0.0)
                self._guard.motion_commanded(axis, rate)
                self._loop_guarded[axis] = rate
        statistics.commands += 1
        for press in sorted(presses, key=lambda p: p.duty):
            if press.duty >= 1.0:
                continue
            await asyncio.sleep(max(0.0, period_start + press.duty * PRESS_PERIOD_S - loop.time()))
            if not self._loop_still_ours():
                return False
            self._loop_presses.pop(press.axis, None)
            # Shielded: cancelling the loop never cuts an exchange short (a resync).
            if not await asyncio.shield(self._apply_buttons(self._loop_still_ours)):
                return False
            statistics.commands += 1
        return True

    async def _first_press(self, press: AxisPress) -> bool:
        """The first presses go through the guard's checks, as rate motions of their client."""

        async def start() -> None:
            self._loop_presses[press.axis] = press.motion
            self._loop_guarded[press.axis] = press.rate_deg_s
            await asyncio.shield(self._apply_buttons(self._loop_still_ours))

        self._loop_joining = True
        try:
            await self._guarded_rate_motion(press.axis, press.rate_deg_s, start)
        finally:
            self._loop_joining = False
        return self._loop_still_ours()
