"""Resolving a future so that its waiting task wakes at once, in the call that resolves it.

``asyncio.Future.set_result`` schedules the waiting task's wake-up with ``call_soon``, so a reply
that arrives in a protocol's ``data_received`` costs two turns of the event loop: the callback in
one, the task in the next, with an ``epoll_wait`` (and the loop's bookkeeping) in between. A
driver polling a device does this for every command. :func:`resolve` runs the task's wake-up
right away instead, when nothing else runs a task at that moment (a transport's callback, a
reader thread's ``call_soon_threadsafe``): one loop turn per reply (issue #14: CPU per command,
``docs/benchmarks.md``, "SynScan driver"). Called from inside a task (a memory link fed by its
peer's write) it sets the result as ``set_result`` does, which schedules the wake-up.

The futures are plain ``asyncio.Future`` objects (a task awaits one through the event loop's C
fast path; a subclass would send it through Python look-ups and a Python
``add_done_callback`` on every reply). :func:`resolve` takes the done callbacks (the awaiting
task's wake-up, with its context) off the future, sets the result, and runs them in their
contexts; a task resumed here runs as in its own turn (its context,
``asyncio.current_task()``). It reads them from ``Future._callbacks``, the attribute asyncio's
own ``repr`` of a future reads (the C and the Python future both have it);
``tests/links/test_links_read_event.py`` checks the whole mechanism on the Python in use.
Cancelling such a future (a timeout cancelling the task) wakes the task with ``call_soon``, as
any future does.
"""

from __future__ import annotations

import asyncio
import sys
from collections.abc import Callable
from contextvars import Context
from typing import Any, TypeVar

__all__ = ["fail", "resolve", "running_task"]

T = TypeVar("T")

if sys.version_info >= (3, 12):  # pragma: no cover - the CI runs 3.11
    from asyncio import current_task as running_task  # C since 3.12
else:
    running_task: Callable[[asyncio.AbstractEventLoop], asyncio.Task[Any] | None] = (
        asyncio.tasks._current_tasks.get  # type: ignore[attr-defined]
    )
    """The task running on a loop, or None. ``asyncio.current_task`` in 3.11 is a Python
    function around this dictionary's (C) ``get``: calling that directly saves a Python call on
    every reply (issue #14)."""


def resolve(future: asyncio.Future[T], result: T) -> None:
    """``future.set_result(result)``, its done callbacks (the awaiting task's wake-up) run now
    unless a task is running (then they are scheduled, as ``set_result`` schedules them)."""
    callbacks = future._callbacks  # see the module's notes
    if callbacks is None or len(callbacks) != 1 or running_task(future.get_loop()) is not None:
        _settle(future, result, None)
        return
    # One callback, the awaiting task's wake-up (the case of every reply): inline.
    ((fn, context),) = callbacks
    future.remove_done_callback(fn)
    future.set_result(result)  # nothing left to schedule
    _run(future, fn, context)


def fail(future: asyncio.Future[Any], error: BaseException) -> None:
    """``future.set_exception(error)``; the callbacks run as :func:`resolve` runs them."""
    _settle(future, None, error)


def _settle(future: asyncio.Future[Any], result: object, error: BaseException | None) -> None:
    """:func:`resolve` (``error`` None) or :func:`fail`, with any number of callbacks."""
    callbacks = future._callbacks
    if callbacks is not None and running_task(future.get_loop()) is None:
        callbacks = callbacks[:]  # a copy: a future may hand out its own list
        for fn, _context in callbacks:
            future.remove_done_callback(fn)
    else:
        callbacks = []  # none, or scheduled by set_result
    if error is None:
        future.set_result(result)
    else:
        future.set_exception(error)
    for fn, context in callbacks:
        _run(future, fn, context)


def _run(future: asyncio.Future[Any], fn: Callable[[Any], object], context: Context) -> None:
    """Run one done callback now in its context; a failure is reported as the loop reports a
    failed callback, not raised into the producer (a transport's callback)."""
    try:
        context.run(fn, future)
    except (SystemExit, KeyboardInterrupt):
        raise
    except BaseException as error:
        future.get_loop().call_exception_handler(
            {"message": f"Exception in callback {fn!r}", "exception": error, "future": future}
        )
