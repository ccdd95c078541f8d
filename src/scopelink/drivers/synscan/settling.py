"""When has an Alt-Az goto ended, on firmware whose ``L`` never says so?

After an Alt-Az (``b``) goto some hand controls answer ``L`` with '1' until the next ``M`` or
goto. Drivers then fall back on the position: the goto has ended once the pointing has stayed put
for a few polls near the target, or, should it never get near (a limit stopped it), once it has
stayed put for a few polls after a generous timeout.
"""

from __future__ import annotations

from dataclasses import dataclass

from scopelink.astro import angular_separation_deg

__all__ = ["SettleDetector"]

STILL_DEG = 0.001
"""Movement between two polls below this (3.6") is standing still. During the final deceleration
of a slew (3.3°/s² for an EQ6) three polls 30 ms apart move several times more than this."""
NEAR_TARGET_DEG = 0.5
"""Close enough to the target for a standstill to count as the landing."""


@dataclass(slots=True)
class SettleDetector:
    """Feed it each polled (alt, az) while ``L`` keeps saying '1'; it says when the goto ended."""

    target_alt_deg: float
    target_az_deg: float
    started_at_s: float
    timeout_s: float = 300.0
    polls: int = 3
    _last: tuple[float, float] | None = None
    _still: int = 0
    settled: bool = False

    def update(self, alt_deg: float, az_deg: float, now_s: float) -> bool:
        """Record one reading taken at ``now_s`` (seconds, any monotonic origin); True once the
        goto has ended (and from then on)."""
        if self.settled:
            return True
        last, self._last = self._last, (alt_deg, az_deg)
        if last is None or angular_separation_deg(last[1], last[0], az_deg, alt_deg) > STILL_DEG:
            self._still = 0
            return False
        self._still += 1
        if self._still + 1 < self.polls:
            return False
        near = (
            angular_separation_deg(self.target_az_deg, self.target_alt_deg, az_deg, alt_deg)
            <= NEAR_TARGET_DEG
        )
        self.settled = near or now_s - self.started_at_s >= self.timeout_s
        return self.settled
