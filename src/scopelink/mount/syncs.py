"""How far a sync may move the frame every limit is judged in.

A sync tells the mount where it points; from then on its readings, and so the horizon, the
altitude limit and every goto's check, are in the synced frame. A far sync therefore moves the
whole envelope: synced 25° high, a mount at the horizon reads 25° and is driven into the ground.
``Mount.sync_equatorial`` refuses a sync (``LimitError``, naming ``limits.max_sync_deg``) when

- its target lies farther than ``max_sync_deg`` on the sky from where the mount reports it points
  (a plate-solve correction is a fraction of a degree to a few degrees; farther is the wrong
  object, a typo or a hostile client), or
- together with every earlier sync it would correct the *un-synced* frame by more than
  ``max_sync_deg``, counted in axis degrees: otherwise a client could walk the frame 9° at a time
  as far as it likes, and near the pole a small step on the sky turns the RA axis far (which
  moves every position away from the pole by that much).

The net correction is kept as (primary, secondary) axis degrees: hour angle and declination on an
equatorial mount, azimuth and altitude on an alt-az one. A device that syncs internally (the hand
control) is modelled by the sum of the steps it was told to make; the simulator knows its
counters exactly and says so itself. The decision and its reasons are in
``docs/reliability-safety.md`` ("Syncs").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scopelink.astro import angular_separation_deg
from scopelink.mount.errors import LimitError
from scopelink.mount.limits import Limits
from scopelink.mount.types import MountState

__all__ = ["SyncFrame", "check_sync", "refuse_sync_while_slewing", "sync_distance_deg"]


@dataclass(frozen=True, slots=True)
class SyncFrame:
    """The net correction syncs have made to the frame, in axis degrees."""

    primary_deg: float = 0.0
    secondary_deg: float = 0.0

    @property
    def reach_deg(self) -> float:
        """The most any position moves between the un-synced frame and this one (degrees)."""
        return math.hypot(self.primary_deg, self.secondary_deg)

    def plus(self, primary_deg: float, secondary_deg: float) -> SyncFrame:
        return SyncFrame(
            _wrap_signed(self.primary_deg + primary_deg), self.secondary_deg + secondary_deg
        )

    def after_sync(
        self,
        ra_j2000_hours: float,
        dec_j2000_deg: float,
        state: MountState,
        target_altaz: tuple[float, float] | None,
    ) -> SyncFrame:
        """This frame plus the step a sync from the reading ``state`` to the target makes on each
        axis: azimuth and altitude when ``target_altaz`` (the target's observed altitude and
        azimuth, for an alt-az mount) is given, else hour angle and declination."""
        if target_altaz is not None and state.alt_deg is not None and state.az_deg is not None:
            alt, az = target_altaz
            return self.plus(az - state.az_deg, alt - state.alt_deg)
        sync_distance_deg(state, ra_j2000_hours, dec_j2000_deg)  # raises without a reading
        assert state.ra_j2000_hours is not None
        assert state.dec_j2000_deg is not None
        return self.plus(
            (ra_j2000_hours - state.ra_j2000_hours) * 15.0, dec_j2000_deg - state.dec_j2000_deg
        )


def refuse_sync_while_slewing(state: MountState) -> None:
    """Raise :class:`LimitError` while ``state`` says the mount slews: the reading lags the
    axes, so the step a sync would make is unknown, and unknown steps could add up past
    ``max_sync_deg``."""
    if state.slewing:
        raise LimitError(
            "the mount is slewing, so a sync would correct it by an unknown amount: nothing "
            "was sent to the mount (wait for the slew to end)"
        )


def sync_distance_deg(state: MountState, ra_j2000_hours: float, dec_j2000_deg: float) -> float:
    """How far (degrees on the sky) a J2000 position is from the reading ``state``."""
    if state.ra_j2000_hours is None or state.dec_j2000_deg is None:
        raise LimitError(
            "the mount has not reported where it points yet, so a sync cannot be judged against "
            "limits.max_sync_deg: nothing was sent to the mount"
        )
    return float(
        angular_separation_deg(
            state.ra_j2000_hours * 15.0, state.dec_j2000_deg, ra_j2000_hours * 15.0, dec_j2000_deg
        )
    )


def check_sync(limits: Limits, distance_deg: float, reach_deg: float) -> None:
    """Raise :class:`LimitError` unless a sync ``distance_deg`` from the reading, leaving the
    frame ``reach_deg`` from the un-synced one, is within ``limits.max_sync_deg``."""
    most = limits.max_sync_deg
    if not distance_deg <= most:
        raise LimitError(
            f"the sync target is {distance_deg:.2f}° from where the mount reports it points, "
            f"beyond limits.max_sync_deg ({most:g}°): nothing was sent to the mount (a plate-solve "
            "correction is smaller; check the target, or raise limits.max_sync_deg if the mount "
            "really is that far off)"
        )
    if not reach_deg <= most:
        raise LimitError(
            f"with the earlier syncs this one would shift the mount's frame by {reach_deg:.2f}° in "
            f"axis angles, beyond limits.max_sync_deg ({most:g}°): nothing was sent to the mount "
            "(near the pole a small step on the sky turns the RA axis far; sync away from the "
            "pole, realign the mount, or raise limits.max_sync_deg)"
        )


def _wrap_signed(degrees: float) -> float:
    return (degrees + 180.0) % 360.0 - 180.0
