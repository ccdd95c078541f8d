"""Where planned continuous motion first crosses a limit (horizon, altitude, meridian, Sun).

After every command the simulated mount searches its plan ahead for the first time the *rest
point* (where the axes would come to rest if stopped then) leaves the allowed region, and plans
a stop there (:class:`~scopelink.sim.motion.MotionPlan`). Coarse steps of at most 2° of motion
(finer during ramps, up to 24 h of tracking) find the crossing; bisection refines it to 1 µs.
See ``docs/simulator.md``, "Horizon and limit safety inside the physics".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime

from scopelink.astro import Site
from scopelink.mount import Limits
from scopelink.mount.errors import SunAvoidanceError
from scopelink.mount.sun import SunZone, sun_zone
from scopelink.mount.types import AlignmentMode
from scopelink.sim.axis import Axis, AxisPlan
from scopelink.sim.geometry import Geometry

__all__ = ["LimitSearch", "LimitStop"]

_TRACKING_LOOKAHEAD_S = 86400.0
"""How far ahead tracking is checked against the horizon and the mechanical limits."""
_SEARCH_STEP_DEG = 2.0
"""Largest motion between two checks of the limits (a crossing is then found by bisection)."""
_SEARCH_MAX_STEP_S = 900.0
_SEARCH_RAMP_STEP_S = 0.1
_SEARCH_RESOLUTION_S = 1e-6


@dataclass(frozen=True, slots=True)
class LimitStop:
    """Motion stopped (or scheduled to stop) by the physics at elapsed time ``at_s``.

    ``replaced`` holds each axis's plan from ``at_s`` on as it was before the stop (and
    ``moving_until`` when manual moves were to end), so a new command issued before the stop can
    restore it and plan afresh.
    """

    at_s: float
    reason: str
    replaced: tuple[AxisPlan, AxisPlan]
    moving_until: tuple[float, float]


class LimitSearch:
    """The search over the plan of ``axes`` as it stands, from elapsed time ``start`` on.

    ``sun_zone`` is the Sun avoidance zone at ``start`` (None: off); it moves with the Sun.
    """

    def __init__(
        self,
        axes: tuple[Axis, Axis],
        geometry: Geometry,
        limits: Limits,
        sun_zone: SunZone | None,
        start: float,
    ) -> None:
        self.axes = axes
        self.geometry = geometry
        self._limits = limits
        self._sun_zone = sun_zone
        self._start = start

    def first_crossing(self) -> float | None:
        """The elapsed time the rest point first leaves the allowed region (None: never).

        Motion away from a limit is always allowed, also when the mount already sits beyond it:
        only going further out than at ``start`` counts.
        """
        start = self._start
        floor = min(0.0, self._margin_at(start)) - 1e-9
        end = self._search_end(start)
        previous = t = start
        while True:
            if self._margin_at(t) < floor:
                break
            if t >= end:
                return None
            previous, t = t, min(t + self._search_step(t), end)
        low, high = previous, t
        while high - low > _SEARCH_RESOLUTION_S:
            middle = 0.5 * (low + high)
            inside = self._margin_at(middle, exact=True) >= floor
            low, high = (middle, high) if inside else (low, middle)
        return low

    def _margin_at(self, t: float, *, exact: bool = False) -> float:
        """How far (degrees) the physical rest point at ``t`` is inside every limit.

        Braking from a tracking rate moves < 1e-5°, so the coarse search counts only kinematic
        motion (one sky evaluation per step); ``exact`` adds the tracking rate too.
        """
        counters = []
        for axis in self.axes:
            if exact:
                counters.append(axis.rest_position_if_stopped_at(t))
            else:
                _, rate = axis.kinematic_at(t)
                braking = rate * abs(rate) / (2.0 * axis.acceleration_deg_s2)
                counters.append(axis.unwrapped_position_at(t) + braking)
        physical = [c - a.counter_offset_deg for c, a in zip(counters, self.axes, strict=True)]
        margin = min(
            self.geometry.axis_margin_deg(physical[0], physical[1]),
            self.geometry.meridian_margin_deg(physical[0], physical[1], self._limits),
        )
        # The limits hold in the frame the user sees (the counters, after syncs) and, since the
        # simulator knows the truth, where the tube physically points.
        synced = any(axis.counter_offset_deg != 0.0 for axis in self.axes)
        for primary, secondary in (counters, physical) if synced else (physical,):
            alt, az = self.geometry.to_observed(primary, secondary)
            margin = min(
                margin,
                alt - self._limits.horizon_at(az),
                self._limits.max_altitude_deg - alt,
                self._sun_margin(alt, az, t),
            )
        return margin

    def _sun_margin(self, alt: float, az: float, t: float) -> float:
        """How far (degrees) the tube at ``t`` is outside the Sun avoidance zone."""
        zone = self._sun_zone
        if zone is None:
            return math.inf
        return zone.distance_deg(alt, az, later_s=t - self._start) - zone.radius_deg

    def _search_step(self, t: float) -> float:
        step = _SEARCH_MAX_STEP_S
        for axis in self.axes:
            rate = abs(axis.rate_at(t))
            if rate > 0.0:
                step = min(step, _SEARCH_STEP_DEG / rate)
            if axis.segment_at(t).acceleration_deg_s2 != 0.0:
                step = min(step, _SEARCH_RAMP_STEP_S)
            change = axis.next_change_after(t)
            if change is not None and change - t > _SEARCH_RESOLUTION_S:
                step = min(step, change - t)
        return step

    def _search_end(self, start: float) -> float:
        finals = [axis.final_segment for axis in self.axes]
        settled = max(start, *(segment.start_s for segment in finals))
        settled = max(settled, *(axis.final_follow.start_s for axis in self.axes))
        if any(axis.final_follow.trajectory is not None for axis in self.axes):
            return settled + _TRACKING_LOOKAHEAD_S
        rates = [abs(segment.rate_deg_s) for segment in finals if segment.rate_deg_s != 0.0]
        if rates:
            return settled + min(_TRACKING_LOOKAHEAD_S, 400.0 / min(rates))
        return settled


def sun_zone_or_none(
    limits: Limits, site: Site, when: datetime, mode: AlignmentMode
) -> SunZone | None:
    """The Sun avoidance zone the physics stops at, at ``when`` (None when it is off, or when the
    clock is outside the ephemeris: the Mount API then refuses every goto until the time is set,
    and the physics must not fail every command meanwhile)."""
    try:
        return sun_zone(limits.sun_avoidance_deg, site, when, mode)
    except SunAvoidanceError:
        return None
