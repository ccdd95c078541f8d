"""The simulated mount: a :class:`~scopelink.mount.Mount` made of two :class:`Axis` and a clock.

Nothing runs in the background. Every command plans the axes' motion from "now" in closed form
(slews, ramps, tracking that follows the target through ``astro``, guide pulses, and a stop where
continuous motion would cross the horizon or a mechanical limit), and every reading evaluates
that plan at the clock's current time. So a stepped clock advanced by a test, or a clock running
x1000, gives exactly the same positions. See ``docs/simulator.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime

from scopelink.astro import (
    PierSide,
    Site,
    angular_separation_deg,
    j2000_to_apparent,
    j2000_to_observed,
    observed_to_j2000,
)
from scopelink.mount import (
    Capabilities,
    GuideDirection,
    Identity,
    Limits,
    Mount,
    MountAxis,
    MountState,
    TrackingMode,
)
from scopelink.mount.errors import SunAvoidanceError
from scopelink.mount.sun import SunZone, sun_zone
from scopelink.mount.syncs import SyncFrame
from scopelink.mount.types import AlignmentMode
from scopelink.sim.axis import Axis, AxisPlan, Trajectory
from scopelink.sim.clock import SimClock
from scopelink.sim.geometry import Geometry, geometry_for
from scopelink.sim.models import EQ6, MountModel
from scopelink.sim.tracking import (
    PolarAxisPath,
    SkyPath,
    SkyTarget,
    ra_drift_hours_per_s,
    tracking_rate_deg_s,
)

__all__ = ["LimitStop", "SimulatedMount"]

_FOREVER = math.inf
_TRACKING_LOOKAHEAD_S = 86400.0
"""How far ahead tracking is checked against the horizon and the mechanical limits."""
_POLE_TRACKING_DEG = 0.5
"""Within this of the celestial pole, tracking turns the polar axis uniformly (PolarAxisPath)."""
_SEARCH_STEP_DEG = 2.0
"""Largest motion between two checks of the limits (a crossing is then found by bisection)."""
_SEARCH_MAX_STEP_S = 900.0
_SEARCH_RAMP_STEP_S = 0.1
_SEARCH_RESOLUTION_S = 1e-6
_LANDING_TOLERANCE_S = 1e-9


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


class SimulatedMount(Mount):
    """A simulated mount of a given :class:`MountModel`.

    ``clock`` defaults to a real-time :class:`SimClock`; tests pass ``SimClock.stepped(...)``.
    ``home`` are the counters at power-on (default: the geometry's home: counterweight down at
    the pole, or level pointing north); ``park_counters`` defaults to ``home``. ``aligned``
    is what the mount reports before any sync (the simulation is always physically perfect).
    """

    poll_interval_s = 0.05  # a refresh costs only CPU: 20 Hz is plenty for any front end
    refresh_uses_wire = False
    stops_itself_at_limits = True  # the physics plans a stop at every limit

    def __init__(
        self,
        model: MountModel = EQ6,
        *,
        site: Site,
        clock: SimClock | None = None,
        limits: Limits | None = None,
        aligned: bool = True,
        home: tuple[float, float] | None = None,
        park_counters: tuple[float, float] | None = None,
        meridian_tolerance_deg: float = 7.5,
        guide_rate_deg_s: float | None = None,
    ) -> None:
        self.clock = clock if clock is not None else SimClock()
        super().__init__(site=site, limits=limits, clock=self.clock.now)
        self.model = model
        self._meridian_tolerance_deg = meridian_tolerance_deg
        self.geometry: Geometry = self._make_geometry(site)
        start = home if home is not None else self.geometry.home
        self.axes: tuple[Axis, Axis] = (
            self._make_axis("primary", start[0], wrap=self.geometry.primary_wraps),
            self._make_axis("secondary", start[1], wrap=False),
        )
        self.park_counters: tuple[float, float] = park_counters or start
        self.guide_rate_deg_s = (
            guide_rate_deg_s if guide_rate_deg_s is not None else model.guide_rate_deg_s
        )
        self._aligned = aligned
        self._connected = False
        self._parked = False
        self._park_landing = _FOREVER
        """Elapsed time the park slew lands: parked from then on, not before."""
        self._tracking = TrackingMode.OFF
        self._goto_until = -_FOREVER
        self._landing = [-_FOREVER, -_FOREVER]
        self._moving_until = [-_FOREVER, -_FOREVER]
        self._pulse_until = [-_FOREVER, -_FOREVER]
        self._retarget_at: set[float] = set()
        self._command_at = 0.0
        """Elapsed time at which the command being carried out began."""
        self._limit_stop: LimitStop | None = None
        self._sun_search: tuple[SunZone | None, float] = (None, 0.0)
        self._capabilities = self._make_capabilities()

    # --- identity -------------------------------------------------------------------------------

    @property
    def capabilities(self) -> Capabilities:
        return self._capabilities

    @property
    def identity(self) -> Identity:
        return Identity("simulator", self.model.name, firmware="scopelink-sim", link="memory")

    # --- reading --------------------------------------------------------------------------------

    def elapsed(self) -> float:
        """Elapsed simulated seconds (the time base of the axes)."""
        return self.clock.elapsed()

    @property
    def tracking(self) -> TrackingMode:
        """The tracking mode in force now."""
        self._settle(self.elapsed())
        return self._tracking

    @property
    def aligned(self) -> bool:
        return self._aligned

    def set_aligned(self, aligned: bool) -> None:
        """Set what the mount reports as its alignment state (e.g. after a star alignment)."""
        self._aligned = aligned

    @property
    def goto_in_progress(self) -> bool:
        """Whether a goto, park or axis slew has not landed yet (SynScan ``L``)."""
        return self.elapsed() < self._goto_until

    @property
    def goto_ends_at(self) -> float | None:
        """Elapsed time the goto (or park, or axis slew) in progress lands, if one is."""
        return self._goto_until if self.goto_in_progress else None

    @property
    def limit_stop(self) -> LimitStop | None:
        """The last stop at the horizon or a mechanical limit (planned or past), if any."""
        return self._limit_stop

    def counters_at(self, t: float) -> tuple[float, float]:
        """Both axis counters (unwrapped degrees) at elapsed ``t``."""
        return self.axes[0].unwrapped_position_at(t), self.axes[1].unwrapped_position_at(t)

    def observed_at(self, t: float) -> tuple[float, float]:
        """Observed (altitude, azimuth) the mount believes it points at, at elapsed ``t``."""
        return self.geometry.to_observed(*self.counters_at(t))

    def j2000_at(self, t: float) -> tuple[float, float]:
        """J2000 (RA hours, Dec degrees) the mount believes it points at, at elapsed ``t``."""
        alt, az = self.observed_at(t)
        return observed_to_j2000(alt, az, self.clock.datetime_at(t), self._site)

    def state_at(self, t: float) -> MountState:
        """The exact state at elapsed ``t`` (does not publish it; ``t`` may lie ahead)."""
        primary, secondary = self.counters_at(t)
        alt, az = self.geometry.to_observed(primary, secondary)
        when = self.clock.datetime_at(t)
        ra, dec = observed_to_j2000(alt, az, when, self._site)
        ra_of_date, dec_of_date = j2000_to_apparent(ra, dec, when)
        stopped = self._limit_stop is not None and self._limit_stop.at_s <= t
        moving = any(t < until for until in self._moving_until)
        problems = (self._limit_stop.reason,) if self._limit_stop and stopped else ()
        return MountState(
            read_at=when,
            connected=self._connected,
            ra_j2000_hours=ra,
            dec_j2000_deg=dec,
            ra_of_date_hours=ra_of_date,
            dec_of_date_deg=dec_of_date,
            alt_deg=alt,
            az_deg=az,
            pier_side=self.geometry.pier_side(primary, secondary),
            slewing=t < self._goto_until or moving,
            tracking=TrackingMode.OFF if stopped else self._tracking,
            parked=self._parked and t >= self._park_landing,
            aligned=self._aligned,
            pulse_guiding=any(t < until for until in self._pulse_until),
            problems=problems,
        )

    def snapshot(self) -> MountState:
        """Compute, publish and return the state now, without awaiting."""
        state = self.state_at(self.elapsed())
        self._publish(state)
        return state

    def step(self, seconds: float) -> MountState:
        """Advance the clock by ``seconds`` and return the state then (deterministic)."""
        self.clock.advance(seconds)
        return self.snapshot()

    def sync_distance_deg(self, ra_j2000_hours: float, dec_j2000_deg: float) -> float:
        """How far (degrees) a J2000 position is from where the mount believes it points."""
        ra, dec = self.j2000_at(self.elapsed())
        return angular_separation_deg(ra * 15.0, dec, ra_j2000_hours * 15.0, dec_j2000_deg)

    # --- connection -----------------------------------------------------------------------------

    async def connect(self) -> None:
        self._connected = True
        self.snapshot()

    async def disconnect(self) -> None:
        t = self._begin(replan=True)
        self._stop_motion(t)
        self._connected = False
        self._finish(limits_from=t)

    async def refresh(self) -> MountState:
        return self.snapshot()

    # --- Mount hooks ----------------------------------------------------------------------------

    async def _goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        t = self._begin(replan=True)
        if self._tracking is TrackingMode.OFF:
            # SynScan: a goto RA/Dec enables tracking if it is stopped.
            self._tracking = self._default_tracking()
        target = SkyTarget(ra_j2000_hours, dec_j2000_deg, t, ra_drift_hours_per_s(self._tracking))
        alt, az = j2000_to_observed(
            ra_j2000_hours, dec_j2000_deg, self.clock.datetime_at(t), self._site
        )
        side = self.geometry.choose_side(alt, az, self._side_at(t))
        path = self._path(target, t, side)
        for index, trajectory in enumerate((path.primary, path.secondary)):
            self._landing[index] = self._land_on(self.axes[index], trajectory, t)
        self._goto_until = max(self._landing)
        self._finish(limits_from=self._goto_until)

    async def _goto_horizontal(self, alt_deg: float, az_deg: float) -> None:
        t = self._begin(replan=True)
        # ASCOM requires tracking off for alt/az slews: the mount lands and holds still.
        self._tracking = TrackingMode.OFF
        side = self.geometry.choose_side(alt_deg, az_deg, self._side_at(t))
        self._slew_both_to(self.geometry.to_axes(alt_deg, az_deg, side), t)
        self._finish(limits_from=self._goto_until)

    async def _sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        t = self._begin()
        alt, az = j2000_to_observed(
            ra_j2000_hours, dec_j2000_deg, self.clock.datetime_at(t), self._site
        )
        counters = self.geometry.to_axes(alt, az, self._side_at(t))
        for axis, counter in zip(self.axes, counters, strict=True):
            current = axis.unwrapped_position_at(t)
            axis.set_position(current + _wrap_signed(counter - current), at=t)
        self._aligned = True
        self._retarget_at.add(t)
        self._finish(limits_from=t)

    def _sync_frame_after(
        self, ra_j2000_hours: float, dec_j2000_deg: float, state: MountState
    ) -> SyncFrame:
        """Exact: every counter redefinition so far plus the one this sync would make."""
        t = self.elapsed()
        alt, az = j2000_to_observed(
            ra_j2000_hours, dec_j2000_deg, self.clock.datetime_at(t), self._site
        )
        counters = self.geometry.to_axes(alt, az, self._side_at(t))
        offsets = [
            axis.counter_offset_deg + _wrap_signed(counter - axis.unwrapped_position_at(t))
            for axis, counter in zip(self.axes, counters, strict=True)
        ]
        return SyncFrame(_wrap_signed(offsets[0]), offsets[1])

    async def _abort(self) -> None:
        t = self._begin(replan=True)
        self._stop_motion(t)
        self._finish(limits_from=t)

    async def _move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        t = self._begin()
        index = axis.value
        self._take_over_from_goto(index, t)
        end = self.axes[index].set_rate(rate_deg_s, at=t)
        self._moving_until[index] = _FOREVER if rate_deg_s != 0.0 else end
        if rate_deg_s == 0.0:
            self._retarget_at.add(end)  # track the new position from where the axis stops
        self._finish(limits_from=t)

    async def _pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        t = self._begin()
        index, sign = self.geometry.guide_axis(direction, self.axes[1].unwrapped_position_at(t))
        self._take_over_from_goto(index, t)
        motor = self.axes[index]
        duration = duration_ms / 1000.0
        motor.set_rate(sign * self.guide_rate_deg_s, at=t)
        self._retarget_at.add(motor.set_rate(0.0, at=t + duration))
        self._pulse_until[index] = t + duration
        self._finish(limits_from=t)

    async def _set_tracking(self, mode: TrackingMode) -> None:
        t = self._begin()
        self._tracking = mode
        # During a goto the new mode applies from the landing on.
        self._retarget_at.add(max(t, self._goto_until))
        self._finish(limits_from=max(t, self._goto_until))

    async def _park(self) -> None:
        t = self._begin(replan=True)
        self._tracking = TrackingMode.OFF
        counters = self.park_counters
        if self.park_position_chosen:  # e.g. Alpaca's SetPark: the chosen alt/az wins
            where = self.park_position
            side = self.geometry.choose_side(where.alt_deg, where.az_deg, self._side_at(t))
            counters = self.geometry.to_axes(where.alt_deg, where.az_deg, side)
        self._slew_both_to(counters, t)
        self._parked = True
        self._park_landing = self._goto_until
        self._finish(limits_from=self._goto_until)

    async def _unpark(self) -> None:
        self._parked = False
        self._park_landing = _FOREVER
        self.snapshot()

    async def _set_site(self, site: Site) -> None:
        t = self._begin()
        self._site = site
        self.geometry = self._make_geometry(site)
        self._retarget_at.add(t)
        self._finish(limits_from=t)

    async def _set_time(self, utc: datetime) -> None:
        t = self._begin()
        self.clock.set_time(utc)
        self._retarget_at.add(t)
        self._finish(limits_from=t)

    # --- low-level access for device emulators ---------------------------------------------------

    def set_axis_position(self, axis: MountAxis, position_deg: float) -> None:
        """Redefine one axis counter (SynScan "set axis position"); the motor does not move."""
        t = self._begin()
        self.axes[axis.value].set_position(position_deg, at=t)
        self._retarget_at.add(t)
        self._finish(limits_from=t)

    def slew_axis_to(
        self, axis: MountAxis, position_deg: float, *, max_rate_deg_s: float | None = None
    ) -> float:
        """Slew one axis counter to ``position_deg`` (SynScan "slow goto"); returns the landing.

        Tracking, if on, resumes from wherever both axes are at the landing.
        """
        t = self._begin()
        index = axis.value
        self._moving_until[index] = -_FOREVER
        landing = self.axes[index].slew_to(position_deg, max_rate_deg_s=max_rate_deg_s, at=t)
        self._landing[index] = landing
        self._goto_until = max(self._goto_until, landing)
        self._retarget_at.add(landing)
        self._finish(limits_from=landing)
        return landing

    # --- internals ------------------------------------------------------------------------------

    def sun_zone_at(self, t: float) -> SunZone | None:
        """The Sun avoidance zone at elapsed time ``t`` (None when it is off, or when the clock
        is outside the ephemeris: the Mount API then refuses every goto until the time is set,
        and the physics must not fail every command meanwhile)."""
        try:
            return sun_zone(
                self._limits.sun_avoidance_deg,
                self._site,
                self.clock.datetime_at(t),
                self.model.alignment_mode,
            )
        except SunAvoidanceError:
            return None

    def _make_geometry(self, site: Site) -> Geometry:
        return geometry_for(
            self.model.alignment_mode,
            site.latitude_deg,
            meridian_tolerance_deg=self._meridian_tolerance_deg,
        )

    def _make_axis(self, name: str, position_deg: float, *, wrap: bool) -> Axis:
        return Axis(
            name,
            max_rate_deg_s=self.model.max_rate_deg_s,
            acceleration_deg_s2=self.model.acceleration_deg_s2,
            time_source=self.clock.elapsed,
            position_deg=position_deg,
            wrap=wrap,
        )

    def _make_capabilities(self) -> Capabilities:
        equatorial = self.model.alignment_mode is not AlignmentMode.ALT_AZ
        rates = {TrackingMode.OFF, TrackingMode.SIDEREAL, TrackingMode.LUNAR, TrackingMode.SOLAR}
        rates.add(TrackingMode.PEC if equatorial else TrackingMode.ALT_AZ)
        return Capabilities(
            alignment_mode=self.model.alignment_mode,
            can_goto=True,
            can_goto_altaz=True,
            can_sync=True,
            can_park=True,
            can_set_park=True,
            can_pulse_guide=True,
            can_move_axis=(True, True),
            max_axis_rate_deg_s=self.model.max_rate_deg_s,
            tracking_modes=frozenset(rates),
            can_set_site=True,
            can_set_time=True,
            can_report_pier_side=self.model.alignment_mode is AlignmentMode.GERMAN_POLAR,
        )

    def _default_tracking(self) -> TrackingMode:
        if self.model.alignment_mode is AlignmentMode.ALT_AZ:
            return TrackingMode.ALT_AZ
        return TrackingMode.SIDEREAL

    def _side_at(self, t: float) -> PierSide:
        return self.geometry.pier_side(*self.counters_at(t))

    def _path(self, target: SkyTarget, t: float, side: PierSide) -> SkyPath:
        return SkyPath(
            target,
            geometry=self.geometry,
            site=self._site,
            epoch=self.clock.epoch,
            side=side,
            primary_reference=self.axes[0].unwrapped_position_at(t),
        )

    def _path_from_here(self, t: float) -> SkyPath | PolarAxisPath:
        counters = self.counters_at(t)
        if self.geometry.pole_distance_deg(*counters) < _POLE_TRACKING_DEG:
            rate = self.geometry.hemisphere * tracking_rate_deg_s(self._tracking)
            return PolarAxisPath(counters, t, rate)
        ra, dec = self.j2000_at(t)
        drift = ra_drift_hours_per_s(self._tracking)
        return self._path(SkyTarget(ra, dec, t, drift), t, self._side_at(t))

    def _resolve_retargets(self) -> None:
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
            path = None if self._tracking is TrackingMode.OFF else self._path_from_here(t)
            trajectories = (path.primary, path.secondary) if path else (None, None)
            for index, axis in enumerate(self.axes):
                if t >= self._landing[index]:
                    axis.insert_follow(trajectories[index], at=t)

    def _finish(self, *, limits_from: float) -> None:
        """End a command: settle tracking, stop at the first limit, publish the state."""
        self._resolve_retargets()
        self._enforce_limits(limits_from)
        for axis in self.axes:
            axis.history_needed_from = None
        self.snapshot()

    def _take_over_from_goto(self, index: int, t: float) -> None:
        """A manual motion of an axis cancels the goto it was landing (as on a hand control)."""
        if t < self._landing[index]:
            self.axes[index].follow(None, at=t)
            self._landing[index] = -_FOREVER
            self._goto_until = max(self._landing)

    def _slew_both_to(self, counters: tuple[float, float], t: float) -> None:
        for index, (axis, target) in enumerate(zip(self.axes, counters, strict=True)):
            self._landing[index] = axis.slew_to(target, at=t)
        self._goto_until = max(self._landing)

    def _land_on(self, axis: Axis, trajectory: Trajectory, t: float) -> float:
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

    def _stop_motion(self, t: float) -> None:
        """Ramp both axes to rest; tracking, if on, resumes from the rest point."""
        rest = max(axis.stop(at=t) for axis in self.axes)
        self._moving_until = [rest, rest]
        self._retarget_at.add(rest)

    def _settle(self, now: float) -> None:
        """Apply what the plan says has happened by ``now`` (a stop at a limit ends tracking)."""
        stop = self._limit_stop
        if stop is not None and stop.at_s <= now:
            self._tracking = TrackingMode.OFF

    def _begin(self, *, replan: bool = False) -> float:
        """Start a command at the current elapsed time: settle, and undo a stop still ahead.

        Every command re-runs the limit search when it has planned its motion. ``replan``:
        the command replaces all motion (goto, park, abort), so what was scheduled is dropped.
        """
        now = self.elapsed()
        self._command_at = now
        for axis in self.axes:
            axis.history_needed_from = now
        self._settle(now)
        stop = self._limit_stop
        if stop is not None and stop.at_s > now:
            for axis, plan in zip(self.axes, stop.replaced, strict=True):
                axis.restore_plan(stop.at_s, plan)
            self._moving_until = list(stop.moving_until)
            self._limit_stop = None
        if replan:
            if now < self._park_landing:  # a park slew cut short (abort, disconnect) is no park
                self._parked = False
                self._park_landing = _FOREVER
            self._retarget_at.clear()
            self._landing = [-_FOREVER, -_FOREVER]
            self._goto_until = -_FOREVER
            self._moving_until = [-_FOREVER, -_FOREVER]
            self._limit_stop = None
        return now

    # --- horizon and mechanical limits ------------------------------------------------------------

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
        margin = self.geometry.axis_margin_deg(physical[0], physical[1])
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
        zone, since = self._sun_search
        if zone is None:
            return math.inf
        return zone.distance_deg(alt, az, later_s=t - since) - zone.radius_deg

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

    def _enforce_limits(self, start: float) -> None:
        """Stop continuous motion from ``start`` on where it would cross a limit."""
        self._limit_stop = None
        self._sun_search = (self.sun_zone_at(start), start)
        floor = min(0.0, self._margin_at(start)) - 1e-9
        end = self._search_end(start)
        previous = t = start
        while True:
            if self._margin_at(t) < floor:
                break
            if t >= end:
                return
            previous, t = t, min(t + self._search_step(t), end)
        low, high = previous, t
        while high - low > _SEARCH_RESOLUTION_S:
            middle = 0.5 * (low + high)
            inside = self._margin_at(middle, exact=True) >= floor
            low, high = (middle, high) if inside else (low, middle)
        replaced = (self.axes[0].plan_from(low), self.axes[1].plan_from(low))
        moving_until = (self._moving_until[0], self._moving_until[1])
        rest = max(axis.stop(at=low) for axis in self.axes)
        self._moving_until = [min(until, rest) for until in self._moving_until]
        alt, az = self.observed_at(rest)
        self._limit_stop = LimitStop(
            low,
            f"motion stopped at a limit (altitude {alt:.2f}°, azimuth {az:.1f}°): the horizon, "
            "the altitude limit, the meridian limit or the Sun avoidance zone; move away or goto "
            "elsewhere",
            replaced,
            moving_until,
        )


def _wrap_signed(degrees: float) -> float:
    return (degrees + 180.0) % 360.0 - 180.0
