"""One motor axis with exact, closed-form motion.

An axis's future is a list of :class:`Segment` s, each a constant-acceleration motion (the
*kinematic* part) optionally added to a *followed trajectory* (a smooth function of time such as
a star's hour angle, used for tracking). The position at any time is evaluated in closed form from
the segment in force, so it does not depend on how often anyone looks: the clock can run x1000
and every reading stays exact.

Commands (``set_rate``, ``slew_to``, ``stop``, ``follow``...) take effect at a time ``at``
(default: now). They keep the plan up to that time and replace everything after it, so
commands may be scheduled ahead (a guide pulse schedules its own end).

Units: degrees, seconds, degrees per second. A *wrapping* axis (RA of a fork, azimuth) reports
positions in [0, 360) and takes the short way round; a bounded one reports the raw angle.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Callable
from dataclasses import dataclass, replace

__all__ = [
    "Axis",
    "Phase",
    "Segment",
    "Trajectory",
    "plan_move",
    "ramp_phase",
]

Trajectory = Callable[[float], float]
"""A followed motion: axis degrees as a function of elapsed simulated seconds."""

_DERIVATIVE_STEP_S = 0.01
"""Half-width of the central difference that gives a followed trajectory's rate."""


@dataclass(frozen=True, slots=True)
class Phase:
    """A stretch of constant acceleration (0 for a cruise)."""

    duration_s: float
    acceleration_deg_s2: float


def ramp_phase(from_rate: float, to_rate: float, acceleration: float) -> Phase:
    """The phase that changes the rate from ``from_rate`` to ``to_rate`` as fast as allowed."""
    duration = abs(to_rate - from_rate) / acceleration
    if duration == 0.0:
        return Phase(0.0, 0.0)
    return Phase(duration, math.copysign(acceleration, to_rate - from_rate))


def plan_move(
    distance: float, start_rate: float, max_rate: float, acceleration: float
) -> tuple[Phase, ...]:
    """The time-optimal phases that cover ``distance`` from ``start_rate`` and end at rest.

    Bang-coast-bang: ramp to a peak rate (at most ``max_rate``), cruise, ramp to zero; a triangle
    when the distance is too short to reach ``max_rate``. If the axis cannot stop before the
    target, it ramps through zero and comes back (one continuous ramp, still time-optimal).
    """
    stopping_distance = start_rate * abs(start_rate) / (2.0 * acceleration)
    beyond = distance - stopping_distance
    if beyond == 0.0:
        return (ramp_phase(start_rate, 0.0, acceleration),)
    # Work in the direction of travel, so the remaining distance is positive.
    sign = 1.0 if beyond > 0.0 else -1.0
    remaining = sign * distance
    rate = sign * start_rate
    phases: list[Phase] = []
    if rate < 0.0:  # moving away: stop first, then it is a move from rest
        phases.append(ramp_phase(rate, 0.0, acceleration))
        remaining += rate * rate / (2.0 * acceleration)
        rate = 0.0
    peak = min(math.sqrt(acceleration * remaining + rate * rate / 2.0), max_rate)
    ramp_distance = abs(peak - rate) * (peak + rate) / (2.0 * acceleration)
    brake_distance = peak * peak / (2.0 * acceleration)
    cruise_distance = max(0.0, remaining - ramp_distance - brake_distance)
    phases.append(ramp_phase(rate, peak, acceleration))
    if cruise_distance > 0.0:
        phases.append(Phase(cruise_distance / peak, 0.0))
    phases.append(ramp_phase(peak, 0.0, acceleration))
    return tuple(
        Phase(p.duration_s, sign * p.acceleration_deg_s2) for p in phases if p.duration_s > 0.0
    )


