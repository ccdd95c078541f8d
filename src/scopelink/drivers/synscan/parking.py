"""The SynScan driver's park and resume pieces: axis positions, "set axis position" after a power
cycle, and slow gotos (``docs/parking.md``).

The hand control has no command that reads its axis counters, so the driver holds the counters'
meaning itself: the geometry of ``scopelink.sim.geometry`` (German equatorial: counterweight down
at the pole is primary 0, secondary 90; alt-az: primary = azimuth, secondary = altitude), the
convention our emulator answers "set axis position" and "slow goto" in. After a power cycle the
hand control is not aligned and ignores every goto; once its counters are restored the driver is
*resumed*: it turns gotos into a slow goto per axis to counters it computes, and follows a moving
target with further, short passes once each lands (:data:`REFINE_PASSES`).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

from scopelink.astro import angular_separation_deg
from scopelink.drivers.synscan.base import AXES
from scopelink.drivers.synscan.polling import SynScanPolling
from scopelink.mount import (
    AlignmentMode,
    DeviceError,
    LimitError,
    MountAxis,
    MountError,
    MountState,
    ParkPosition,
    Priority,
)
from scopelink.mount.parking import ParkRecord, ParkRecordError, Resume, check_restore_agrees
from scopelink.protocol.synscan import (
    Aligned,
    GotoInProgress,
    IsAligned,
    IsGotoInProgress,
    PassthroughFailed,
    SetAxisPosition,
    SlowGoto,
)

if TYPE_CHECKING:
    from scopelink.sim.geometry import Geometry

__all__ = [
    "POLE_AMBIGUITY_DEG",
    "POWER_ON_TOLERANCE_DEG",
    "REFINE_PASSES",
    "RESTORE_TOLERANCE_DEG",
    "STILL_DEG",
    "SlowGotoRefusedError",
    "SynScanParking",
]

logger = logging.getLogger(__name__)

POWER_ON_TOLERANCE_DEG = 1.0
"""An unaligned hand control whose reading is farther than this from where its counters point at
power-on has been moved since (on the keypad): its counters are not restored."""

STILL_DEG = 0.01
"""Two readings in a row farther apart than this: an axis turns (a keypad slew, which ``L`` does
not report), and no axis position is set."""

RESTORE_TOLERANCE_DEG = 0.05
"""After "set axis position" the reading must be this close to the park record (else the hand
control did not obey, and the driver says so)."""

POLE_AMBIGUITY_DEG = 1.0
"""Parked (by ``b``) this close to the celestial pole, an equatorial mount's polar axis angle
cannot be told from its pointing: the record then has no axis positions."""

REFINE_PASSES = 2
"""Further slow gotos to a moving (tracked) target once a resumed goto lands: the first lands
where the target was when it started, each pass after it where the target is then."""


class SlowGotoRefusedError(DeviceError):
    """The hand control answered a slow goto as a failed passthrough (a bridge does)."""


def _separation_deg(state: MountState, alt_deg: float, az_deg: float) -> float:
    assert state.alt_deg is not None
    assert state.az_deg is not None
    return float(angular_separation_deg(state.az_deg, state.alt_deg, az_deg, alt_deg))


class SynScanParking(SynScanPolling):
    """Park records and resumes (see the module's docstring and :class:`SynScanMount`)."""

    # Immutable defaults at class level: the constructor stays SynScanBase's, typed.
    _resumed: bool = False
    """The counters were restored after a power cycle: gotos go by slow goto."""
    _park_axes: tuple[float, float] | None = None
    """The counters the last park slow-goto went to (exact, for the park record)."""
    _refine: tuple[float, float] | None = None
    _refine_passes: int = 0
    _slow_goto_refused = False
    """The device answered a slow goto as a failed passthrough (a bridge): park by ``b``."""

    async def _identify(self, *, reopen: bool = True) -> None:
        """Identifying the device anew (connect, reconnect) ends resumed mode: a link that was
        lost may have been a power cycle, after which the restored counters are gone."""
        self._resumed = False
        self._refine = None
        await super()._identify(reopen=reopen)

    @property
    def resumed(self) -> bool:
        """Whether gotos go by slow goto: counters restored, the hand control not aligned."""
        return self._resumed and not self._aligned

    def geometry(self) -> Geometry:
        """What the hand control's axis counters mean on this mount (see the module)."""
        from scopelink.sim.geometry import geometry_for  # noqa: PLC0415 - the sim, only if used

        return geometry_for(self._capabilities.alignment_mode, self.site.latitude_deg)

    def axes_for(self, alt_deg: float, az_deg: float) -> tuple[float, float]:
        """The counters that point at an observed alt/az (the pier side a goto would choose)."""
        geometry = self.geometry()
        side = geometry.choose_side(alt_deg, az_deg, self._pier_side)
        return geometry.to_axes(alt_deg, az_deg, side)

    def park_position_at_axes(self, primary_deg: float, secondary_deg: float) -> ParkPosition:
        """A park position given as axis positions (reached by slow goto to exactly them)."""
        alt, az = self.geometry().to_observed(primary_deg, secondary_deg)
        return ParkPosition(alt, az % 360.0, axes_deg=(primary_deg, secondary_deg))

    def _slow_park_axes(self, park: ParkPosition) -> tuple[float, float] | None:
        """The counters to park at by slow goto, or None to park with ``b`` (see the docs)."""
        if park.axes_deg is not None:
            return park.axes_deg
        if self.resumed:
            return self.axes_for(park.alt_deg, park.az_deg)
        equatorial = self._capabilities.alignment_mode is not AlignmentMode.ALT_AZ
        if equatorial and not self.park_position_chosen and not self._slow_goto_refused:
            return self.geometry().home  # counterweight down at the pole: SynScan's home
        return None

    async def _slow_goto_axes(self, axes: tuple[float, float]) -> None:
        for axis, degrees in zip(MountAxis, axes, strict=True):
            command = SlowGoto.from_degrees(AXES[axis], degrees)
            if isinstance(await self._wire_ask(command), PassthroughFailed):
                raise SlowGotoRefusedError(
                    f"{command.describe()!r}: the hand control answered a failed passthrough"
                )

    def _follow(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """Refine the resumed goto that just started once it lands (tracked targets move)."""
        self._refine = (ra_j2000_hours, dec_j2000_deg)
        self._refine_passes = REFINE_PASSES

    async def _goto_landed(self) -> bool:
        """A goto just landed: send the next refining pass if one is due (True if sent)."""
        target, self._refine = self._refine, None
        if target is None or self._refine_passes <= 0 or not self.resumed:
            return False
        if any(self._axis_rates.values()) or self._pulses or self._owed:
            return False  # something else took the axes over
        self._refine_passes -= 1
        alt, az = self.observed_altaz(*target)
        try:
            self._limits.check_altaz(alt, az)
            with self._stops_owed_on_failure(cancel_goto=True):
                await self._slow_goto_axes(self.axes_for(alt, az))
        except (LimitError, MountError) as error:
            logger.warning("%s: the goto was not refined: %s", self.wire.name, error)
            return False
        self._refine = target
        self._motion_epoch += 1
        return True

    # --- the park record (scopelink.mount.parking.AxisResuming) ------------------------------

    def park_axes(self, state: MountState) -> tuple[float, float] | None:
        if self._park_axes is not None:
            return self._park_axes
        if state.alt_deg is None or state.az_deg is None:
            return None
        geometry = self.geometry()
        axes = geometry.to_axes(state.alt_deg, state.az_deg, state.pier_side)
        if geometry.pole_distance_deg(*axes) < POLE_AMBIGUITY_DEG:
            return None
        return axes

    async def resume_axes(self, record: ParkRecord, state: MountState) -> Resume:
        self._aligned = (await self._ask(IsAligned(), Aligned)).aligned
        if self._aligned:
            try:
                off = check_restore_agrees(record, state, self._limits)
            except ParkRecordError as error:  # refused: the aligned hand control knows better
                return Resume(str(error))
            return Resume(
                f"the hand control kept its alignment ({off:.2f}° from the park record): "
                "nothing to restore",
                restored=True,
                record=record,
            )
        running = (await self._ask(IsGotoInProgress(), GotoInProgress)).in_progress
        again = await self._read_state(Priority.COMMAND)  # a keypad slew shows no L: it moves
        assert again.alt_deg is not None
        assert again.az_deg is not None
        if (
            running
            or self._slewing
            or _separation_deg(state, again.alt_deg, again.az_deg) > STILL_DEG
        ):
            raise ParkRecordError(
                "the mount is moving: axis positions are never set while it moves; stop it and "
                "unpark again"
            )
        if record.axes_deg is None:
            return Resume("the park record has no axis positions: nothing was restored")
        geometry = self.geometry()
        home_alt, home_az = geometry.to_observed(*geometry.home)
        moved = _separation_deg(again, home_alt, home_az)
        if moved > POWER_ON_TOLERANCE_DEG:
            return Resume(
                f"not restored: the hand control is not aligned but points {moved:.1f}° from "
                "where its counters start at power-on (moved on the keypad since?): align it"
            )
        async with self.wire.exclusive():
            for axis, degrees in zip(MountAxis, record.axes_deg, strict=True):
                await self._ask_passthrough(SetAxisPosition.from_degrees(AXES[axis], degrees))
        after = await self._read_state(Priority.COMMAND)
        off = _separation_deg(after, record.alt_deg, record.az_deg)
        if off > RESTORE_TOLERANCE_DEG:
            raise DeviceError(
                f"set axis position not obeyed: the hand control points {off:.3f}° from the "
                "park record"
            )
        self._resumed = True
        return Resume(
            f"axis positions of the park at {record.parked_at:%Y-%m-%d %H:%M} UTC restored; "
            "gotos go by slow goto until the hand control is aligned",
            restored=True,
            record=record,
        )
