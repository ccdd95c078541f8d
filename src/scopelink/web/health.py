"""The connection's health in words: "link OK, 48 readings/s", "no reading for 6 s".

Readings per second are the poller's successful polls over the last few seconds. The level is
``ok``, ``warn`` (amber: no reading for more than half of ``stale_after_s``, or failed readings
in the window) or ``bad`` (red: the link is down, or the last reading is older than
``stale_after_s`` and no longer shown as current).
"""

from __future__ import annotations

import time
from collections import deque

from scopelink.mount import Mount, MountState

__all__ = ["WINDOW_S", "HealthMeter"]

WINDOW_S = 3.0
"""The window over which readings per second are counted."""


class HealthMeter:
    """Counts the poller's readings between updates and words the result."""

    def __init__(self) -> None:
        self._samples: deque[tuple[float, int, int]] = deque()

    def update(self, mount: Mount, state: MountState) -> dict[str, object]:
        """``{"level": "ok"/"warn"/"bad", "text", "readings_per_s"}``."""
        now = time.monotonic()
        poller = mount.poller
        samples = self._samples
        samples.append((now, poller.polls, poller.failures))
        while len(samples) > 2 and now - samples[1][0] >= WINDOW_S:
            samples.popleft()
        first = samples[0]
        elapsed = now - first[0]
        rate = (poller.polls - first[1]) / elapsed if elapsed > 0.5 else None
        failed = poller.failures - first[2]
        age = state.position_age_s()
        stale_after = mount.stale_after_s
        if not state.connected:
            level, text = "bad", f"link down: no reading for {_span(age)}"
        elif age > stale_after:
            level, text = "bad", f"no reading for {_span(age)}"
        elif age > max(0.5 * stale_after, 1.0):
            level, text = "warn", f"no reading for {age:.1f} s"
        else:
            level = "warn" if failed > 0 else "ok"
            text = "link OK" if rate is None else f"link OK, {rate:.0f} readings/s"
            if failed > 0:
                text += f", {failed} failed reading{'s' if failed > 1 else ''}"
        return {"level": level, "text": text, "readings_per_s": _round(rate)}


def _span(seconds: float) -> str:
    """``6 s``, ``12 min``, ``3 h``: how long, as an observer says it."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.0f} h"


def _round(value: float | None) -> float | None:
    return None if value is None else round(value, 1)
