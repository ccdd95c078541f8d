"""What the panel shows beside the mount's state, followed across updates by the one broadcaster
(``LiveHub``) and sent as each message's ``panel``: slew progress and how a slew ended, the
health in words, the pad's directions now, the clock, and the push-to figures.

The page merges ``panel`` into the state it shows (``state.slew``, ``state.health_words``,
``state.pad``, ``state.clock``, ``state.pushto``); see docs/dashboard.md.
"""

from __future__ import annotations

import asyncio

from scopelink.mount import Mount
from scopelink.web.almanac import clock_json
from scopelink.web.health import HealthMeter
from scopelink.web.pad import pad_json
from scopelink.web.progress import SlewWatch
from scopelink.web.pushto_live import PushToTarget

__all__ = ["PanelView"]


class PanelView:
    """The panel's part of every message, for one mount."""

    def __init__(self, mount: Mount) -> None:
        self._mount = mount
        self._slew = SlewWatch()
        self._health = HealthMeter()
        self._clock: dict[str, object] | None = None
        self.pushto = PushToTarget(mount)
        """The push-to target every page shows (one telescope, one target)."""

    async def as_json(self, *, with_clock: bool) -> dict[str, object]:
        """The panel's fields now; ``with_clock`` computes the clock again (the Sun and Moon
        cost ERFA time: off the event loop, with the chart's objects), else the last one."""
        mount = self._mount
        if with_clock or self._clock is None:
            self._clock = await asyncio.to_thread(clock_json, mount.now(), mount.site)
        state = mount.state
        return {
            "slew": self._slew.update(mount, state),
            "health_words": self._health.update(mount, state),
            "pad": pad_json(mount, state),
            "clock": self._clock,
            "pushto": self.pushto.figures(state),
        }
