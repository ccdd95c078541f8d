"""Simulated time: real, accelerated, or stepped by hand.

The clock keeps *elapsed simulated seconds* (a float that only ever grows, what the physics runs
on) and an *epoch* (the UTC date at elapsed 0, what astronomy runs on). Changing the speed
re-anchors the clock at the current reading, so simulated time never jumps; :meth:`set_time`
moves the epoch only, so the physics (which reads elapsed seconds) is not disturbed.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import Callable
from datetime import UTC, datetime, timedelta

__all__ = ["DEFAULT_EPOCH", "SimClock"]

DEFAULT_EPOCH = datetime(2026, 1, 1, tzinfo=UTC)
"""A fixed start date, so runs are reproducible unless asked otherwise."""


class SimClock:
    """A clock for the simulator.

    ``rate`` is simulated seconds per real second: 1 for real time, N for N times faster, 0 for
    stepped mode where time moves only through :meth:`advance`. :meth:`advance` also works while
    running (it skips ahead). ``monotonic`` is the real-time source (injectable for tests).
    """

    def __init__(
        self,
        *,
        start: datetime | None = None,
        rate: float = 1.0,
        monotonic: Callable[[], float] = time.monotonic,
    ) -> None:
        start = start if start is not None else datetime.now(UTC)
        if start.tzinfo is None:
            raise ValueError("the start epoch must carry a time zone (use UTC)")
        _check_rate(rate)
        self._monotonic = monotonic
        self._epoch = start.astimezone(UTC)
        self._rate = rate
        self._anchor_real = monotonic()
        self._anchor_elapsed = 0.0
        self._changed: asyncio.Event | None = None

    @classmethod
    def stepped(cls, start: datetime = DEFAULT_EPOCH) -> SimClock:
        """A clock that stands still until a test calls :meth:`advance`."""
        return cls(start=start, rate=0.0)

    @classmethod
    def accelerated(cls, factor: float, start: datetime = DEFAULT_EPOCH) -> SimClock:
        """A clock running ``factor`` times faster than real time."""
        return cls(start=start, rate=factor)

    # --- reading --------------------------------------------------------------------------------

    @property
    def rate(self) -> float:
        """Simulated seconds per real second (0 in stepped mode)."""
        return self._rate

    @property
    def is_stepped(self) -> bool:
        return self._rate == 0.0

    @property
    def epoch(self) -> datetime:
        """The UTC date at elapsed 0."""
        return self._epoch

    def elapsed(self) -> float:
        """Simulated seconds since the clock started."""
        return self._anchor_elapsed + (self._monotonic() - self._anchor_real) * self._rate

    def datetime_at(self, elapsed_s: float) -> datetime:
        """The UTC date at a given elapsed time (microsecond resolution, as ``datetime`` has)."""
        return self._epoch + timedelta(seconds=elapsed_s)

    def now(self) -> datetime:
        """The simulated UTC date now (aware)."""
        return self.datetime_at(self.elapsed())

    # --- changing -------------------------------------------------------------------------------

    def set_rate(self, rate: float) -> None:
        """Run at ``rate`` from now on (0 = stepped); the reading continues without a jump."""
        _check_rate(rate)
        self._reanchor()
        self._rate = rate
        self._notify()

    def advance(self, seconds: float) -> None:
        """Move simulated time forward by ``seconds`` at once; sleepers past their deadline wake."""
        if not (math.isfinite(seconds) and seconds >= 0.0):
            raise ValueError(f"can only advance by a finite, non-negative time, not {seconds}")
        self._reanchor()
        self._anchor_elapsed += seconds
        self._notify()

    def set_time(self, utc: datetime) -> None:
        """Make :meth:`now` read ``utc`` by moving the epoch; elapsed time is untouched."""
        if utc.tzinfo is None:
            raise ValueError("the time must carry a time zone (use UTC)")
        self._epoch = utc.astimezone(UTC) - timedelta(seconds=self.elapsed())

    # --- waiting --------------------------------------------------------------------------------

    async def sleep(self, sim_seconds: float) -> None:
        """Wait ``sim_seconds`` of simulated time, whatever the mode (and if it changes)."""
        await self.sleep_until(self.elapsed() + max(0.0, sim_seconds))

    async def sleep_until(self, elapsed_s: float) -> None:
        """Wait until :meth:`elapsed` reaches ``elapsed_s``."""
        while True:
            remaining = elapsed_s - self.elapsed()
            if remaining <= 0.0:
                return
            changed = self._change_event()
            timeout = None if self.is_stepped else remaining / self._rate
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(changed.wait(), timeout)

    # --- internals ------------------------------------------------------------------------------

    def _reanchor(self) -> None:
        now_real = self._monotonic()
        self._anchor_elapsed += (now_real - self._anchor_real) * self._rate
        self._anchor_real = now_real

    def _change_event(self) -> asyncio.Event:
        if self._changed is None:
            self._changed = asyncio.Event()
        return self._changed

    def _notify(self) -> None:
        # Waking every sleeper is enough: each recomputes its own deadline.
        if self._changed is not None:
            self._changed.set()
            self._changed = None


def _check_rate(rate: float) -> None:
    if not (math.isfinite(rate) and rate >= 0.0):
        raise ValueError(f"clock rate {rate} must be a finite number >= 0 (0 = stepped)")
