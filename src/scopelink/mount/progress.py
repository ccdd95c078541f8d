"""How far a slew has to go, and when it should arrive (``Mount.wait_for_slew``'s progress)."""

from __future__ import annotations

from datetime import datetime

from scopelink.astro import angular_separation_deg
from scopelink.mount.types import MountState, SlewProgress, SlewTarget

__all__ = ["ProgressTracker"]


class ProgressTracker:
    """Distance to the target and an arrival estimate from the recent closing speed."""

    def __init__(self, target: SlewTarget | None) -> None:
        self._target = target
        self._last: tuple[datetime, float] | None = None
        self._speed_deg_s: float | None = None

    def update(self, state: MountState) -> SlewProgress:
        distance = self._distance(state)
        if distance is None:
            return SlewProgress(state, None, None)
        if self._last is not None:
            elapsed = (state.read_at - self._last[0]).total_seconds()
            closed = self._last[1] - distance
            if elapsed > 0 and closed > 0:
                speed = closed / elapsed
                # Smooth over a few readings: acceleration ramps make single steps jumpy.
                previous = self._speed_deg_s
                self._speed_deg_s = speed if previous is None else 0.5 * (previous + speed)
        self._last = (state.read_at, distance)
        eta = None
        if not state.slewing:
            eta = 0.0
        elif self._speed_deg_s:
            eta = distance / self._speed_deg_s
        return SlewProgress(state, distance, eta)

    def _distance(self, state: MountState) -> float | None:
        target = self._target
        if target is None:
            return None
        if target.ra_j2000_hours is not None and target.dec_j2000_deg is not None:
            if state.ra_j2000_hours is None or state.dec_j2000_deg is None:
                return None
            return angular_separation_deg(
                state.ra_j2000_hours * 15.0,
                state.dec_j2000_deg,
                target.ra_j2000_hours * 15.0,
                target.dec_j2000_deg,
            )
        if (
            target.alt_deg is None
            or target.az_deg is None
            or state.alt_deg is None
            or state.az_deg is None
        ):
            return None
        return angular_separation_deg(state.az_deg, state.alt_deg, target.az_deg, target.alt_deg)
