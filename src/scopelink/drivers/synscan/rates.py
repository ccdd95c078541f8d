"""Custom tracking rates on a SynScan hand control: a closed loop on the PC (docs/tracking.md).

The hand control tracks at sidereal, lunar or solar rates of its own but takes no offset, and the
seed warns that a slew command overrides tracking. So while custom rates are in force on an
equatorial mount the driver turns the hand control's tracking off (``T 0``) and drives both axes
itself with variable-rate slews (``P 3 16|17 6|7 hi lo``, ¼″/s steps) at the sidereal rate plus the
offsets, corrected from every position poll: a proportional loop on the error between the
reading and the target integrated from where the loop started (so drift is corrected, never
accumulated). The slews are rate motions the horizon guard watches (and the dead-man stops with
their client); a goto, an abort, a manual move or a stop by the guard ends the loop, and the hand
control's own tracking is given back.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from contextlib import aclosing
from datetime import datetime, timedelta

from scopelink.astro import SIDEREAL_RATE_DEG_S, PierSide, wrap_signed_degrees
from scopelink.drivers.synscan.base import AXES
from scopelink.drivers.synscan.identify import synscan_tracking
from scopelink.drivers.synscan.loop_target import LoopTarget
from scopelink.drivers.synscan.parking import SynScanParking
from scopelink.mount import (
    MountAxis,
    MountError,
    MountState,
    Priority,
    TrackingMode,
)
from scopelink.mount.deadman import MotionClient, current_client
from scopelink.mount.rates import (
    GuideShifts,
    RateLoopStatistics,
    TrackingRates,
    clamp_rate,
)
from scopelink.protocol.synscan import Ack, SetTrackingMode, VariableRateSlew

__all__ = [
    "LOOP_GAIN_PER_S",
    "MAX_CORRECTION_ARCSEC_S",
    "RateLoopStatistics",
    "SynScanRates",
    "quantised",
]

logger = logging.getLogger(__name__)

LOOP_GAIN_PER_S = 0.2
"""The loop's proportional gain: a pointing error of E arcsec adds 0.2·E arcsec/s (a 5 s time
constant, long against one poll on the hand control's 9600-baud line)."""

MAX_CORRECTION_ARCSEC_S = 60.0
"""The correction never exceeds this on an axis (4x sidereal): a large error (a reading of the
slew just after the loop started) is closed at a bounded speed, not by a slew."""

QUANTUM_ARCSEC_S = 0.25
"""The variable-rate slew's step."""

POSITION_REPLY_BYTES = 18
"""The precise ``e`` reply (``34AB0500,12CE0500#``): the hand control reads its position when
the command arrives, the reading is stamped when the reply has arrived."""

LOOP_MODES = frozenset(
    {
        TrackingMode.SIDEREAL,
        TrackingMode.PEC,
        TrackingMode.LUNAR,
        TrackingMode.SOLAR,
        TrackingMode.KING,
        TrackingMode.ALT_AZ,
    }
)
"""The modes the loop runs in: sidereal, PEC and alt-az with custom rates; lunar, solar and King
always (the hand control has none of them: sidereal plus their RA offset)."""

HAND_CONTROL_MODES = frozenset({TrackingMode.SIDEREAL, TrackingMode.PEC, TrackingMode.ALT_AZ})
"""The modes the hand control tracks in by itself (alt-az: an alt-az mount's)."""


def quantised(arcsec_per_s: float) -> float:
    """A rate (arcsec/s) rounded to the variable-rate slew's ¼″/s step."""
    return round(arcsec_per_s / QUANTUM_ARCSEC_S) * QUANTUM_ARCSEC_S


