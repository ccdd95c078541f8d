"""One motor axis with exact, closed-form motion.

The counter is the sum of two continuous parts, each planned ahead:

* the *kinematic* part: :class:`Segment` s of constant acceleration (ramps, cruises, slews);
* the *followed* part: :class:`FollowPiece` s, each adding the change of a smooth function of
  time (a star's hour angle, for tracking) since the piece began, so swapping the function
  never makes the axis jump.

The position at any time is evaluated in closed form, so it does not depend on how often anyone
looks: the clock can run x1000 and every reading stays exact.

Commands (``set_rate``, ``slew_to``, ``stop``, ``follow``...) take effect at a time ``at``
(default: now) and replace what was planned after it, so commands may be scheduled ahead (a guide
pulse schedules its own end).

Units: degrees, seconds, degrees per second. A *wrapping* axis (RA of a fork, azimuth) reports
positions in [0, 360) and takes the short way round; a bounded one reports the raw angle.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TypeVar

from scopelink.astro import wrap_signed_degrees

__all__ = [
    "Axis",
    "AxisPlan",
    "FollowPiece",
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
    """Kinematic motion from ``start_s`` until the next segment starts.

    Position ``offset + rate τ + acceleration τ²/2`` and rate ``rate + acceleration τ``, with
    τ = t - start.
    """

    start_s: float
    offset_deg: float
    rate_deg_s: float
    acceleration_deg_s2: float

    def kinematic_at(self, t: float) -> tuple[float, float]:
        """(position, rate) at ``t``."""
        tau = t - self.start_s
        position = self.offset_deg + tau * (self.rate_deg_s + 0.5 * self.acceleration_deg_s2 * tau)
        return position, self.rate_deg_s + self.acceleration_deg_s2 * tau


@dataclass(frozen=True, slots=True)
class FollowPiece:
    """Followed motion from ``start_s``: ``base + trajectory(t) - trajectory(start)``.

    With no trajectory the followed part holds ``base``.
    """

    start_s: float
    base_deg: float
    trajectory: Trajectory | None = None
    origin_deg: float = 0.0

    def value_at(self, t: float) -> float:
        if self.trajectory is None:
            return self.base_deg
        return self.base_deg + self.trajectory(t) - self.origin_deg


_Planned = TypeVar("_Planned", Segment, FollowPiece)


@dataclass(frozen=True, slots=True)
class AxisPlan:
    """Both parts of an axis's plan from some time on (to put back with ``restore_plan``)."""

    segments: tuple[Segment, ...]
    follows: tuple[FollowPiece, ...]


