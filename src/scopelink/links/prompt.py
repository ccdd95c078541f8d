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
"""

from __future__ import annotations

import asyncio
import contextvars
from collections.abc import Callable
from typing import Any, TypeVar

T = TypeVar("T")

_Callback = tuple[Callable[[Any], object], contextvars.Context | None]


class PromptFuture(asyncio.Future[T]):
    """An ``asyncio.Future`` whose :meth:`resolve` wakes its awaiting task in the same call.

    Made as ``PromptFuture(loop=loop)``; no ``__init__`` of its own (one is a Python call per
    future: every reply makes one)."""

    _prompt_callbacks: list[_Callback] | None = None
    """The done callbacks held back for :meth:`resolve` (None until the first is added; a
    class default rather than a slot, which would need an ``__init__`` to set it)."""

    def add_done_callback(
        self, fn: Callable[[Any], object], *, context: contextvars.Context | None = None
    ) -> None:
        if self.done():
            super().add_done_callback(fn, context=context)  # scheduled at once, as usual
            return
        callbacks = self._prompt_callbacks
        if callbacks is None:
            self._prompt_callbacks = [(fn, context)]
        else:
            callbacks.append((fn, context))

    def remove_done_callback(self, fn: Callable[[Any], object]) -> int:
        callbacks = self._held()
        kept = [callback for callback in callbacks if callback[0] != fn]
        self._prompt_callbacks = kept
        return len(callbacks) - len(kept) + super().remove_done_callback(fn)

    def resolve(self, result: T) -> None:
        """``set_result(result)``, then run the done callbacks (the task's wake-up) now, unless
        a task is running (then they are scheduled, as ``set_result`` would)."""
        self.set_result(result)
        self._run_callbacks(asyncio.current_task(self.get_loop()) is None)

    def fail(self, error: BaseException) -> None:
        """``set_exception(error)``; the callbacks run as :meth:`resolve` runs them."""
        self.set_exception(error)
        self._run_callbacks(asyncio.current_task(self.get_loop()) is None)

    def cancel(self, msg: Any | None = None) -> bool:
        if not super().cancel(msg=msg):
            return False
        self._run_callbacks(False)
        return True

    def _held(self) -> list[_Callback]:
        return self._prompt_callbacks or []

    def _run_callbacks(self, now: bool) -> None:
        callbacks = self._held()
        self._prompt_callbacks = []
        loop = self.get_loop()
        for fn, context in callbacks:
            if not now:
                loop.call_soon(fn, self, context=context)
                continue
            try:
                if context is None:
                    fn(self)
                else:
                    context.run(fn, self)
            except (SystemExit, KeyboardInterrupt):
                raise
            except BaseException as error:  # as the loop reports a failed callback
                loop.call_exception_handler(
                    {"message": f"Exception in callback {fn!r}", "exception": error, "future": self}
                )
