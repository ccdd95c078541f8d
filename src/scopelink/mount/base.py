"""The protocol-neutral Mount: every front end drives a mount through this class alone.

Public methods validate their arguments and check the configured limits *before* the
protocol-specific implementation runs, so no subclass can forget a check: a motion that would leave
the allowed sky raises :class:`LimitError` and nothing reaches the link. Subclasses implement the
underscore methods they support (:mod:`scopelink.mount.device`); the rest raise
:class:`NotSupportedError`, which front ends report as "not implemented".
"""

from __future__ import annotations

import asyncio
import dataclasses
import functools
import logging
import math
from collections.abc import Awaitable, Callable
from contextlib import AbstractAsyncContextManager, AbstractContextManager, aclosing
from datetime import UTC, datetime

from scopelink.astro import PierSide, Site, observed_to_j2000
from scopelink.astro.catalog import CatalogObject, lookup
from scopelink.mount.deadman import DeadMan, MotionClient
from scopelink.mount.errors import (
    InvalidValueError,
    LimitError,
    NotConnectedError,
    NotSupportedError,
    ParkedError,
    SyncRefusedError,
)
from scopelink.mount.guard import HorizonGuard
from scopelink.mount.guarded import GuardSettings
from scopelink.mount.limits import Limits
from scopelink.mount.meridian import (
    applies,
    hour_angle_of_altaz,
    hour_angle_of_j2000,
    plan_goto_side,
)
from scopelink.mount.meridian_watch import MeridianWatch
from scopelink.mount.parking import ParkKeeper, Resume
from scopelink.mount.pointed import PointedMount
from scopelink.mount.progress import ProgressTracker
from scopelink.mount.rates import RateKeeper, TrackingRates, check_tracking_rates
from scopelink.mount.setters import check_park_position, check_time
from scopelink.mount.sun import SunZone, sun_zone
from scopelink.mount.syncs import (
    SyncFrame,
    check_sync,
    refuse_sync_while_slewing,
    sync_distance_deg,
)
from scopelink.mount.types import (
    GuideDirection,
    MountAxis,
    MountState,
    ParkPosition,
    SlewProgress,
    SlewTarget,
    TrackingMode,
)

__all__ = ["MAX_PULSE_GUIDE_MS", "Mount", "utc_now"]

_log = logging.getLogger(__name__)

MAX_PULSE_GUIDE_MS = 60_000
"""Longest guide pulse accepted; a longer one is almost surely a unit mistake (s for ms)."""


utc_now: Callable[[], datetime] = functools.partial(datetime.now, UTC)
"""The PC's clock in UTC: the default time source of a real mount. A partial, not a function:
it is called twice a poll, and calling it runs no Python frame (issue #14)."""


def _check_ra_dec(ra_hours: float, dec_deg: float) -> None:
    if not (math.isfinite(ra_hours) and 0.0 <= ra_hours < 24.0):
        raise InvalidValueError(f"right ascension {ra_hours} h must lie in [0, 24)")
    if not (math.isfinite(dec_deg) and -90.0 <= dec_deg <= 90.0):
        raise InvalidValueError(f"declination {dec_deg}° must lie in [-90, +90]")


def _check_alt_az(alt_deg: float, az_deg: float) -> None:
    if not (math.isfinite(alt_deg) and -90.0 <= alt_deg <= 90.0):
        raise InvalidValueError(f"altitude {alt_deg}° must lie in [-90, +90]")
    if not (math.isfinite(az_deg) and 0.0 <= az_deg < 360.0):
        raise InvalidValueError(f"azimuth {az_deg}° must lie in [0, 360)")


