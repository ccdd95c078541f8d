"""A Sky Commander sync, as both drivers do it: ``L99`` (the object) then ``N`` (realign), and
the position read back, since ``N`` has no reply. Realigning can be repeated, so a lost ``N`` (the
Sky Tracker's port is unbuffered) gets a second try, then :class:`DeviceError`."""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable

from scopelink.astro import angular_separation_deg
from scopelink.mount import DeviceError
from scopelink.protocol.skytracker import Acknowledge, Reply

__all__ = ["SYNC_TOLERANCE_DEG", "realign_on"]

logger = logging.getLogger(__name__)

SYNC_TOLERANCE_DEG = 0.05
"""After a sync the position read back must lie this close to the synced one (3-decimal
coordinates both ways, and the sky's drift during the read)."""


async def realign_on(
    ra_j2000_hours: float,
    dec_j2000_deg: float,
    load_and_realign: Callable[[], Awaitable[Reply | None]],
    read_back: Callable[[], Awaitable[tuple[float, float]]],
) -> None:
    """``load_and_realign()`` sends ``L99`` and ``N`` and returns the reply to ``L99``;
    ``read_back()`` reads the position (J2000 RA hours, Dec degrees) afterwards."""
    off_by = 0.0
    for _ in range(2):
        load = await load_and_realign()
        if not isinstance(load, Acknowledge):
            raise DeviceError(f"the Sky Commander did not acknowledge the object: {load}")
        ra, dec = await read_back()
        off_by = angular_separation_deg(ra * 15.0, dec, ra_j2000_hours * 15.0, dec_j2000_deg)
        if off_by <= SYNC_TOLERANCE_DEG:
            return
        logger.info("realign did not take (%.3f° off): once more", off_by)
    raise DeviceError(
        f"the Sky Commander did not realign: it reads {off_by:.3f}° from the synced "
        "position after 'N', twice (is 'N' lost on the line?)"
    )