@dataclass(frozen=True, slots=True)
class Segment:
    """Motion from ``start_s`` until the next segment starts.

    The kinematic part is ``offset + rate τ + acceleration τ²/2`` (τ = t - start); the position is
    that plus ``follow(t)`` when a trajectory is followed.
    """

    start_s: float
    offset_deg: float
    rate_deg_s: float
    acceleration_deg_s2: float
    follow: Trajectory | None = None

    def kinematic_at(self, t: float) -> tuple[float, float]:
        """Kinematic (position, rate) at ``t``."""
        tau = t - self.start_s
        position = self.offset_deg + tau * (self.rate_deg_s + 0.5 * self.acceleration_deg_s2 * tau)
        return position, self.rate_deg_s + self.acceleration_deg_s2 * tau


class Axis:
    """One motor axis: closed-form motion under a rate limit and an acceleration limit.

    ``position`` is the motor *counter* the controller reads; :meth:`set_position` redefines it
    (the motor does not move), and ``counter_offset_deg`` accumulates those redefinitions so the
    physical angle stays known (``physical = counter - counter_offset``).
    """

    def __init__(
        self,
        name: str,
        *,
        max_rate_deg_s: float,
        acceleration_deg_s2: float,
        time_source: Callable[[], float],
        position_deg: float = 0.0,
        wrap: bool = False,
    ) -> None:
        if not (max_rate_deg_s > 0.0 and acceleration_deg_s2 > 0.0):
            raise ValueError("an axis needs a positive rate limit and a positive acceleration")
        self.name = name
        self.max_rate_deg_s = max_rate_deg_s
        self.acceleration_deg_s2 = acceleration_deg_s2
        self.wrap = wrap
        self._time = time_source
        self._segments: list[Segment] = [Segment(time_source(), position_deg, 0.0, 0.0)]
        self.counter_offset_deg = 0.0

    # --- reading --------------------------------------------------------------------------------

    def now(self) -> float:
        return self._time()

    @property
    def segments(self) -> tuple[Segment, ...]:
        """The plan in force (for inspection and tests)."""
        return tuple(self._segments)

    def segment_at(self, t: float) -> Segment:
        """The segment in force at ``t`` (the earliest kept one for times before it)."""
        index = bisect_right([s.start_s for s in self._segments], t) - 1
        return self._segments[max(index, 0)]

    def unwrapped_position_at(self, t: float) -> float:
        """Counter position at ``t`` without wrapping (continuous in time)."""
        segment = self.segment_at(t)
        position, _ = segment.kinematic_at(t)
        return position + segment.follow(t) if segment.follow is not None else position

    def position_at(self, t: float) -> float:
        """Counter position at ``t``: in [0, 360) on a wrapping axis."""
        position = self.unwrapped_position_at(t)
        return position % 360.0 if self.wrap else position

    def rate_at(self, t: float) -> float:
        """Rate at ``t`` in degrees per second (kinematic plus followed)."""
        segment = self.segment_at(t)
        _, rate = segment.kinematic_at(t)
        if segment.follow is not None:
            rate += self._difference(segment.follow, t)
        return rate

    def rest_position_if_stopped_at(self, t: float) -> float:
        """Where the axis would come to rest (unwrapped) if told to stop at ``t``."""
        rate = self.rate_at(t)
        return self.unwrapped_position_at(t) + rate * abs(rate) / (2.0 * self.acceleration_deg_s2)

    def physical_position_at(self, t: float) -> float:
        """The physical angle at ``t`` (unwrapped): the counter minus every redefinition."""
        return self.unwrapped_position_at(t) - self.counter_offset_deg

    def is_following_at(self, t: float) -> bool:
        return self.segment_at(t).follow is not None

    def is_moving_at(self, t: float) -> bool:
        """Whether the axis turns at ``t`` (tracking counts as moving)."""
        segment = self.segment_at(t)
        return segment.follow is not None or self.rate_at(t) != 0.0

    def next_change_after(self, t: float) -> float | None:
        """Start of the first planned segment after ``t``, if any."""
        for segment in self._segments:
            if segment.start_s > t:
                return segment.start_s
        return None

    def segments_from(self, t: float) -> tuple[Segment, ...]:
        """The planned segments starting at or after ``t``."""
        return tuple(s for s in self._segments if s.start_s >= t)

    def replace_from(self, t: float, segments: tuple[Segment, ...]) -> None:
        """Replace the plan from ``t`` on by ``segments`` (as saved by :meth:`segments_from`)."""
        self._cut(t)
        self._segments.extend(segments)

    @property
    def final_segment(self) -> Segment:
        """The open-ended motion the plan settles into."""
        return self._segments[-1]

    @property
    def position(self) -> float:
        return self.position_at(self.now())

    @property
    def rate(self) -> float:
        return self.rate_at(self.now())

    @property
    def is_moving(self) -> bool:
        return self.is_moving_at(self.now())

    # --- commanding -----------------------------------------------------------------------------

    def set_rate(self, rate_deg_s: float, *, at: float | None = None) -> float:
        """Ramp the kinematic rate to ``rate_deg_s`` (added to any followed trajectory).

        Returns the time the ramp ends.
        """
        self._check_rate(rate_deg_s)
        t = self._when(at)
        segment = self.segment_at(t)
        offset, rate = segment.kinematic_at(t)
        self._cut(t)
        phase = ramp_phase(rate, rate_deg_s, self.acceleration_deg_s2)
        end = t + phase.duration_s
        if phase.duration_s > 0.0:
            ramp = Segment(t, offset, rate, phase.acceleration_deg_s2, segment.follow)
            self._segments.append(ramp)
            offset, _ = ramp.kinematic_at(end)
        self._segments.append(Segment(end, offset, rate_deg_s, 0.0, segment.follow))
        return end

    def stop(self, *, at: float | None = None) -> float:
        """Ramp down to rest (a followed trajectory is dropped). Returns the time at rest."""
        t = self._when(at)
        position, rate = self.unwrapped_position_at(t), self.rate_at(t)
        self._cut(t)
        phase = ramp_phase(rate, 0.0, self.acceleration_deg_s2)
        end = t + phase.duration_s
        if phase.duration_s > 0.0:
            self._segments.append(Segment(t, position, rate, phase.acceleration_deg_s2))
            position += rate * abs(rate) / (2.0 * self.acceleration_deg_s2)
        self._segments.append(Segment(end, position, 0.0, 0.0))
        return end

    def slew_phases(
        self, target_deg: float, *, max_rate_deg_s: float | None = None, at: float | None = None
    ) -> tuple[float, tuple[Phase, ...]]:
        """The unwrapped target and the phases a slew to ``target_deg`` would take (no change)."""
        t = self._when(at)
        position, rate = self.unwrapped_position_at(t), self.rate_at(t)
        target = self._unwrapped_target(target_deg, position)
        limit = self._limit(max_rate_deg_s)
        return target, plan_move(target - position, rate, limit, self.acceleration_deg_s2)

    def slew_duration(
        self, target_deg: float, *, max_rate_deg_s: float | None = None, at: float | None = None
    ) -> float:
        """How long a slew to ``target_deg`` starting at ``at`` would take."""
        _, phases = self.slew_phases(target_deg, max_rate_deg_s=max_rate_deg_s, at=at)
        return sum(p.duration_s for p in phases)

    def slew_to(
        self,
        target_deg: float,
        *,
        max_rate_deg_s: float | None = None,
        at: float | None = None,
        then_follow: Trajectory | None = None,
    ) -> float:
        """Slew to ``target_deg`` and land on it exactly; returns the landing time.

        A wrapping axis takes the short way round. After landing the axis holds still, or
        follows ``then_follow`` from the landing point (the small rate of a tracked trajectory
        is picked up at once: far less than one motor step of acceleration).
        """
        t = self._when(at)
        position, rate = self.unwrapped_position_at(t), self.rate_at(t)
        target, phases = self.slew_phases(target_deg, max_rate_deg_s=max_rate_deg_s, at=t)
        self._cut(t)
        start, offset = t, position
        for phase in phases:
            segment = Segment(start, offset, rate, phase.acceleration_deg_s2)
            self._segments.append(segment)
            start += phase.duration_s
            offset, rate = segment.kinematic_at(start)
        # Rounding in the phase sums is ~1e-13 degrees; land on the target itself.
        if then_follow is None:
            self._segments.append(Segment(start, target, 0.0, 0.0))
        else:
            self._segments.append(
                Segment(start, target - then_follow(start), 0.0, 0.0, then_follow)
            )
        return start

    def follow(self, trajectory: Trajectory, *, at: float | None = None) -> None:
        """Follow ``trajectory`` from ``at`` on, keeping the current position as an offset."""
        t = self._when(at)
        position = self.unwrapped_position_at(t)
        self._cut(t)
        self._segments.append(Segment(t, position - trajectory(t), 0.0, 0.0, trajectory))

    def rebase(self, trajectory: Trajectory | None, *, at: float | None = None) -> None:
        """Swap the followed trajectory for ``trajectory`` (``None``: none) from ``at`` on.

        The position does not jump. Any kinematic motion in progress (a guide pulse, a rate
        offset) continues unchanged on top of the new trajectory; later segments that followed
        the old one follow the new one. Only the followed rate changes at once (by a tracking
        rate at most, far below what the acceleration limit allows in one motor step).
        """
        t = self._when(at)
        current = self.segment_at(t)
        old = current.follow
        shift = (old(t) if old is not None else 0.0) - (trajectory(t) if trajectory else 0.0)
        offset, rate = current.kinematic_at(t)
        later = [s for s in self._segments if s.start_s > t]
        self._cut(t)
        self._segments.append(
            Segment(t, offset + shift, rate, current.acceleration_deg_s2, trajectory)
        )
        self._segments.extend(
            replace(s, offset_deg=s.offset_deg + shift, follow=trajectory) if s.follow is old else s
            for s in later
        )

    def set_position(self, position_deg: float, *, at: float | None = None) -> None:
        """Redefine the counter to read ``position_deg`` at ``at``; the motor does not move."""
        t = self._when(at)
        current = self.unwrapped_position_at(t)
        shift = position_deg - current
        if self.wrap:
            shift = _wrap_signed(shift)
        self._segments = [replace(s, offset_deg=s.offset_deg + shift) for s in self._segments]
        self.counter_offset_deg += shift

    # --- internals ------------------------------------------------------------------------------

    def _when(self, at: float | None) -> float:
        return self.now() if at is None else at

    def _limit(self, max_rate_deg_s: float | None) -> float:
        if max_rate_deg_s is None:
            return self.max_rate_deg_s
        if not 0.0 < max_rate_deg_s <= self.max_rate_deg_s:
            raise ValueError(
                f"{self.name}: slew rate {max_rate_deg_s}°/s must lie in (0, {self.max_rate_deg_s}]"
            )
        return max_rate_deg_s

    def _check_rate(self, rate_deg_s: float) -> None:
        if not (math.isfinite(rate_deg_s) and abs(rate_deg_s) <= self.max_rate_deg_s):
            raise ValueError(
                f"{self.name}: rate {rate_deg_s}°/s exceeds the limit of ±{self.max_rate_deg_s}°/s"
            )

    def _unwrapped_target(self, target_deg: float, position: float) -> float:
        if not math.isfinite(target_deg):
            raise ValueError(f"{self.name}: target {target_deg} is not a number")
        return position + _wrap_signed(target_deg - position) if self.wrap else target_deg

    def _cut(self, t: float) -> None:
        """Keep the plan strictly before ``t``; the caller appends what happens from ``t``.

        History is not kept: segments over before the present are dropped, so a long session
        (hours of guide pulses) stays small and fast.
        """
        kept = [s for s in self._segments if s.start_s < t]
        present = self.now()
        while len(kept) > 1 and kept[1].start_s <= present:
            kept.pop(0)
        self._segments = kept

    def _difference(self, trajectory: Trajectory, t: float) -> float:
        step = trajectory(t + _DERIVATIVE_STEP_S) - trajectory(t - _DERIVATIVE_STEP_S)
        if self.wrap:
            step = _wrap_signed(step)
        return step / (2.0 * _DERIVATIVE_STEP_S)


def _wrap_signed(degrees: float) -> float:
    """``degrees`` wrapped to [-180, 180)."""
    return (degrees + 180.0) % 360.0 - 180.0