class SynScanRates(SynScanParking):
    """Custom tracking rates by a PC loop (module docstring); between parking and the commands."""

    _rate_loop: asyncio.Task[None] | None = None
    _loop_mode: TrackingMode | None = None
    _loop_rates: dict[MountAxis, float] | None = None
    _hc_tracking: TrackingMode = TrackingMode.OFF
    _loop_taken = False
    """Another motion command is on its way: no correction may follow it onto the wire."""
    _loop_starting = False
    _loop_joining = False
    """A guide pulse joins the loop (pulse_guide): it does not take the axes over."""
    _loop_shifts: GuideShifts | None = None
    _loop_drive: tuple[TrackingRates, float, float] | None = None
    """The loop's rates in force and the last errors (RA, Dec degrees): to drive between polls."""
    _loop_target: LoopTarget | None = None
    _loop_owner: MotionClient | None = None
    """Who set the rates last: the owner of the loop's axes for the dead-man."""
    rate_updates = 0
    """Rate changes the running loop took without a restart (all loops of this driver)."""
    _loop_clock: tuple[datetime, float] | None = None
    """The loop's start on the mount clock and on the PC's (``loop.time()``)."""
    rate_loop_statistics: RateLoopStatistics | None = None
    """The running (or last) loop's errors: None before the first."""

    # While the loop runs, the hand control reads 't' = off, but the mount tracks (ours).
    # After the loop gave way to another command, tracking resumes in its mode even if a poll
    # that read 't' = off before the hand-back finishes after it (until 't' reads it back).
    _resume_mode: TrackingMode | None = None

    @property
    def _tracking(self) -> TrackingMode:
        return self._loop_mode or self._resume_mode or self._hc_tracking

    @_tracking.setter
    def _tracking(self, mode: TrackingMode) -> None:
        self._hc_tracking = mode
        if mode is not TrackingMode.OFF:
            self._resume_mode = None

    def _motion_commanded(self) -> None:
        """Called before any motion command is sent (goto, move, pulse, abort, park): from now
        on the loop sends no correction that could land after it."""
        super()._motion_commanded()
        if self._loop_mode is not None and not (self._loop_starting or self._loop_joining):
            self._loop_taken = True

    @property
    def custom_rates_running(self) -> bool:
        """Whether the PC loop drives the axes now."""
        return self._loop_mode is not None

    async def _set_tracking_rates(self, rates: TrackingRates) -> None:
        mode = self._loop_mode
        if (
            mode is not None
            and self._rate_loop is not None
            and self._loop_still_ours()
            and not (rates.zero and mode in HAND_CONTROL_MODES)
        ):
            await self._change_loop_rates(rates.plus_mode(mode))
            return
        await self._end_custom_rates()
        await self._start_custom_rates(rates)

    async def _change_loop_rates(self, rates: TrackingRates) -> None:
        """New rates for the running loop, without stopping it (a satellite's updates every
        second): its target goes on from where it is now at the new rates, and the axes get
        the new rates at once. The axis rates are checked by the horizon guard first, as a
        loop's first rates are: one heading out at a limit is refused, nothing changed."""
        assert self._loop_drive is not None
        assert self._loop_target is not None
        statistics = self.rate_loop_statistics
        assert statistics is not None
        _, first_error, second_error = self._loop_drive  # (RA, Dec) or (azimuth, altitude)
        target = self._loop_target.moved_to(self._loop_time_s()[0], rates)
        wanted = self._axis_rates_for(target, self._with_pulses(rates), first_error, second_error)
        changed = {
            axis: rate
            for axis, rate in wanted.items()
            if (self._loop_rates or {}).get(axis) != rate
        }
        for axis, rate in changed.items():
            await self._guard.check_move_now(axis, rate)
        if self._loop_target is None or not self._loop_still_ours():
            return  # ended meanwhile (a goto, an abort): the rates are recorded, not started
        t = self._loop_time_s()[0]  # now: a fresh reading above may have taken a while
        self._loop_target = self._loop_target.moved_to(t, rates)
        # The statistics' anchor: where and when the target is integrated from at these rates.
        assert self._loop_clock is not None
        statistics.started_at = self._loop_clock[0] + timedelta(seconds=t)
        statistics.anchor = (self._loop_target.ra_hours, self._loop_target.dec_deg)
        self._loop_drive = (rates, first_error, second_error)
        self._loop_owner = current_client()
        self.rate_updates += 1
        await self._drive_now(statistics)
        if self._loop_still_ours():  # the axes are the new owner's, changed or not
            for axis, rate in (self._loop_rates or {}).items():
                self._guard.motion_commanded(axis, rate)

    async def _start_custom_rates(
        self, rates: TrackingRates | None = None, mode: TrackingMode | None = None
    ) -> None:
        """Start the loop if rates are set, the mode is one it replaces, and no goto runs."""
        rates = self.tracking_rates if rates is None else rates
        mode = self._tracking if mode is None else mode
        if mode not in LOOP_MODES or (rates.zero and mode in HAND_CONTROL_MODES):
            return
        if self._goto_running:  # never a rate slew over a goto: set them again once it landed
            return
        rates = rates.plus_mode(mode)
        state = await self._read_state(Priority.COMMAND)
        if state.ra_j2000_hours is None or state.dec_j2000_deg is None:
            return
        await self._ask(SetTrackingMode(synscan_tracking(TrackingMode.OFF)), Ack)
        self._loop_mode = mode
        self._loop_rates = {}
        self._loop_taken = False
        self._loop_owner = current_client()
        self._loop_target = LoopTarget(0.0, state.ra_j2000_hours, state.dec_j2000_deg, rates)
        statistics = RateLoopStatistics(
            started_at=state.read_at, anchor=(state.ra_j2000_hours, state.dec_j2000_deg)
        )
        self.rate_loop_statistics = statistics
        self._loop_shifts = GuideShifts()
        self._loop_drive = (rates, 0.0, 0.0)
        self._loop_clock = (state.read_at, asyncio.get_running_loop().time())
        self._loop_starting = True
        try:
            first = self._axis_rates_for(self._loop_target, rates, 0.0, 0.0)
            await self._drive(first, statistics, first=True)
        except BaseException:
            await self._end_custom_rates(force=True)
            raise
        finally:
            self._loop_starting = False
        self._rate_loop = asyncio.create_task(
            self._run(state, statistics), name="synscan custom tracking rates"
        )

    def _axis_rates_for(
        self, target: LoopTarget, rates: TrackingRates, ra_error_deg: float, dec_error_deg: float
    ) -> dict[MountAxis, float]:
        """Axis rates (°/s, signed as the driver's rate slews) for the rates (with the guide
        pulses running) and the errors; ``target`` is the loop's (an alt-az loop's path)."""
        hemisphere = 1.0 if self.site.latitude_deg >= 0 else -1.0
        ra_arcsec = rates.ra_arcsec_per_s + clamp_rate(
            LOOP_GAIN_PER_S * ra_error_deg * 3600.0, MAX_CORRECTION_ARCSEC_S
        )
        dec_arcsec = rates.dec_arcsec_per_s + clamp_rate(
            LOOP_GAIN_PER_S * dec_error_deg * 3600.0, MAX_CORRECTION_ARCSEC_S
        )
        # RA growing means the polar axis turns slower than the stars.
        primary = hemisphere * (SIDEREAL_RATE_DEG_S * 3600.0 - ra_arcsec)
        dec_sign = -hemisphere if self._pier_side is PierSide.WEST else hemisphere
        return {
            MountAxis.PRIMARY: quantised(primary) / 3600.0,
            MountAxis.SECONDARY: quantised(dec_sign * dec_arcsec) / 3600.0,
        }

    async def _drive(
        self, wanted: dict[MountAxis, float], statistics: RateLoopStatistics, *, first: bool = False
    ) -> None:
        """Send the axis rates that changed. The first are rate motions started through the
        guard's checks; corrections are sent only while the axes are still the loop's, checked
        and sent in one turn on the wire, so a stop (abort, the dead-man, the guard) queued
        meanwhile always comes after them and wins."""
        assert self._loop_rates is not None
        for axis, rate in wanted.items():
            if self._loop_rates.get(axis) == rate:
                continue
            command = VariableRateSlew.from_arcsec_per_second(AXES[axis], rate * 3600.0)
            if first:

                async def start(
                    axis: MountAxis = axis, rate: float = rate, command: VariableRateSlew = command
                ) -> None:
                    if self._loop_rates is None:  # ended before its first command
                        return
                    # Recorded first: a hand-back queued behind this command stops the axis.
                    self._loop_rates[axis] = rate
                    self._axis_rates[axis] = rate
                    with self._stops_owed_on_failure(axes={axis}):
                        await self._ask_passthrough(command)

                await self._guarded_rate_motion(axis, rate, start)
                if self._loop_ended():  # meanwhile: its hand-back stopped the axis
                    return
            else:
                async with self.wire.exclusive():
                    if not self._loop_still_ours():
                        return
                    with self._stops_owed_on_failure(axes={axis}):
                        await self._ask_passthrough(command)
                    self._axis_rates[axis] = rate
                    owner = self._loop_owner
                    with self.acting_for(owner.token if owner is not None else None):
                        self._guard.motion_commanded(axis, rate)
            self._loop_rates[axis] = rate
            statistics.commands += 1

    def _reading_lag_s(self, first: MountState, state: MountState, dt: float) -> float:
        """How long before its stamp a reading was taken, on the mount's clock: the ``e`` reply's
        time on the line (at ``poll_policy.max_poll_baud``), scaled by the mount clock's rate
        against the PC's (a simulator's clock may run fast). The loop then leads a moving
        target by the reply time instead of trailing it (docs/tracking.md)."""
        real_s = POSITION_REPLY_BYTES * 10.0 / self.poll_policy.max_poll_baud
        elapsed_real = state.received_s - first.received_s
        ratio = dt / elapsed_real if elapsed_real > 0.5 and dt > 0.0 else 1.0
        return real_s * ratio

    def _loop_ended(self) -> bool:
        return self._loop_rates is None

    def _loop_still_ours(self) -> bool:
        """False once anything else took the axes over (goto, abort, move, the guard's stop)."""
        if self._loop_rates is None or self._loop_taken or not self._connected:
            return False
        return all(self._axis_rates.get(axis) == rate for axis, rate in self._loop_rates.items())

    async def _run(self, first: MountState, statistics: RateLoopStatistics) -> None:
        try:
            async with aclosing(self.states()) as states:
                async for state in states:
                    if not self._loop_still_ours():
                        break
                    if not state.connected or state.ra_j2000_hours is None:
                        continue
                    assert state.dec_j2000_deg is not None
                    dt = (state.read_at - first.read_at).total_seconds()
                    dt -= self._reading_lag_s(first, state, dt)
                    target = self._loop_target
                    assert target is not None
                    first_error, second_error, sky = self._loop_errors(target, state, dt)
                    statistics.add_error(sky)
                    self._loop_drive = (target.rates, first_error, second_error)
                    await self._drive_now(statistics)
        except MountError as error:
            logger.warning("%s: custom tracking rates: %s", self.wire.name, error)
            self._report_problem(f"custom tracking rates stopped: {error}")
        finally:
            if self._rate_loop is asyncio.current_task():
                mode = self._loop_mode
                self._resume_mode = mode if mode in HAND_CONTROL_MODES else TrackingMode.SIDEREAL
                # After the command that took over, which has the wire before the hand-back.
                with contextlib.suppress(MountError):  # a failed stop is owed, sent later
                    await asyncio.shield(self._hand_back())

    def _loop_errors(
        self, target: LoopTarget, state: MountState, dt: float
    ) -> tuple[float, float, float]:
        """The reading's errors against the target ``dt`` s after the loop began (the guide
        pulses' shifts added): RA and Dec (°) as :meth:`_axis_rates_for` takes them, and the
        error on the sky (arcsec)."""
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        ra_shift, dec_shift = (self._loop_shifts or GuideShifts()).at(dt)
        target_ra, target_dec = target.at(dt)
        ra_error = wrap_signed_degrees((target_ra + ra_shift - state.ra_j2000_hours) * 15.0)
        dec_error = target_dec + dec_shift - state.dec_j2000_deg
        return ra_error, dec_error, _sky_error_arcsec(ra_error, dec_error, state)

    def _loop_time_s(self) -> tuple[float, float]:
        """Seconds since the loop started on the mount's clock, and the mount clock's rate
        against the PC's (a simulator's may run fast; pulses are timed on the PC)."""
        assert self._loop_clock is not None
        mount_start, real_start = self._loop_clock
        t = (self.now() - mount_start).total_seconds()
        real = asyncio.get_running_loop().time() - real_start
        return t, (t / real if real > 0.5 and t > 0.0 else 1.0)

    async def _drive_now(self, statistics: RateLoopStatistics) -> None:
        """Drive at the rates in force, the running pulses and the last errors."""
        assert self._loop_drive is not None
        assert self._loop_target is not None
        rates, first_error, second_error = self._loop_drive
        target, with_pulses = self._loop_target, self._with_pulses(rates)
        await self._drive(
            self._axis_rates_for(target, with_pulses, first_error, second_error), statistics
        )

    def _with_pulses(self, rates: TrackingRates) -> TrackingRates:
        """``rates`` plus the guide pulses running now."""
        t, _ = self._loop_time_s()
        ra_pulse, dec_pulse = (self._loop_shifts or GuideShifts()).rates_at(t)
        return TrackingRates(
            rates.ra_arcsec_per_s + ra_pulse * 54000.0, rates.dec_arcsec_per_s + dec_pulse * 3600.0
        )

    async def _end_custom_rates(self, *, force: bool = False) -> None:
        """Stop the loop (rates zeroed, a tracking change, a disconnect): both axes stopped and
        the hand control's tracking given back."""
        self._resume_mode = None  # a command of the user's: its mode stands
        task, self._rate_loop = self._rate_loop, None
        if task is not None and task is not asyncio.current_task():
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
        if self._loop_mode is not None or force:
            await self._hand_back()

    async def _hand_back(self) -> None:
        """Stop the axes the loop still drives, and give the hand control its tracking back."""
        mode, rates = self._loop_mode, self._loop_rates or {}
        self._loop_mode = None
        self._loop_rates = None
        self._rate_loop = None
        if mode is None or not self._connected:
            return
        async with self.wire.exclusive():
            # The command that took over (a goto, a move) had the wire just before: let it
            # record what it did before telling which axes are still the loop's.
            for _ in range(3):
                await asyncio.sleep(0)
            ours = [axis for axis, rate in rates.items() if self._axis_rates.get(axis) == rate]
            with self._stops_owed_on_failure(axes=set(ours)):
                for axis in ours:
                    await self._send_rate_zero(axis)
                    self._axis_rates.pop(axis, None)
                    self._guard.motion_commanded(axis, 0.0)
                if self._goto_running:  # the goto decides the tracking (an RA/Dec one starts it)
                    return
                await self._ask(SetTrackingMode(synscan_tracking(mode)), Ack)
                self._hc_tracking = mode if mode in HAND_CONTROL_MODES else TrackingMode.SIDEREAL


def _sky_error_arcsec(ra_error_deg: float, dec_error_deg: float, state: MountState) -> float:
    cos_dec = math.cos(math.radians(state.dec_j2000_deg or 0.0))
    return 3600.0 * math.hypot(ra_error_deg * cos_dec, dec_error_deg)
