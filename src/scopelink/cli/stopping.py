"""Ctrl-C and SIGTERM as an event, so that a long-running command shuts down cleanly."""

from __future__ import annotations

import asyncio
import contextlib
import signal
from collections.abc import AsyncIterator

__all__ = ["until_stopped"]


@contextlib.asynccontextmanager
async def until_stopped() -> AsyncIterator[asyncio.Event]:
    """An event set by Ctrl-C or SIGTERM, so a long-running command can shut down cleanly."""
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    previous: dict[int, object] = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        try:
            loop.add_signal_handler(signum, stop.set)
        except NotImplementedError:
            # Windows event loops have no signal handlers: a plain handler wakes the loop.
            previous[signum] = signal.signal(signum, lambda *_: loop.call_soon_threadsafe(stop.set))
    try:
        yield stop
    finally:
        for signum in (signal.SIGINT, signal.SIGTERM):
            if signum in previous:
                signal.signal(signum, previous[signum])  # type: ignore[arg-type]
                continue
            with contextlib.suppress(ValueError, NotImplementedError):
                loop.remove_signal_handler(signum)
