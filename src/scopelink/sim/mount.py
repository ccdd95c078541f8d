"""The simulated mount: a :class:`~scopelink.mount.Mount` made of two :class:`Axis` and a clock.

Nothing runs in the background. Every command plans the axes' motion from "now" in closed form
(slews, ramps, tracking that follows the target through ``astro``, guide pulses, and a stop where
continuous motion would cross the horizon or a mechanical limit), and every reading evaluates
that plan at the clock's current time. So a stepped clock advanced by a test, or a clock running
x1000, gives exactly the same positions. The mount decides what the axes do; its
:class:`~scopelink.sim.motion.MotionPlan` carries it out and keeps the timing, and
:class:`~scopelink.sim.limit_search.LimitSearch` finds where the plan must stop. See
``docs/simulator.md``.
"""

from __future__ import annotations

from datetime import datetime

from scopelink.astro import (
    PierSide,
    Site,
    angular_separation_deg,
    hadec_to_altaz,
    j2000_to_apparent,
    j2000_to_observed,
    observed_to_j2000,
    wrap_signed_degrees,
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
from scopelink.mount.rates import TrackingRates
from scopelink.mount.syncs import SyncFrame
from scopelink.mount.types import AlignmentMode
from scopelink.sim.axis import Axis
from scopelink.sim.clock import SimClock
from scopelink.sim.geometry import Geometry, geometry_for
from scopelink.sim.limit_search import LimitSearch, LimitStop, sun_zone_or_none
from scopelink.sim.misalignment import Misalignment
from scopelink.sim.models import EQ6, MountModel
from scopelink.sim.motion import FOREVER, MotionPlan
from scopelink.sim.tracking import (
    PolarAxisPath,
    SkyPath,
    sky_target,
    tracking_path,
)

__all__ = ["SimulatedMount"]

MAX_SIM_TRACKING_OFFSET_ARCSEC_S = 3600.0
"""The simulator's largest custom tracking rate offset (1°/s on each axis; docs/tracking.md)."""


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
        misalignment: Misalignment | None = None,
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
        self._park_landing = FOREVER
        """Elapsed time the park slew lands: parked from then on, not before."""
        self._tracking = TrackingMode.OFF
        self._plan = MotionPlan(self.axes)
        self._capabilities = _capabilities_of(model)
        self.misalignment = misalignment or Misalignment()
        """How the real sky differs from the mount's frame (:mod:`scopelink.sim.misalignment`)."""

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
        return self.elapsed() < self._plan.goto_until

    @property
    def goto_ends_at(self) -> float | None:
        """Elapsed time the goto (or park, or axis slew) in progress lands, if one is."""
        return self._plan.goto_until if self.goto_in_progress else None

    @property
    def limit_stop(self) -> LimitStop | None:
        """The last stop at the horizon or a mechanical limit (planned or past), if any."""
        return self._plan.limit_stop

    def counters_at(self, t: float) -> tuple[float, float]:
        """Both axis counters (unwrapped degrees) at elapsed ``t``."""
        return self._plan.counters_at(t)

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
        stop = self._plan.limit_stop
        stopped = self._plan.stopped_at_limit_by(t)
        problems = (stop.reason,) if stop and stopped else ()
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
            slewing=self._plan.slewing_at(t),
            tracking=TrackingMode.OFF if stopped else self._tracking,
            parked=self._parked and t >= self._park_landing,
            aligned=self._aligned,
            pulse_guiding=self._plan.pulse_guiding_at(t),
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

    def true_pointing(self) -> tuple[float, float]:
        """The true observed (alt, az) the tube points at now: the reading, moved by
        :attr:`misalignment` (what a camera on the tube would plate-solve)."""
        alt, az = self.observed_at(self.elapsed())
        equatorial = self.model.alignment_mode is not AlignmentMode.ALT_AZ
        return self.misalignment.true_of(alt, az, self._site.latitude_deg, equatorial=equatorial)

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
        self._plan.stop(t)
        self._connected = False
        self._finish(limits_from=t)

    async def refresh(self) -> MountState:
        return self.snapshot()

    # --- Mount hooks ----------------------------------------------------------------------------

    can_choose_pier_side = True  # the physics lands on either side

    def _predicted_pier_side(self, ha_hours: float, dec_deg: float) -> PierSide:
        alt, az = hadec_to_altaz(ha_hours, dec_deg, self._site.latitude_deg)
        return self.geometry.choose_side(alt, az, self._side_at(self.elapsed()))

    async def _goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        await self._goto_equatorial_on(ra_j2000_hours, dec_j2000_deg, None)

    async def _goto_equatorial_on(
        self, ra_j2000_hours: float, dec_j2000_deg: float, side: PierSide | None
    ) -> None:
        t = self._begin(replan=True)
        if self._tracking is TrackingMode.OFF:
            # SynScan: a goto RA/Dec enables tracking if it is stopped.
            self._tracking = _default_tracking(self.model)
        alt, az = j2000_to_observed(
            ra_j2000_hours, dec_j2000_deg, self.clock.datetime_at(t), self._site
        )
        if side is None:
            side = self.geometry.choose_side(alt, az, self._side_at(t))
        path = self._path(ra_j2000_hours, dec_j2000_deg, t, side)
        self._plan.land_both_on((path.primary, path.secondary), t)
        self._finish(limits_from=self._plan.goto_until)

    async def _goto_horizontal(self, alt_deg: float, az_deg: float) -> None:
        await self._goto_horizontal_on(alt_deg, az_deg, None)

    async def _goto_horizontal_on(
        self, alt_deg: float, az_deg: float, side: PierSide | None
    ) -> None:
        t = self._begin(replan=True)
        # ASCOM requires tracking off for alt/az slews: the mount lands and holds still.
        self._tracking = TrackingMode.OFF
        if side is None:
            side = self.geometry.choose_side(alt_deg, az_deg, self._side_at(t))
        self._plan.slew_both_to(self.geometry.to_axes(alt_deg, az_deg, side), t)
        self._finish(limits_from=self._plan.goto_until)

    async def _sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        t = self._begin()
        alt, az = j2000_to_observed(
            ra_j2000_hours, dec_j2000_deg, self.clock.datetime_at(t), self._site
        )
        counters = self.geometry.to_axes(alt, az, self._side_at(t))
        for axis, counter in zip(self.axes, counters, strict=True):
            current = axis.unwrapped_position_at(t)
            axis.set_position(current + wrap_signed_degrees(counter - current), at=t)
        self._aligned = True
        self._plan.retarget(t)
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
            axis.counter_offset_deg + wrap_signed_degrees(counter - axis.unwrapped_position_at(t))
            for axis, counter in zip(self.axes, counters, strict=True)
        ]
        return SyncFrame(wrap_signed_degrees(offsets[0]), offsets[1])

    async def _abort(self) -> None:
        t = self._begin(replan=True)
        self._plan.stop(t)
        self._finish(limits_from=t)

    async def _move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        t = self._begin()
        self._plan.move_axis(axis.value, rate_deg_s, t)
        self._finish(limits_from=t)

    async def _pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        t = self._begin()
        index, sign = self.geometry.guide_axis(direction, self.axes[1].unwrapped_position_at(t))
        self._plan.pulse(index, sign * self.guide_rate_deg_s, duration_ms / 1000.0, t)
        self._finish(limits_from=t)

    async def _set_tracking(self, mode: TrackingMode) -> None:
        t = self._begin()
        self._tracking = mode
        # During a goto the new mode applies from the landing on.
        from_t = max(t, self._plan.goto_until)
        self._plan.retarget(from_t)
        self._finish(limits_from=from_t)

    async def _set_tracking_rates(self, rates: TrackingRates) -> None:
        self._rates.set(rates)  # read by sky_target when tracking is planned anew
        await self._set_tracking(self.tracking)

    async def _park(self) -> None:
        t = self._begin(replan=True)
        self._tracking = TrackingMode.OFF
        counters = self.park_counters
        if self.park_position_chosen:  # e.g. Alpaca's SetPark: the chosen alt/az wins
            where = self.park_position
            side = self.geometry.choose_side(where.alt_deg, where.az_deg, self._side_at(t))
            counters = self.geometry.to_axes(where.alt_deg, where.az_deg, side)
        self._plan.slew_both_to(counters, t)
        self._parked = True
        self._park_landing = self._plan.goto_until
        self._finish(limits_from=self._plan.goto_until)

    async def _unpark(self) -> None:
        self._parked = False
        self._park_landing = FOREVER
        self.snapshot()

    async def _set_site(self, site: Site) -> None:
        t = self._begin()
        self._site = site
        self.geometry = self._make_geometry(site)
        self._plan.retarget(t)
        self._finish(limits_from=t)

    async def _set_time(self, utc: datetime) -> None:
        t = self._begin()
        self.clock.set_time(utc)
        self._plan.retarget(t)
        self._finish(limits_from=t)

    # --- low-level access for device emulators ---------------------------------------------------

    def set_axis_position(self, axis: MountAxis, position_deg: float) -> None:
        """Redefine one axis counter (SynScan "set axis position"); the motor does not move."""
        t = self._begin()
        self.axes[axis.value].set_position(position_deg, at=t)
        self._plan.retarget(t)
        self._finish(limits_from=t)

    def slew_axis_to(
        self, axis: MountAxis, position_deg: float, *, max_rate_deg_s: float | None = None
    ) -> float:
        """Slew one axis counter to ``position_deg`` (SynScan "slow goto"); returns the landing.

        Tracking, if on, resumes from wherever both axes are at the landing.
        """
        t = self._begin()
        landing = self._plan.slew_axis_to(axis.value, position_deg, max_rate_deg_s, t)
        self._finish(limits_from=landing)
        return landing

    # --- internals ------------------------------------------------------------------------------

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

    def _side_at(self, t: float) -> PierSide:
        return self.geometry.pier_side(*self.counters_at(t))

    def _path(self, ra_j2000: float, dec_j2000: float, t: float, side: PierSide) -> SkyPath:
        return SkyPath(
            sky_target(ra_j2000, dec_j2000, t, self._tracking, self.tracking_rates),
            geometry=self.geometry,
            site=self._site,
            epoch=self.clock.epoch,
            side=side,
            primary_reference=self.axes[0].unwrapped_position_at(t),
        )

    def _path_from_here(self, t: float) -> SkyPath | PolarAxisPath:
        def sky_path() -> SkyPath:
            return self._path(*self.j2000_at(t), t, self._side_at(t))

        return tracking_path(self.counters_at(t), t, self._tracking, self.geometry, sky_path)

    def _tracking_path_at(self, t: float) -> SkyPath | PolarAxisPath | None:
        return None if self._tracking is TrackingMode.OFF else self._path_from_here(t)

    def _finish(self, *, limits_from: float) -> None:
        """End a command: settle tracking, stop at the first limit, publish the state."""
        self._plan.resolve_retargets(self._tracking_path_at)
        when = self.clock.datetime_at(limits_from)
        zone = sun_zone_or_none(self._limits, self._site, when, self.model.alignment_mode)
        self._plan.stop_at_first_limit(
            LimitSearch(self.axes, self.geometry, self._limits, zone, limits_from)
        )
        self._plan.end_command()
        self.snapshot()

    def _settle(self, now: float) -> None:
        """Apply what the plan says has happened by ``now`` (a stop at a limit ends tracking)."""
        if self._plan.stopped_at_limit_by(now):
            self._tracking = TrackingMode.OFF

    def _begin(self, *, replan: bool = False) -> float:
        """Start a command at the current elapsed time: settle, and undo a stop still ahead.

        Every command re-runs the limit search when it has planned its motion. ``replan``:
        the command replaces all motion (goto, park, abort), so what was scheduled is dropped.
        """
        now = self.elapsed()
        self._settle(now)
        if (
            replan and now < self._park_landing
        ):  # a park slew cut short (abort, disconnect) is no park
            self._parked = False
            self._park_landing = FOREVER
        self._plan.begin(now, replan=replan)
        return now


