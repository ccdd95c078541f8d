"""Ctrl-C, SIGTERM and a lost terminal (SIGHUP) as an event, so that a long-running command
shuts down cleanly: a ``move`` whose SSH session drops stops the axis it moved."""

from __future__ import annotations

import asyncio
import contextlib
import signal
from collections.abc import AsyncIterator

__all__ = ["until_stopped"]


@contextlib.asynccontextmanager
async def until_stopped() -> AsyncIterator[asyncio.Event]:
    """An event set by Ctrl-C, SIGTERM or SIGHUP, so a long-running command can shut down
    cleanly. SIGHUP is left alone where it is ignored (``nohup scopelink serve``)."""
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    previous: dict[int, object] = {}
    signals = _signals()
    for signum in signals:
        try:
            loop.add_signal_handler(signum, stop.set)
        except NotImplementedError:
            # Windows event loops have no signal handlers: a plain handler wakes the loop.
            previous[signum] = signal.signal(signum, lambda *_: loop.call_soon_threadsafe(stop.set))
    try:
        yield stop
    finally:
        for signum in signals:
            if signum in previous:
                signal.signal(signum, previous[signum])  # type: ignore[arg-type]
                continue
            with contextlib.suppress(ValueError, NotImplementedError):
                loop.remove_signal_handler(signum)


def _signals() -> tuple[signal.Signals, ...]:
    hangup = getattr(signal, "SIGHUP", None)  # not on Windows
    if hangup is None or signal.getsignal(hangup) is signal.SIG_IGN:
        return (signal.SIGINT, signal.SIGTERM)
    return (signal.SIGINT, signal.SIGTERM, hangup)