class Mount(PointedMount):
    """A telescope mount, whatever protocol (or simulation) is behind it.

    Reads come from a state cache (:attr:`state`) that a background poller keeps fresh while
    anyone is inside :meth:`watching` (or iterating :meth:`states`), at the rate
    :attr:`poll_policy` gives: full rate while something needs it, else slowly (see
    :mod:`scopelink.mount.cache` and :mod:`scopelink.mount.polling`). What a driver implements
    is :class:`~scopelink.mount.device.MountDevice`'s.
    """

    stops_itself_at_limits: bool = False
    """Whether the device stops rate motions and tracking at the limits by itself (the
    simulator); otherwise :attr:`guard` watches them and stops them in time."""

    def __init__(
        self,
        *,
        site: Site,
        limits: Limits | None = None,
        clock: Callable[[], datetime] = utc_now,
        park_position: ParkPosition | None = None,
    ) -> None:
        super().__init__(site=site, limits=limits, clock=clock)
        self._target: SlewTarget | None = None
        self._park_position = park_position or ParkPosition.pole(site.latitude_deg)
        self._park_position_chosen = park_position is not None
        self._rates = RateKeeper(self)
        self._guard = HorizonGuard(self, GuardSettings(), show_notice=self._publish_again)
        self._meridian = MeridianWatch(self, GuardSettings(), show_notice=self._publish_again)
        self._dead_man = DeadMan(self._guard.axes_of, lambda axis: self.move_axis(axis, 0.0))
        self._dead_man.left = self._rates.left  # a client's custom tracking rates end with it
        self._sync_lock = asyncio.Lock()
        """One sync at a time, so the recorded frame follows the order the device got them in."""
        self._parking = False
        """Park was commanded and not undone (AtPark once the mount has arrived and stopped)."""
        self.park_keeper = ParkKeeper()
        """Records the park and restores it at unpark (:mod:`scopelink.mount.parking`)."""
        self.aborts = 0
        """How often :meth:`abort` was called: a follower seeing one ends (mount/follow.py)."""

    # --- who, what, where -------------------------------------------------------------------------

    @property
    def park_position(self) -> ParkPosition:
        """Where :meth:`park` points the mount: the pole of the site's hemisphere unless chosen
        (a device that keeps its own park position uses it only once one was chosen)."""
        return self._park_position

    @park_position.setter
    def park_position(self, position: ParkPosition) -> None:
        check_park_position(position, self._limits)
        self._park_position = position
        self._park_position_chosen = True

    @property
    def park_position_chosen(self) -> bool:
        """Whether a park position was given (constructor, Alpaca SetPark, configuration)."""
        return self._park_position_chosen

    @property
    def target(self) -> SlewTarget | None:
        """Where the last goto was sent (``None`` before the first)."""
        return self._target

    @property
    def guard(self) -> HorizonGuard:
        """What stops rate motions and tracking at the limits (see :mod:`scopelink.mount.guard`)."""
        return self._guard

    @property
    def meridian(self) -> MeridianWatch:
        """What stops tracking at the meridian limit, or flips
        (:mod:`scopelink.mount.meridian_watch`)."""
        return self._meridian

    def motion_client(self, name: str) -> AbstractAsyncContextManager[MotionClient]:
        """The dead-man for one client of a front end: inside ``async with``, rate motions are
        owned by the client, and those still running when the block ends are stopped."""
        return self._dead_man.client(name)

    def acting_for(self, token: str | None) -> AbstractContextManager[MotionClient | None]:
        """Commands inside are on behalf of the :class:`MotionClient` with ``token`` (requests
        that arrive apart from their client's connection, like the dashboard's HTTP calls)."""
        return self._dead_man.acting_for(token)

    def _publish(self, state: MountState) -> None:
        """Correct, annotate and publish ``state``, then show it to the watchers, in one pass
        (every poll's reading comes here: nothing is rebuilt unless something changes it)."""
        state = self._corrected(state)
        if state.parked and state.slewing:  # parked only once arrived and stopped
            state = dataclasses.replace(state, parked=False)
        if not state.connected:
            self._parking = False  # a device that reconnects says itself whether it is parked
        guard, meridian = self._guard, self._meridian
        if guard.notice or meridian.notice:  # a stop's reason, shown among the problems
            state = meridian.annotate(guard.annotate(state))
        super()._publish(state)
        published = self._broadcast.state
        guard.observe(published)
        self.park_keeper.observe(self, published)
        meridian.observe(published)

    def _publish_again(self) -> None:
        """Publish the current state again (with the guard's latest notice)."""
        self._publish(self.state)

    def _full_rate_needed(self) -> bool:
        return super()._full_rate_needed() or self._parking or bool(self._guard.rate_motions)

    async def wait_for_slew(
        self,
        timeout_s: float | None = None,
        progress: Callable[[SlewProgress], None] | None = None,
    ) -> MountState:
        """Wait until the current slew has ended (read after this call began) and return that
        state; ``progress`` is called with each new reading meanwhile."""
        since = self.now()
        tracker = ProgressTracker(self._target)
        async with asyncio.timeout(timeout_s), aclosing(self.states()) as states:
            async for state in states:
                if progress is not None:
                    progress(tracker.update(state))
                # A state read while the link is down says nothing about the slew.
                if state.connected and not state.slewing and state.read_at >= since:
                    return state
        raise AssertionError("unreachable: states() never ends")  # pragma: no cover

    # --- preconditions ----------------------------------------------------------------------------

    def _require_connected(self) -> None:
        if not self.state.connected:
            if self.engaged:  # the link was lost: say so, with the reading's age
                self.fresh_state()
            raise NotConnectedError(f"{self.identity.model or 'the mount'} is not connected")

    def _require_unparked(self) -> None:
        self._require_connected()
        if self.state.parked:
            raise ParkedError("the mount is parked: unpark it before moving it")
        if self._parking:
            raise ParkedError(
                "the mount is on its way to the park position: wait until it is parked and "
                "unpark it, or abort to cancel the park"
            )

    @property
    def parking(self) -> bool:
        """Whether the park slew is under way (commanded, not arrived, not cancelled)."""
        return self._parking and not self.state.parked

    # --- checked motion: validate, check limits, then delegate ---------------------------------

    async def goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """Start a slew to a J2000 position; returns once the slew has started."""
        _check_ra_dec(ra_j2000_hours, dec_j2000_deg)
        self._require_unparked()
        alt, az = self.observed_altaz(ra_j2000_hours, dec_j2000_deg)
        self._limits.check_altaz(alt, az)
        await self._check_sun(alt, az)
        ha, dec = hour_angle_of_j2000(self, ra_j2000_hours, dec_j2000_deg)
        side = self._meridian_side(ha, dec, tracking=True)
        self._motion_commanded()
        if self._pointing.active:  # checked above where the tube will point; sent in device terms
            ra, dec = observed_to_j2000(*self._pointing.reading_of(alt, az), self.now(), self._site)
        else:
            ra, dec = ra_j2000_hours, dec_j2000_deg
        if side is None:
            await self._goto_equatorial(ra, dec)
        else:
            await self._goto_equatorial_on(ra, dec, side)
        self._guard.goto_started()
        self._meridian.goto_started()
        self._target = SlewTarget(ra_j2000_hours=ra_j2000_hours, dec_j2000_deg=dec_j2000_deg)

    async def goto_object(self, name: str) -> CatalogObject:
        """Start a slew to a named object of the offline catalogue (``"M31"``, ``"Vega"``,
        ``"Jupiter"``, ``"HIP 91262"``); returns the object, with its J2000 position now.
        Unknown names raise :class:`~scopelink.astro.catalog.UnknownObjectError` with
        suggestions."""
        found = lookup(name, self.now(), self._site)
        await self.goto_equatorial(found.ra_hours, found.dec_deg)
        self._target = dataclasses.replace(self._target or SlewTarget(), name=found.name)
        return found

    async def goto_horizontal(self, alt_deg: float, az_deg: float) -> None:
        """Start a slew to an observed altitude and azimuth; returns once the slew has started."""
        _check_alt_az(alt_deg, az_deg)
        self._require_unparked()
        self._limits.check_altaz(alt_deg, az_deg)
        await self._check_sun(alt_deg, az_deg)
        side = self._meridian_side(*hour_angle_of_altaz(self, alt_deg, az_deg), tracking=False)
        self._motion_commanded()
        device_alt, device_az = self._pointing.reading_of(alt_deg, az_deg)
        if side is None:
            await self._goto_horizontal(device_alt, device_az)
        else:
            await self._goto_horizontal_on(device_alt, device_az, side)
        self._guard.goto_started()
        self._meridian.goto_started()
        self._target = SlewTarget(alt_deg=alt_deg, az_deg=az_deg)

    def _meridian_side(self, ha_hours: float, dec_deg: float, *, tracking: bool) -> PierSide | None:
        """The pier side a goto must ask for (None: the device's own), or ``LimitError``."""
        if not applies(self.capabilities):
            return None
        predicted = self._predicted_pier_side(ha_hours, dec_deg)
        return plan_goto_side(
            self._limits,
            ha_hours,
            predicted,
            can_choose=self.can_choose_pier_side,
            tracking=tracking,
            leave=self._meridian.leaving,
        )

    def destination_side_of_pier(self, ra_j2000_hours: float, dec_j2000_deg: float) -> PierSide:
        """Where a goto to this J2000 position would put the tube now (``UNKNOWN`` where it
        would be refused by the meridian limits, or on a mount without a pier side)."""
        if not applies(self.capabilities):
            return PierSide.UNKNOWN
        ha, dec = hour_angle_of_j2000(self, ra_j2000_hours, dec_j2000_deg)
        try:
            side = self._meridian_side(ha, dec, tracking=True)
        except LimitError:
            return PierSide.UNKNOWN
        return side if side is not None else self._predicted_pier_side(ha, dec)

    async def sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """Tell the mount it is pointing at this J2000 position, unless that is farther than
        ``limits.max_sync_deg`` from its reading or from its un-synced frame (see
        :mod:`scopelink.mount.syncs`); refused while the mount slews."""
        _check_ra_dec(ra_j2000_hours, dec_j2000_deg)
        async with self._sync_lock:
            self._require_unparked()
            state = await self.current_state()
            self._check_sync_now(state)
            alt, az = self.observed_altaz(ra_j2000_hours, dec_j2000_deg)
            await self._check_sun(alt, az, what="sync position", slew=False)
            distance = sync_distance_deg(state, ra_j2000_hours, dec_j2000_deg)
            frame = self._sync_frame_after(ra_j2000_hours, dec_j2000_deg, state)
            on_device = self.syncs_on_device and not self._pointing.active
            # A sync kept on the PC leaves the device's frame; its model is checked instead.
            check_sync(self._limits, distance, (frame if on_device else self._sync_frame).reach_deg)
            if on_device:
                try:
                    await self._sync_equatorial(ra_j2000_hours, dec_j2000_deg)
                    self._sync_frame = frame
                    return
                except (NotSupportedError, SyncRefusedError) as refusal:
                    _log.info("sync kept on the PC: %s", refusal)
            await self._keep_sync(ra_j2000_hours, dec_j2000_deg)

    async def _keep_sync(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """Keep a sync in :attr:`pointing`: a reading taken now (not one a poll may have started
        before the observer centred the star) and the true position at its time."""
        await self.refresh()
        reach = self._sync_frame.reach_deg
        self._pointing.keep(ra_j2000_hours, dec_j2000_deg, self._site, reach, self._limits)
        self.pointing_changed()

    def _check_sync_now(self, state: MountState) -> None:
        """Refuse a sync while the mount slews (a driver may refuse in its own words first)."""
        refuse_sync_while_slewing(state)

    def sun_zone(self) -> SunZone | None:
        """The Sun avoidance zone now (None when ``limits.sun_avoidance_deg`` is 0)."""
        mode = self.capabilities.alignment_mode
        return sun_zone(self._limits.sun_avoidance_deg, self._site, self.now(), mode)

    async def _check_sun(
        self, alt_deg: float, az_deg: float, *, what: str = "target", slew: bool = True
    ) -> None:
        """Refuse a target inside the Sun avoidance zone, or a slew through it from where the
        mount points (read again unless the cache is fresh)."""
        zone = self.sun_zone()
        if zone is None:
            return
        zone.check_position(alt_deg, az_deg, what=what)
        state = self.state
        if slew and (not state.connected or (self.now() - state.read_at).total_seconds() > 2.0):
            state = await self.refresh()
        if slew:
            zone.check_slew_from(state, (alt_deg, az_deg), what=f"the slew to the {what}")

    async def abort(self) -> None:
        """Stop every motion now (tracking keeps its setting where the protocol allows); tried
        while the link is lost too (the driver tries it, or owes the stop)."""
        if not self.engaged:
            self._require_connected()
        self.aborts += 1
        cancels_park = self.parking
        self._motion_commanded()  # seen to stop at full rate
        await self._abort()
        self._guard.motions_stopped()
        if cancels_park:  # stopped short of the park position: not parked
            self._parking = False
            await self._unpark()

    async def move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        """Turn one axis at a signed rate (degrees per second); 0 stops it."""
        self._require_unparked()
        limit = self.capabilities.max_axis_rate_deg_s
        if not self.capabilities.can_move_axis[axis.value]:
            raise NotSupportedError(
                f"this mount cannot move its {axis.name.lower()} axis at a rate"
            )
        if not (math.isfinite(rate_deg_s) and abs(rate_deg_s) <= limit):
            raise InvalidValueError(f"axis rate {rate_deg_s}°/s must lie within ±{limit}°/s")
        await self._guarded_rate_motion(axis, rate_deg_s, lambda: self._move_axis(axis, rate_deg_s))

    async def _guarded_rate_motion(
        self, axis: MountAxis, rate_deg_s: float, start: Callable[[], Awaitable[None]]
    ) -> None:
        """Start a rate motion with ``start`` unless the horizon guard refuses it, and have the
        guard watch it. Every way a driver offers to turn an axis at a rate goes through here."""
        # Even a mount that stops itself at the limits refuses a motion heading further out.
        await self._guard.check_move_now(axis, rate_deg_s)
        self._motion_commanded()
        async with self._guard.starting(axis, rate_deg_s):  # watched before its command leaves
            await start()

    async def pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        """Nudge the mount at the guide rate for ``duration_ms`` milliseconds."""
        self._require_unparked()
        if not 0 <= duration_ms <= MAX_PULSE_GUIDE_MS:
            raise InvalidValueError(
                f"guide pulse {duration_ms} ms must lie in [0, {MAX_PULSE_GUIDE_MS}]"
            )
        self._motion_commanded()
        await self._pulse_guide(direction, duration_ms)

    async def set_tracking(self, mode: TrackingMode) -> None:
        """Start tracking in ``mode`` or stop it with ``TrackingMode.OFF``."""
        self._require_connected()
        if mode not in self.capabilities.tracking_modes:
            supported = ", ".join(sorted(m.value for m in self.capabilities.tracking_modes))
            raise NotSupportedError(
                f"tracking mode {mode.value!r} is not supported (use {supported})"
            )
        if mode is not TrackingMode.OFF:
            self._require_unparked()
            self._meridian.check_tracking(self.state)
        await self._set_tracking(mode)
        if mode is not TrackingMode.OFF:
            self._guard.command_accepted()
            self._meridian.command_accepted()

    @property
    def tracking_rates(self) -> TrackingRates:  # zero: the tracking mode's own rate
        return self._rates.rates

    async def set_tracking_rates(self, ra_arcsec_per_s: float, dec_arcsec_per_s: float) -> None:
        """Add these J2000 RA/Dec rates to tracking (docs/tracking.md; 0, 0: the mode's own)."""
        rates = check_tracking_rates(self.capabilities, ra_arcsec_per_s, dec_arcsec_per_s)
        (self._require_connected if rates.zero else self._require_unparked)()
        await self._set_tracking_rates(rates)
        self._rates.set(rates)

    async def park(self) -> None:
        """Move to the park position, stop tracking and refuse motion until unparked."""
        self._require_connected()
        park = self._park_position
        await self._check_sun(park.alt_deg, park.az_deg, what="park position")
        if self._park_position_chosen:  # the limits may have changed since it was chosen
            check_park_position(self._park_position, self._limits)
        self._motion_commanded()
        await self._park()
        self._parking = True
        self._guard.motions_stopped()

    async def unpark(self) -> Resume:
        """Allow motion again; first put back what the park record says where the device forgot
        it in a power cycle (:mod:`scopelink.mount.parking`). Returns what was done with it."""
        self._require_connected()
        resume = await self.park_keeper.resume(self)
        if resume.restored and resume.record is not None:
            self._sync_frame = SyncFrame(*resume.record.sync_frame_deg)
        await self._unpark()
        self._parking = False
        return resume

    async def set_site(self, site: Site) -> None:
        """Use ``site`` from now on, and tell the device where supported."""
        if not isinstance(site, Site):
            raise InvalidValueError(f"a site is a scopelink Site, not {site!r}")
        await self._set_site(site)
        self._site = site

    async def set_time(self, utc: datetime) -> None:
        """Tell the device the time (an aware datetime between 2001 and 2099: see
        :mod:`scopelink.mount.setters`)."""
        check_time(utc)
        self._require_connected()
        await self._set_time(utc)
