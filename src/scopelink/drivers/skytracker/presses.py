"""Timed presses: a mean rate finer than the box's 1″/s ``K`` steps (docs/tracking.md).

In GUIDE mode an arrow adds ``K`` arcsec/s (1-255, whole numbers, one per axis) to the box's
tracking. A rate in between is a press of part of every period: pressed for ``duty`` of
:data:`PRESS_PERIOD_S` at speed ``K`` gives ``K x duty`` on average. ``K`` is chosen a little
above the wanted rate (so the duty is high and the ripple small) and kept while it still fits,
so that ``K`` (three bytes and a read-back) is not sent every period.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scopelink.mount import MountAxis
from scopelink.protocol.skytracker import Direction, TrackerMode

from .motion import GUIDE_SPEED_MAX_ARCSEC_S, AxisMotion

__all__ = ["MIN_PRESS_ARCSEC_S", "PRESS_PERIOD_S", "SPEED_HEADROOM", "AxisPress", "plan_press"]

PRESS_PERIOD_S = 0.5
"""Real seconds per press period: each axis is pressed once per period (at most three short
exchanges on the line: press, release one axis, release the other)."""

SPEED_HEADROOM = 1.15
"""A new ``K`` is the wanted rate times this, rounded up: duty about 87 %."""

MIN_PRESS_ARCSEC_S = 0.02
"""A wanted rate below this is no press at all (a 20 ms press of 1″/s)."""

_POSITIVE = {MountAxis.PRIMARY: Direction.RIGHT, MountAxis.SECONDARY: Direction.UP}
_NEGATIVE = {MountAxis.PRIMARY: Direction.LEFT, MountAxis.SECONDARY: Direction.DOWN}


@dataclass(frozen=True, slots=True)
class AxisPress:
    """One axis in one period: press ``direction`` at ``speed`` (″/s) for ``duty`` of it."""

    axis: MountAxis
    direction: Direction
    speed_arcsec_s: int
    duty: float
    saturated: bool
    """The wanted rate was beyond 255″/s: pressed all the period at 255."""

    @property
    def rate_deg_s(self) -> float:
        """The signed rate while pressed (°/s): what the horizon guard is told."""
        sign = 1.0 if self.direction in (Direction.RIGHT, Direction.UP) else -1.0
        return sign * self.speed_arcsec_s / 3600.0

    @property
    def motion(self) -> AxisMotion:
        """The held GUIDE-mode motion this press is while it lasts."""
        return AxisMotion(self.direction, TrackerMode.GUIDE, self.speed_arcsec_s, self.rate_deg_s)


def _speed_for(wanted: float, current: int) -> int:
    if wanted <= current <= max(2.0, 2.0 * wanted):
        return current
    return max(1, min(GUIDE_SPEED_MAX_ARCSEC_S, math.ceil(wanted * SPEED_HEADROOM)))


def plan_press(axis: MountAxis, wanted_arcsec_s: float, current_speed: int) -> AxisPress | None:
    """How to give ``wanted_arcsec_s`` (signed, on top of tracking) on ``axis`` this period;
    None below :data:`MIN_PRESS_ARCSEC_S`. PRIMARY is azimuth (positive: RIGHT, compass azimuth
    increasing), SECONDARY altitude (positive: UP); ``current_speed`` is ``K`` on the axis now."""
    size = abs(wanted_arcsec_s)
    if not math.isfinite(size) or size < MIN_PRESS_ARCSEC_S:
        return None
    direction = _POSITIVE[axis] if wanted_arcsec_s > 0 else _NEGATIVE[axis]
    speed = _speed_for(size, current_speed)
    saturated = size > GUIDE_SPEED_MAX_ARCSEC_S
    return AxisPress(axis, direction, speed, min(1.0, size / speed), saturated)
