"""The motion plan of the two axes: when slews land, when manual motion ends, where tracking
starts afresh, and the stop planned at the first limit.

The simulated mount decides *what* the axes do (a goto's target, the tracking mode, parking);
the plan carries it out on the two :class:`~scopelink.sim.axis.Axis` and keeps the timing
bookkeeping every reading needs. A command runs as ``begin`` (undo a limit stop still ahead),
the motion, then ``resolve_retargets`` and ``stop_at_first_limit``, then ``end_command``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from scopelink.sim.axis import Axis, Trajectory
from scopelink.sim.limit_search import LimitSearch, LimitStop
from scopelink.sim.tracking import PolarAxisPath, SkyPath

__all__ = ["FOREVER", "MotionPlan", "TrackingPathAt"]

FOREVER = math.inf
_LANDING_TOLERANCE_S = 1e-9

TrackingPathAt = Callable[[float], SkyPath | PolarAxisPath | None]
"""The path tracking follows from where the axes are at an elapsed time (None: tracking off)."""


class MotionPlan:
    """What both ``axes`` do from now on, as elapsed times."""

    def __init__(self, axes: tuple[Axis, Axis]) -> None:
        self.axes = axes
        self.goto_until = -FOREVER
        """Elapsed time the goto (or park, or axis slew) lands: slewing until then."""
        self.limit_stop: LimitStop | None = None
        """The last stop at a limit (planned or past), if any."""
        self._landing = [-FOREVER, -FOREVER]
        self._moving_until = [-FOREVER, -FOREVER]
        self._pulse_until = [-FOREVER, -FOREVER]
        self._retarget_at: set[float] = set()
        self._command_at = 0.0
        """Elapsed time at which the command being carried out began."""

    # --- reading ---------------------------------------------------------------------------------

    def counters_at(self, t: float) -> tuple[float, float]:
        """Both axis counters (unwrapped degrees) at elapsed ``t``."""
        return self.axes[0].unwrapped_position_at(t), self.axes[1].unwrapped_position_at(t)

    def stopped_at_limit_by(self, t: float) -> bool:
        """Whether the planned limit stop has begun by elapsed ``t``."""
        return self.limit_stop is not None and self.limit_stop.at_s <= t

    def slewing_at(self, t: float) -> bool:
        """A goto still landing, or an axis still moving at a rate (a guide pulse is not)."""
        return t < self.goto_until or any(t < until for until in self._moving_until)

    def pulse_guiding_at(self, t: float) -> bool:
        return any(t < until for until in self._pulse_until)

    # --- a command's frame -----------------------------------------------------------------------

    def begin(self, now: float, *, replan: bool) -> None:
        """Start a command at elapsed ``now``: undo a limit stop still ahead.

        Every command re-runs the limit search when it has planned its motion. ``replan``:
        the command replaces all motion (goto, park, abort), so what was scheduled is dropped.
        """
        self._command_at = now
        for axis in self.axes:
            axis.history_needed_from = now
        stop = self.limit_stop
        if stop is not None and stop.at_s > now:
            for axis, plan in zip(self.axes, stop.replaced, strict=True):
                axis.restore_plan(stop.at_s, plan)
            self._moving_until = list(stop.moving_until)
            self.limit_stop = None
        if replan:
            self._retarget_at.clear()
            self._landing = [-FOREVER, -FOREVER]
            self.goto_until = -FOREVER
            self._moving_until = [-FOREVER, -FOREVER]
            self.limit_stop = None

    def retarget(self, t: float) -> None:
        """Track afresh from wherever the axes are at elapsed ``t`` (if tracking is on then)."""
        self._retarget_at.add(t)

    def resolve_retargets(self, tracking_path_at: TrackingPathAt) -> None:
        """At each pending time, track the sky position the axes reach then (or hold still).

        Recomputed in time order after every command, so each uses the plan as it now stands
        (two overlapping guide pulses end at two different, correct positions). Motion in
        progress at that time (a ramp, another pulse) carries on; an axis still slewing to a
        goto target is left to its own landing.
        """
        # The command's own time, not a fresh clock reading: on a running clock time passes while
        # the command plans, and a retarget it scheduled at its start must not be dropped as past.
        now = self._command_at
        self._retarget_at = {t for t in self._retarget_at if t >= now}
        for t in sorted(self._retarget_at):
            path = tracking_path_at(t)
            trajectories = (path.primary, path.secondary) if path else (None, None)
            for index, axis in enumerate(self.axes):
                if t >= self._landing[index]:
                    axis.insert_follow(trajectories[index], at=t)

    def stop_at_first_limit(self, search: LimitSearch) -> None:
        """Plan a stop of both axes where ``search`` finds the motion first crossing a limit."""
        self.limit_stop = None
        low = search.first_crossing()
        if low is None:
            return
        replaced = (self.axes[0].plan_from(low), self.axes[1].plan_from(low))
        moving_until = (self._moving_until[0], self._moving_until[1])
        rest = max(axis.stop(at=low) for axis in self.axes)
        self._moving_until = [min(until, rest) for until in self._moving_until]
        alt, az = search.geometry.to_observed(*self.counters_at(rest))
        self.limit_stop = LimitStop(
            low,
            f"motion stopped at a limit (altitude {alt:.2f}°, azimuth {az:.1f}°): the horizon, "
            "the altitude limit, the meridian limit or the Sun avoidance zone; move away or goto "
            "elsewhere",
            replaced,
            moving_until,
        )

    def end_command(self) -> None:
        """The axes may forget the history before the next command."""
        for axis in self.axes:
            axis.history_needed_from = None

    # --- motion ----------------------------------------------------------------------------------

    def land_both_on(self, trajectories: tuple[Trajectory, Trajectory], t: float) -> None:
        """A goto: each axis meets its moving ``trajectory`` and follows it from its landing."""
        for index, trajectory in enumerate(trajectories):
            self._landing[index] = self._land_on(self.axes[index], trajectory, t)
        self.goto_until = max(self._landing)

    def slew_both_to(self, counters: tuple[float, float], t: float) -> None:
        """A goto to fixed counters (alt/az slews, park): both axes land and hold still."""
        for index, (axis, target) in enumerate(zip(self.axes, counters, strict=True)):
            self._landing[index] = axis.slew_to(target, at=t)
        self.goto_until = max(self._landing)

    def slew_axis_to(
        self, index: int, position_deg: float, max_rate_deg_s: float | None, t: float
    ) -> float:
        """Slew one axis to a counter (SynScan "slow goto"); tracking resumes at the landing."""
        self._moving_until[index] = -FOREVER
        landing = self.axes[index].slew_to(position_deg, max_rate_deg_s=max_rate_deg_s, at=t)
        self._landing[index] = landing
        self.goto_until = max(self.goto_until, landing)
        self.retarget(landing)
        return landing

    def move_axis(self, index: int, rate_deg_s: float, t: float) -> None:
        """Turn one axis at a rate (on top of tracking) until told otherwise; 0 stops it."""
        self._take_over_from_goto(index, t)
        end = self.axes[index].set_rate(rate_deg_s, at=t)
        self._moving_until[index] = FOREVER if rate_deg_s != 0.0 else end
        if rate_deg_s == 0.0:
            self.retarget(end)  # track the new position from where the axis stops

    def pulse(self, index: int, rate_deg_s: float, duration_s: float, t: float) -> None:
        """A guide pulse: one axis at ``rate_deg_s`` for exactly ``duration_s``."""
        self._take_over_from_goto(index, t)
        motor = self.axes[index]
        motor.set_rate(rate_deg_s, at=t)
        self.retarget(motor.set_rate(0.0, at=t + duration_s))
        self._pulse_until[index] = t + duration_s

    def stop(self, t: float) -> None:
        """Ramp both axes to rest; tracking, if on, resumes from the rest point."""
        rest = max(axis.stop(at=t) for axis in self.axes)
        self._moving_until = [rest, rest]
        self.retarget(rest)

    def _take_over_from_goto(self, index: int, t: float) -> None:
        """A manual motion of an axis cancels the goto it was landing (as on a hand control)."""
        if t < self._landing[index]:
            self.axes[index].follow(None, at=t)
            self._landing[index] = -FOREVER
            self.goto_until = max(self._landing)

    @staticmethod
    def _land_on(axis: Axis, trajectory: Trajectory, t: float) -> float:
        """Slew ``axis`` so it meets the moving ``trajectory`` and follows it; returns landing.

        Solves T = t + duration(trajectory(T)): fixed-point steps (a contraction, since the sky
        moves far slower than the axis), then bisection if a tiny move makes that slow.
        """

        def landing(when: float) -> float:
            return t + axis.slew_duration(trajectory(when), at=t)

        when = landing(t)
        for _ in range(6):
            when = landing(when)
        if abs(landing(when) - when) > _LANDING_TOLERANCE_S:
            low, high = t, max(when, t) + 1.0
            while landing(high) > high:
                high = t + 2.0 * (high - t)
            while high - low > _LANDING_TOLERANCE_S:
                middle = 0.5 * (low + high)
                low, high = (middle, high) if landing(middle) > middle else (low, middle)
            when = high
        return axis.slew_to(trajectory(when), at=t, then_follow=trajectory)
