"""The SynScan PC loop's integrated target (docs/tracking.md, "The SynScan loop")."""

from __future__ import annotations

from dataclasses import dataclass

from scopelink.mount.rates import TrackingRates

__all__ = ["LoopTarget"]


@dataclass(frozen=True, slots=True)
class LoopTarget:
    """The loop's integrated target: J2000 RA (h) and Dec (°) at ``since_s`` (seconds of the
    mount's clock after the loop began), moving at ``rates`` from there. A rate update moves the
    anchor to where the target is then (:meth:`moved_to`), so the target never jumps."""

    since_s: float
    ra_hours: float
    dec_deg: float
    rates: TrackingRates

    def at(self, t_s: float) -> tuple[float, float]:
        dt = t_s - self.since_s
        return self.ra_hours + self.rates.ra_hours_per_s * dt, self.dec_deg + (
            self.rates.dec_deg_per_s * dt
        )

    def moved_to(self, t_s: float, rates: TrackingRates) -> LoopTarget:
        """The same target from ``t_s`` on, at ``rates``."""
        return LoopTarget(t_s, *self.at(t_s), rates)
