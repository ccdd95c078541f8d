"""Slew progress for the page: distance and arrival estimate while a goto runs, then for a few
seconds how it ended ("arrived at Vega", "stopped 12.3° from Vega"), then nothing.

The distance and estimate are :class:`scopelink.mount.progress.ProgressTracker`'s (the CLI's
``goto`` shows the same). A slew is a goto when ``mount.target`` changed since the last one (a
new goto sets a new target); the pad's rate motions keep the old target and are shown as "moving",
with no distance, so an old target is never shown as where the mount is going.
"""

from __future__ import annotations

import time

from scopelink.mount import Mount, MountState, SlewTarget
from scopelink.mount.progress import ProgressTracker

__all__ = ["ARRIVED_DEG", "ENDED_SHOWN_S", "SlewWatch"]

ARRIVED_DEG = 0.25
"""A goto that ended closer than this to its target arrived; farther, it was stopped."""
ENDED_SHOWN_S = 6.0
"""How long the page shows how a slew ended."""


def _target_label(target: SlewTarget) -> str:
    if target.name:
        return target.name
    if target.ra_j2000_hours is not None and target.dec_j2000_deg is not None:
        return f"RA {target.ra_j2000_hours:.3f} h, Dec {target.dec_j2000_deg:+.2f}°"
    return f"alt {target.alt_deg:.1f}°, az {target.az_deg:.1f}°"


class SlewWatch:
    """Follows the mount's slews across updates; :meth:`update` gives what the page shows."""

    def __init__(self) -> None:
        self._target: SlewTarget | None = None
        self._tracker = ProgressTracker(None)
        self._goto = False
        self._moving = False
        self._ended: dict[str, object] | None = None
        self._ended_until = 0.0

    def update(self, mount: Mount, state: MountState) -> dict[str, object] | None:
        """``{"active": true, "kind": "goto"/"park"/"moving", "target", "distance_deg",
        "eta_s"}`` while moving; ``{"active": false, "arrived", "target", "distance_deg"}`` for
        a few seconds after; None otherwise (and while the link is down)."""
        target = mount.target
        if target is not self._target:
            self._target = target
            self._tracker = ProgressTracker(target)
            self._goto = target is not None
        if not state.connected:
            return None
        if state.slewing:
            self._ended = None
            self._moving = True
            if mount.parking:
                return {"active": True, "kind": "park", "target": "the park position"}
            if self._goto and target is not None:
                progress = self._tracker.update(state)
                return {
                    "active": True,
                    "kind": "goto",
                    "target": _target_label(target),
                    "distance_deg": _round(progress.distance_deg, 3),
                    "eta_s": _round(progress.eta_s, 1),
                }
            return {"active": True, "kind": "moving", "target": None}
        if self._moving:
            self._moving = False
            self._ended = self._ending(mount, state)
            self._ended_until = time.monotonic() + ENDED_SHOWN_S
        if self._ended is not None and time.monotonic() < self._ended_until:
            return self._ended
        self._ended = None
        return None

    def _ending(self, mount: Mount, state: MountState) -> dict[str, object]:
        target = self._target
        if state.parked:
            return {"active": False, "kind": "park", "arrived": True, "target": "park"}
        if not self._goto or target is None:
            return {"active": False, "kind": "moving", "arrived": True, "target": None}
        self._goto = False  # the pad's motions after it are not this goto
        distance = self._tracker.update(state).distance_deg
        return {
            "active": False,
            "kind": "goto",
            "arrived": distance is not None and distance <= ARRIVED_DEG,
            "target": _target_label(target),
            "distance_deg": _round(distance, 3),
        }


def _round(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)