def _capabilities_of(model: MountModel) -> Capabilities:
    """What a simulated mount of ``model`` can do: everything, at the preset's top rate."""
    equatorial = model.alignment_mode is not AlignmentMode.ALT_AZ
    rates = {TrackingMode.OFF, TrackingMode.SIDEREAL, TrackingMode.LUNAR, TrackingMode.SOLAR}
    rates.add(TrackingMode.KING)
    rates.add(TrackingMode.PEC if equatorial else TrackingMode.ALT_AZ)
    return Capabilities(
        alignment_mode=model.alignment_mode,
        can_goto=True,
        can_goto_altaz=True,
        can_sync=True,
        can_park=True,
        can_set_park=True,
        can_pulse_guide=True,
        can_move_axis=(True, True),
        max_axis_rate_deg_s=model.max_rate_deg_s,
        tracking_modes=frozenset(rates),
        can_set_site=True,
        can_set_time=True,
        can_report_pier_side=model.alignment_mode is AlignmentMode.GERMAN_POLAR,
        max_tracking_offset_arcsec_s=MAX_SIM_TRACKING_OFFSET_ARCSEC_S,
    )


def _default_tracking(model: MountModel) -> TrackingMode:
    """The mode a goto RA/Dec starts when tracking is off (an alt-az mount's own mode)."""
    if model.alignment_mode is AlignmentMode.ALT_AZ:
        return TrackingMode.ALT_AZ
    return TrackingMode.SIDEREAL
