"""A future that wakes its waiting task at once, in the call that resolves it.

``asyncio.Future.set_result`` schedules the waiting task's wake-up with ``call_soon``, so a reply
that arrives in a protocol's ``data_received`` costs two turns of the event loop: the callback in
one, the task in the next, with an ``epoll_wait`` (and the loop's bookkeeping) in between. A
driver polling a device does this for every command. :class:`PromptFuture.resolve` runs the
task's wake-up right away instead, when nothing else runs a task at that moment (a transport's
callback, a reader thread's ``call_soon_threadsafe``): one loop turn per reply (issue #14: CPU
per command, ``docs/benchmarks.md``, "SynScan driver"). Called from inside a task (a memory link
fed by its peer's write) it schedules the wake-up as ``set_result`` does.

It relies on the future protocol a task follows with any future-like object that is not exactly
``asyncio.Future`` (it registers its wake-up with :meth:`add_done_callback`, with its context),
which every CPython since 3.4 keeps; a task resumed here runs as in its own turn (its context,
``asyncio.current_task()``). Cancelling it (a timeout cancelling the task) wakes the task with
``call_soon``, as any future does.

Only the first callback (the awaiting task's wake-up) is held back and run by :meth:`resolve`;
later ones are registered as usual and scheduled when the result is set. Every other way of
finishing the future (``set_result``, ``set_exception``, ``cancel``) schedules the held one too,
so it behaves as any future; only :meth:`resolve` and :meth:`fail` run it at once. The hot path
is one Python override (:meth:`add_done_callback`) and :meth:`resolve` (issue #14 part 2).
"""

from __future__ import annotations

import asyncio
import contextvars
import sys
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["PromptFuture", "running_task"]

T = TypeVar("T")

_Callback = tuple[Callable[[Any], object], contextvars.Context]

if sys.version_info >= (3, 12):  # pragma: no cover - the CI runs 3.11
    from asyncio import current_task as running_task  # C since 3.12
else:
    running_task: Callable[[asyncio.AbstractEventLoop], asyncio.Task[Any] | None] = (
        asyncio.tasks._current_tasks.get  # type: ignore[attr-defined]
    )
    """The task running on a loop, or None. ``asyncio.current_task`` in 3.11 is a Python
    function around this dictionary's (C) ``get``: calling that directly saves a Python call on
    every reply (issue #14)."""

_set_result = asyncio.Future.set_result
_set_exception = asyncio.Future.set_exception


class PromptFuture(asyncio.Future[T]):
    """An ``asyncio.Future`` whose :meth:`resolve` wakes its awaiting task in the same call.

    Made as ``PromptFuture(loop=loop)``; no ``__init__`` of its own (one is a Python call per
    future: every reply makes one)."""

    _held: _Callback | None = None
    """The first done callback, held back for :meth:`resolve` (a class default rather than a
    slot, which would need an ``__init__`` to set it)."""

    def add_done_callback(
        self, fn: Callable[[Any], object], *, context: contextvars.Context | None = None
    ) -> None:
        if self._held is None and not self.done():
            # In the context given, else a copy of the current one, as asyncio does.
            self._held = (fn, contextvars.copy_context() if context is None else context)
        else:
            super().add_done_callback(fn, context=context)  # scheduled when done, as usual

    def remove_done_callback(self, fn: Callable[[Any], object]) -> int:
        held = self._held
        removed = 0
        if held is not None and held[0] == fn:
            self._held = None
            removed = 1
        return removed + super().remove_done_callback(fn)

    def resolve(self, result: T) -> None:
        """``set_result(result)``, then run the held callback (the task's wake-up) now, unless
        a task is running (then it is scheduled, as ``set_result`` would)."""
        _set_result(self, result)
        held = self._held
        if held is not None:
            self._held = None
            fn, context = held
            if running_task(self.get_loop()) is not None:
                self._run(held, False)
                return
            try:  # _run's, inline: every reply passes here (issue #14)
                context.run(fn, self)
            except (SystemExit, KeyboardInterrupt):
                raise
            except BaseException as error:
                self._report(fn, error)

    def fail(self, error: BaseException) -> None:
        """``set_exception(error)``; the held callback runs as :meth:`resolve` runs it."""
        _set_exception(self, error)
        held = self._held
        if held is not None:
            self._held = None
            self._run(held, running_task(self.get_loop()) is None)

    def set_result(self, result: T) -> None:
        _set_result(self, result)
        self._schedule_held()

    def set_exception(self, exception: type | BaseException) -> None:
        _set_exception(self, exception)
        self._schedule_held()

    def cancel(self, msg: Any | None = None) -> bool:
        if not super().cancel(msg=msg):
            return False
        self._schedule_held()
        return True

    def _schedule_held(self) -> None:
        held = self._held
        if held is not None:
            self._held = None
            self._run(held, False)

    def _run(self, callback: _Callback, now: bool) -> None:
        fn, context = callback
        if not now:
            self.get_loop().call_soon(fn, self, context=context)
            return
        try:
            context.run(fn, self)
        except (SystemExit, KeyboardInterrupt):
            raise
        except BaseException as error:
            self._report(fn, error)

    def _report(self, fn: Callable[[Any], object], error: BaseException) -> None:
        """As the loop reports a failed callback."""
        self.get_loop().call_exception_handler(
            {"message": f"Exception in callback {fn!r}", "exception": error, "future": self}
        )
