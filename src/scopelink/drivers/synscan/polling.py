"""The SynScan driver's state: one poll (``L``, ``e``; ``t``, ``p`` around motion and every
tenth cycle; ``J`` while unaligned), alt/az and RA/Dec of date computed on the PC, goto completion.
"""

from __future__ import annotations

import asyncio
import logging
from datetime import datetime

from scopelink.astro import PierSide, Site, angular_separation_deg
from scopelink.drivers.common import Pointing
from scopelink.drivers.synscan.connection import SynScanConnection
from scopelink.drivers.synscan.identify import mount_tracking
from scopelink.mount import DeviceError, MountState, NotConnectedError, Priority
from scopelink.protocol.synscan import (
    Aligned,
    GetPointingState,
    GetRaDec,
    GetTrackingMode,
    GotoInProgress,
    IsAligned,
    IsGotoInProgress,
    PointingSide,
    PointingState,
    Position,
    TrackingModeReply,
)

__all__ = ["SynScanPolling"]

logger = logging.getLogger(__name__)

FULL_READ_EVERY = 10
"""Poll cycles of a mount at rest read ``L`` and ``e`` only; every tenth also reads ``t`` and
``p`` (a tracking change on the keypad shows within about a third of a second)."""

PARK_TOLERANCE_DEG = 1.0
"""The park goto must end this close to the park position for the mount to read parked (the
hand control's alt/az and ours differ by refraction, under 0.6° above the horizon)."""


def pointing_of(position: Position, read_at: datetime, site: Site) -> Pointing:
    """The reading of one ``e`` reply (a Dec read beyond the pole is the same direction at
    RA + 12 h)."""
    ra = position.ra_hours
    if position.flipped:
        ra = (ra + 12.0) % 24.0
    return Pointing(ra, position.dec_degrees, read_at, site)


