"""Bounded computations for the dashboard's requests: CPU-heavy answers (an object's almanac,
~0.1 s each) run one at a time on the dashboard's own thread, resting as long as each took, with a
few waiting; any more are answered ``429 Busy`` at once (``docs/dashboard.md``, "Information"
and "Security").

Without this a client within the access policy's request rate (16 connections asking
``/api/object`` back to back) kept the default executor's threads busy and took the event loop's
share of the CPU from the mount's poller (42 polls/s fell to 7: ``bench/web_object_flood.py``),
and delayed every other ``asyncio.to_thread`` of the process by more than a second.
"""

from __future__ import annotations

import asyncio
import functools
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Final, TypeVar

from aiohttp import web

__all__ = [
    "OBJECT_INFO_AT_ONCE",
    "REST_PER_BUSY",
    "BusyError",
    "Computations",
    "busy_response",
]

OBJECT_INFO_AT_ONCE: Final = 4
"""Requests for an object's information in hand at once (one computed, the others waiting)."""
REST_PER_BUSY: Final = 1.0
"""After each computation the thread rests this many times as long as it worked, so back to back
requests take at most half of one core's time (and of the interpreter's lock) from the rest."""

_T = TypeVar("_T")


class BusyError(Exception):
    """Too many heavy requests in hand: the client is told to come back."""


class Computations:
    """One thread for a dashboard's heavy answers and a bound on those in hand."""

    def __init__(self, at_once: int = OBJECT_INFO_AT_ONCE) -> None:
        self._at_once = at_once
        self._in_hand = 0
        self._turn = asyncio.Lock()
        self._executor: ThreadPoolExecutor | None = None

    async def run(self, function: Callable[..., _T], *args: object) -> _T:
        """``function(*args)`` on the dashboard's thread; :class:`BusyError` when full."""
        if self._in_hand >= self._at_once:
            raise BusyError("the dashboard is busy with other requests for object information")
        if self._executor is None:
            self._executor = ThreadPoolExecutor(1, thread_name_prefix="scopelink-dashboard")
        self._in_hand += 1
        try:
            async with self._turn:
                loop = asyncio.get_running_loop()
                started = loop.time()
                try:
                    return await loop.run_in_executor(
                        self._executor, functools.partial(function, *args)
                    )
                finally:
                    await asyncio.sleep((loop.time() - started) * REST_PER_BUSY)
        finally:
            self._in_hand -= 1

    async def close(self, app: web.Application | None = None) -> None:
        """Let the thread go (an aiohttp ``on_cleanup`` handler)."""
        executor, self._executor = self._executor, None
        if executor is not None:
            executor.shutdown(wait=False, cancel_futures=True)


def busy_response(error: BusyError) -> web.Response:
    """``429`` with ``Retry-After: 1``, in the API's error form."""
    return web.json_response(
        {"error": f"{error}: try again in a second", "kind": "Busy"},
        status=429,
        headers={"Retry-After": "1"},
    )