class Axis:
    """One motor axis: closed-form motion under a rate limit and an acceleration limit.

    ``position`` is the motor *counter* the controller reads; :meth:`set_position` redefines it
    (the motor does not move), and ``counter_offset_deg`` accumulates those redefinitions so the
    physical angle stays known (``physical = counter - counter_offset``). The rate and
    acceleration limits bind the kinematic part; a followed trajectory (tracking) adds its own
    slow motion on top.
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
        start = time_source()
        self._segments: list[Segment] = [Segment(start, position_deg, 0.0, 0.0)]
        self._follows: list[FollowPiece] = [FollowPiece(start, 0.0)]
        self.counter_offset_deg = 0.0
        self.history_needed_from: float | None = None
        """Set while a command plans from a time that may already be past on a running clock:
        history from then on is kept (pruning against the live clock would lose it)."""

    # --- reading --------------------------------------------------------------------------------

    def now(self) -> float:
        return self._time()

    @property
    def segments(self) -> tuple[Segment, ...]:
        """The kinematic plan in force (for inspection and tests)."""
        return tuple(self._segments)

    @property
    def follows(self) -> tuple[FollowPiece, ...]:
        """The followed plan in force (for inspection and tests)."""
        return tuple(self._follows)

    def segment_at(self, t: float) -> Segment:
        """The kinematic segment in force at ``t`` (the earliest kept one before it)."""
        return _in_force(self._segments, t)

    def follow_at(self, t: float) -> FollowPiece:
        """The followed piece in force at ``t``."""
        return _in_force(self._follows, t)

    def kinematic_at(self, t: float) -> tuple[float, float]:
        """Kinematic (position, rate) at ``t``: the motor's own commanded motion."""
        return self.segment_at(t).kinematic_at(t)

    def unwrapped_position_at(self, t: float) -> float:
        """Counter position at ``t`` without wrapping (continuous in time)."""
        position, _ = self.kinematic_at(t)
        return position + self.follow_at(t).value_at(t)

    def position_at(self, t: float) -> float:
        """Counter position at ``t``: in [0, 360) on a wrapping axis."""
        position = self.unwrapped_position_at(t)
        return position % 360.0 if self.wrap else position

    def rate_at(self, t: float) -> float:
        """Rate at ``t`` in degrees per second (kinematic plus followed)."""
        _, rate = self.kinematic_at(t)
        trajectory = self.follow_at(t).trajectory
        return rate if trajectory is None else rate + self._difference(trajectory, t)

    def rest_position_if_stopped_at(self, t: float) -> float:
        """Where the axis would come to rest (unwrapped) if told to stop at ``t``."""
        rate = self.rate_at(t)
        return self.unwrapped_position_at(t) + rate * abs(rate) / (2.0 * self.acceleration_deg_s2)

    def physical_position_at(self, t: float) -> float:
        """The physical angle at ``t`` (unwrapped): the counter minus every redefinition."""
        return self.unwrapped_position_at(t) - self.counter_offset_deg

    def is_following_at(self, t: float) -> bool:
        return self.follow_at(t).trajectory is not None

    def is_moving_at(self, t: float) -> bool:
        """Whether the axis turns at ``t`` (tracking counts as moving)."""
        return self.is_following_at(t) or self.kinematic_at(t)[1] != 0.0

    def next_change_after(self, t: float) -> float | None:
        """Start of the first planned segment or piece after ``t``, if any."""
        starts = [s.start_s for s in self._segments] + [f.start_s for f in self._follows]
        later = [start for start in starts if start > t]
        return min(later) if later else None

    @property
    def final_segment(self) -> Segment:
        """The open-ended kinematic motion the plan settles into."""
        return self._segments[-1]

    @property
    def final_follow(self) -> FollowPiece:
        """The open-ended followed motion the plan settles into."""
        return self._follows[-1]

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
        """Ramp the kinematic rate to ``rate_deg_s`` (on top of any followed trajectory).

        Returns the time the ramp ends.
        """
        self._check_rate(rate_deg_s)
        t = self._when(at)
        offset, rate = self.kinematic_at(t)
        self._segments = self._kept(self._segments, t)
        phase = ramp_phase(rate, rate_deg_s, self.acceleration_deg_s2)
        end = t + phase.duration_s
        if phase.duration_s > 0.0:
            ramp = Segment(t, offset, rate, phase.acceleration_deg_s2)
            self._segments.append(ramp)
            offset, _ = ramp.kinematic_at(end)
        self._segments.append(Segment(end, offset, rate_deg_s, 0.0))
        return end

    def stop(self, *, at: float | None = None) -> float:
        """Stop following and ramp down to rest. Returns the time at rest."""
        t = self._when(at)
        offset, _ = self.kinematic_at(t)
        rate = self.rate_at(t)  # the followed rate is taken over by the motor and ramped down
        self._freeze(t)
        self._segments = self._kept(self._segments, t)
        phase = ramp_phase(rate, 0.0, self.acceleration_deg_s2)
        end = t + phase.duration_s
        if phase.duration_s > 0.0:
            self._segments.append(Segment(t, offset, rate, phase.acceleration_deg_s2))
            offset += rate * abs(rate) / (2.0 * self.acceleration_deg_s2)
        self._segments.append(Segment(end, offset, 0.0, 0.0))
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
        held = self._freeze(t)
        self._segments = self._kept(self._segments, t)
        start, offset = t, position - held
        for phase in phases:
            segment = Segment(start, offset, rate, phase.acceleration_deg_s2)
            self._segments.append(segment)
            start += phase.duration_s
            offset, rate = segment.kinematic_at(start)
        # Rounding in the phase sums is ~1e-13 degrees; land on the target itself.
        self._segments.append(Segment(start, target - held, 0.0, 0.0))
        if then_follow is not None:
            self._follows.append(FollowPiece(start, held, then_follow, then_follow(start)))
        return start

    def follow(self, trajectory: Trajectory | None, *, at: float | None = None) -> None:
        """Follow ``trajectory`` (``None``: hold) from ``at`` on, replacing later pieces.

        The position does not jump; only the followed rate changes at once (by a tracking rate
        at most, far below what the acceleration limit allows in one motor step).
        """
        t = self._when(at)
        base = self._follow_value_before(t)
        self._follows = self._kept(self._follows, t)
        self._follows.append(_piece(t, base, trajectory))

    def insert_follow(self, trajectory: Trajectory | None, *, at: float) -> None:
        """Follow ``trajectory`` from ``at`` until the next planned piece.

        Later pieces keep their trajectories and start from wherever this one leaves off.
        """
        pieces = [f for f in self._follows if f.start_s != at]
        pieces.append(_piece(at, 0.0, trajectory))
        pieces.sort(key=lambda f: f.start_s)
        self._prune(pieces)
        chained = pieces[:1]
        for piece in pieces[1:]:
            chained.append(replace(piece, base_deg=chained[-1].value_at(piece.start_s)))
        self._follows = chained

    def set_position(self, position_deg: float, *, at: float | None = None) -> None:
        """Redefine the counter to read ``position_deg`` at ``at``; the motor does not move."""
        t = self._when(at)
        shift = position_deg - self.unwrapped_position_at(t)
        if self.wrap:
            shift = wrap_signed_degrees(shift)
        self._segments = [replace(s, offset_deg=s.offset_deg + shift) for s in self._segments]
        self.counter_offset_deg += shift

    def plan_from(self, t: float) -> AxisPlan:
        """What is planned from ``t`` on (to put back later with :meth:`restore_plan`)."""
        return AxisPlan(
            tuple(s for s in self._segments if s.start_s >= t),
            tuple(f for f in self._follows if f.start_s >= t),
        )

    def restore_plan(self, t: float, plan: AxisPlan) -> None:
        """Replace what is planned from ``t`` on by ``plan`` (as saved by :meth:`plan_from`)."""
        self._segments = [*self._kept(self._segments, t), *plan.segments]
        self._follows = [*self._kept(self._follows, t), *plan.follows]

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
        return position + wrap_signed_degrees(target_deg - position) if self.wrap else target_deg

    def _follow_value_before(self, t: float) -> float:
        """The followed part just before ``t`` (pieces starting at ``t`` ignored)."""
        earlier = [f for f in self._follows if f.start_s < t]
        return (earlier[-1] if earlier else self._follows[0]).value_at(t)

    def _freeze(self, t: float) -> float:
        """Stop following at ``t`` (dropping later pieces); returns the value held."""
        held = self._follow_value_before(t)
        self._follows = [*self._kept(self._follows, t), FollowPiece(t, held)]
        return held

    def _kept(self, items: list[_Planned], t: float) -> list[_Planned]:
        """``items`` strictly before ``t``, without those over before the present.

        History is not kept, so a long session (hours of guide pulses) stays small and fast.
        """
        kept = [item for item in items if item.start_s < t]
        self._prune(kept)
        return kept

    def _prune(self, items: list[_Planned]) -> None:
        present = self.now()
        if self.history_needed_from is not None:
            present = min(present, self.history_needed_from)
        while len(items) > 1 and items[1].start_s < present:
            items.pop(0)

    def _difference(self, trajectory: Trajectory, t: float) -> float:
        step = trajectory(t + _DERIVATIVE_STEP_S) - trajectory(t - _DERIVATIVE_STEP_S)
        if self.wrap:
            step = wrap_signed_degrees(step)
        return step / (2.0 * _DERIVATIVE_STEP_S)


def _in_force(items: list[_Planned], t: float) -> _Planned:
    index = bisect_right([item.start_s for item in items], t) - 1
    return items[max(index, 0)]


def _piece(t: float, base: float, trajectory: Trajectory | None) -> FollowPiece:
    origin = trajectory(t) if trajectory is not None else 0.0
    return FollowPiece(t, base, trajectory, origin)