class SynScanPolling(SynScanConnection):
    """Read the state (see :class:`SynScanMount`)."""

    async def refresh(self) -> MountState:
        """Poll ``L`` and ``e`` (J2000 RA/Dec); ``t`` and ``p`` (equatorial mounts) around motion
        and every tenth cycle; ``J`` while unaligned. Alt/az and of-date RA/Dec are computed on
        the PC (see ``docs/drivers-synscan.md``)."""
        return await self._read_state(Priority.POLL)

    async def _read_state(self, priority: Priority) -> MountState:
        if not self._connected:
            raise NotConnectedError(f"{self.wire.name} is not connected")
        try:
            await self._reconnection.run_if(self._needs_reidentifying, self._reconnect)
        except DeviceError as error:
            self._report_problem(f"reconnecting: {error}")
            self._judge_link()
            raise
        epoch = self._motion_epoch
        failures = self.wire.statistics.failures
        # 't' and 'p' change with motion (a goto enables tracking and may flip the tube) or on the
        # keypad: read them around motion and every few cycles, not in every one (see the docs).
        full = (
            priority is Priority.COMMAND
            or self._slewing
            or epoch != self._epoch_at_full_read
            or self._cycles_since_full_read + 1 >= FULL_READ_EVERY
            # A failed exchange may have been a command the hand control carried out late.
            or self.wire.statistics.failures != self._failures_at_full_read
        )
        tracking: TrackingModeReply | None = None
        try:
            # L before e: when L says the goto has ended, the position read next is its landing.
            goto = await self._ask(IsGotoInProgress(), GotoInProgress, priority)
            position = await self._ask(GetRaDec(), Position, priority)
            read_at = self.now()
            place = pointing_of(position, read_at, self.site)
            if full:
                # The astrometry (about 1 ms of CPU) runs while the hand control answers 't'.
                tracking = await self._ask(
                    GetTrackingMode(), TrackingModeReply, priority, meanwhile=place.compute
                )
                if self._capabilities.can_report_pier_side:
                    side = await self._ask(GetPointingState(), PointingState, priority)
                    self._pier_side = self._pier_side_of(side)
            if not self._aligned:
                self._aligned = (await self._ask(IsAligned(), Aligned, priority)).aligned
        except DeviceError as error:
            if not self._stop_blind_motion(error):
                self._report_problem(str(error))
            self._judge_link()
            raise
        ra, dec = place.ra_j2000_hours, place.dec_j2000_deg
        alt, az, ra_of_date, dec_of_date = place.compute()
        problems: tuple[str, ...] = (self._site_mismatch,) if self._site_mismatch else ()
        if tracking is not None:
            self._cycles_since_full_read = 0
            self._epoch_at_full_read = epoch
            self._failures_at_full_read = failures
            mode = mount_tracking(tracking.mode)
            if mode is None:
                problems += (f"unknown tracking mode {tracking.mode} reported",)
            else:
                self._tracking = mode
        else:
            self._cycles_since_full_read += 1
        mode = self._tracking
        if self._motion_epoch == epoch:
            # A goto sent while this poll waited for the wire is not over whatever L said.
            self._goto_running = self._goto_still_running(goto.in_progress, alt, az)
            if not self._goto_running and await self._goto_landed():
                self._goto_running = True  # a further pass to a moving target (parking.py)
        if self._parked and not self._slewing and not self._arrived_at_park(alt, az):
            problems += (
                "the park goto ended away from the park position: not parked (park again, "
                "unpark, or abort)",
            )
        state = MountState(
            read_at=read_at,
            connected=True,
            ra_j2000_hours=ra,
            dec_j2000_deg=dec,
            ra_of_date_hours=ra_of_date,
            dec_of_date_deg=dec_of_date,
            alt_deg=alt,
            az_deg=az,
            pier_side=self._pier_side,
            slewing=self._slewing,
            tracking=mode,
            parked=self._arrived_at_park(alt, az),
            aligned=self._aligned,
            pulse_guiding=bool(self._pulses),
            problems=problems,
            received_s=place.received_s,
        )
        self._publish(state)
        return state

    async def _goto_landed(self) -> bool:
        """A goto has just ended: True if a further pass was sent (``parking.py``)."""
        return False

    def _arrived_at_park(self, alt: float, az: float) -> bool:
        """Parked: the park goto has ended, within ``PARK_TOLERANCE_DEG`` of where it went."""
        target = self._park_target
        if not self._parked or self._slewing or target is None:
            return False
        off = angular_separation_deg(az, alt, target.az_deg, target.alt_deg)
        return bool(off <= PARK_TOLERANCE_DEG)

    def _stop_blind_motion(self, error: DeviceError) -> bool:
        """A poll failed (twice: the retry too) while an axis turns at a rate: nobody sees where
        it goes, so its stop is owed, sent when the link returns. Gotos carry on (their target
        was checked against the limits), as does tracking. True if a stop was owed."""
        moving = {axis for axis, rate in self._axis_rates.items() if rate} | set(self._pulses)
        if not moving:
            return False
        self._owe_stops(axes=moving, cause=f"the position cannot be read while it turns: {error}")
        return True

    @property
    def _slewing(self) -> bool:
        # An unconfirmed stop means the mount may still move: say so until it is confirmed.
        return self._goto_running or any(self._axis_rates.values()) or bool(self._owed)

    def _goto_still_running(self, in_progress: bool, alt: float, az: float) -> bool:
        if not in_progress:
            self._settle = None
            return False
        if self._settle is None:
            return True
        # An Alt-Az goto on firmware whose L may stick: trust the position once it stands still.
        loop_time = asyncio.get_running_loop().time()
        return not self._settle.update(alt, az, loop_time)

    def _pier_side_of(self, reply: PointingState) -> PierSide:
        # 'E' is the normal side in the north and the flipped one in the south ("W" vice versa).
        flipped = reply.side is PointingSide.WEST
        if self.site.latitude_deg < 0:
            flipped = not flipped
        return PierSide.WEST if flipped else PierSide.EAST
