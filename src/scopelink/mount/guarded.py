"""What the horizon guard is given: the narrow view of the mount it guards, and its settings.

The guard (:mod:`scopelink.mount.guard`) and its arithmetic (:mod:`scopelink.mount.budget`,
:mod:`scopelink.mount.danger`) see the mount only through :class:`GuardedMount`: its limits and
site, its clock and astrometry, its state stream, and the two commands that stop it. They import
nothing of :mod:`scopelink.mount.base`, so any object with these members can be guarded.
"""

from __future__ import annotations

from collections.abc import AsyncGenerator
from dataclasses import dataclass
from datetime import datetime
from typing import Protocol

from scopelink.astro import Site
from scopelink.mount.limits import Limits
from scopelink.mount.sun import SunZone
from scopelink.mount.types import Capabilities, MountState, TrackingMode

__all__ = ["GuardSettings", "GuardedMount"]


class GuardedMount(Protocol):
    """The members of a mount that the horizon guard reads and commands (``Mount`` has them)."""

    @property
    def stops_itself_at_limits(self) -> bool:
        """Whether the device stops rate motions and tracking at the limits by itself (then the
        guard only refuses motions that head further out)."""

    @property
    def capabilities(self) -> Capabilities: ...

    @property
    def site(self) -> Site: ...

    @property
    def limits(self) -> Limits: ...

    @property
    def state(self) -> MountState:
        """The last published state."""

    def now(self) -> datetime:
        """The mount's clock (a simulated mount may run its own)."""

    def observed_altaz(self, ra_j2000_hours: float, dec_j2000_deg: float) -> tuple[float, float]:
        """Observed altitude and azimuth of a J2000 position now, at the mount's site."""

    def sun_zone(self) -> SunZone | None:
        """The Sun avoidance zone now (None: off); raises ``LimitError`` if it cannot be placed."""

    def states(self) -> AsyncGenerator[MountState, None]:
        """Each newly published state, the current one first; polls at full rate meanwhile."""

    async def refresh(self) -> MountState:
        """A fresh reading, published."""

    async def abort(self) -> None:
        """Stop every rate motion (and a slew)."""

    async def set_tracking(self, mode: TrackingMode) -> None:
        """Turn tracking off (the guard sends only ``TrackingMode.OFF``)."""


@dataclass(frozen=True, slots=True)
class GuardSettings:
    """How early the guard stops a motion.

    ``margin_deg`` is kept between the predicted stopping point and the limit. The guard looks
    ``reaction_polls`` poll periods ahead: one to see the next reading, the rest for the stop
    commands to reach the device. ``min_lookahead_s`` (mount clock) is the floor of that
    look-ahead for very fast links. The motors then brake: ``braking_deg_s2`` is the deceleration
    assumed (lower than any Sky-Watcher ramp we know: the simulator's EQ6 brakes at 3.3°/s², the
    Sky Tracker at 2°/s²), so the braking distance is over- rather than underestimated.

    Tracking alone moves at most 15°/h: while the tracked position is more than ``near_deg``
    (plus the margin) from every limit, the guard computes where tracking has carried it every
    ``far_check_s`` (real) seconds instead of polling the device; nearer, it polls.

    Between good readings (a noisy link) the guard budgets for the travel it cannot see: the
    time since the last good reading plus ``stop_latency_s`` (from the decision until the
    device has the stop) at the worst rate the commanded motions and ``tracking_deg_s`` allow,
    plus the braking distance; it checks that budget every ``blind_check_s``. A stop the device
    has not confirmed within ``confirm_s`` is sent again (the wait doubling up to
    ``confirm_max_s``), both axes, until it is confirmed.
    """

    margin_deg: float = 0.2
    reaction_polls: float = 4.0
    min_lookahead_s: float = 0.05
    braking_deg_s2: float = 1.5
    near_deg: float = 1.0
    far_check_s: float = 0.25
    stop_latency_s: float = 0.15
    blind_check_s: float = 0.02
    tracking_deg_s: float = 0.0045
    confirm_s: float = 1.0
    confirm_max_s: float = 8.0
