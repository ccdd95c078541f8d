"""What the panel shows beside the mount's state, followed across updates by the one broadcaster
(``LiveHub``) and sent as each message's ``panel``: slew progress and how a slew ended, the
health in words, the pad's directions now, the clock, and the push-to figures.

The page merges ``panel`` into the state it shows (``state.slew``, ``state.health_words``,
``state.pad``, ``state.clock``, ``state.pushto``); see docs/dashboard.md.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable

from scopelink.mount import Mount
from scopelink.web.almanac import clock_json
from scopelink.web.health import HealthMeter
from scopelink.web.pad import pad_json
from scopelink.web.progress import SlewWatch
from scopelink.web.pushto_live import PushToTarget

__all__ = ["PanelView"]

logger = logging.getLogger(__name__)


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
        cost ERFA time: off the event loop, with the chart's objects), else the last one.
        A part that fails is left out (logged): the page, and its STOP, must keep updating."""
        mount = self._mount
        if with_clock or self._clock is None:
            try:
                self._clock = await asyncio.to_thread(clock_json, mount.now(), mount.site)
            except Exception:
                logger.exception("cannot compute the dashboard's clock")
        state = mount.state
        parts: dict[str, Callable[[], object]] = {
            "slew": lambda: self._slew.update(mount, state),
            "health_words": lambda: self._health.update(mount, state),
            "pad": lambda: pad_json(mount, state),
            "pushto": lambda: self.pushto.figures(state),
        }
        panel: dict[str, object] = {"clock": self._clock}
        for name, part in parts.items():
            try:
                panel[name] = part()
            except Exception:
                logger.exception("cannot compute the dashboard's %s", name)
                panel[name] = None
        return panel
