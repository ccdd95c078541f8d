"""Wait for a slew unless told to stop: the command line's Ctrl-C, the follower's stop."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable

from scopelink.mount.base import Mount
from scopelink.mount.types import MountState, SlewProgress

__all__ = ["slew_unless_stopped"]


async def slew_unless_stopped(
    mount: Mount,
    stop: asyncio.Event,
    timeout_s: float | None = None,
    progress: Callable[[SlewProgress], None] | None = None,
) -> MountState | None:
    """The state the slew ended in (``Mount.wait_for_slew``: its TimeoutError too), or None when
    ``stop`` was set (first, or as the slew ended: a stop asked for is a stop): then the mount
    has been told to abort."""
    slew = asyncio.create_task(mount.wait_for_slew(timeout_s, progress=progress))
    stopper = asyncio.create_task(stop.wait())
    done, _ = await asyncio.wait({slew, stopper}, return_when=asyncio.FIRST_COMPLETED)
    for task in (slew, stopper):
        if task not in done:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
    if stopper in done:
        await mount.abort()
        return None
    return slew.result()
