"""A receive buffer fed by a producer (a peer link, a reader thread, a protocol) and read by one
coroutine."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import Callable
from typing import Any, TypeVar

from scopelink.links.base import Link, LinkClosedError
from scopelink.links.prompt import fail, resolve
from scopelink.links.trace import trace_logger, trace_transfer
from scopelink.protocol.base import NEED_DATA, NeedData

E = TypeVar("E")


class InboundBuffer:
    """Bytes waiting to be read, plus an end-of-stream marker that wakes a waiting reader.

    Bytes fed before the end are still delivered; only then does ``read`` raise.
    All methods run on the event loop's thread (threads feed it via ``call_soon_threadsafe``).
    A waiting reader sleeps on a future of its own, which ``feed`` resolves (no
    ``asyncio.Event``: its extra look-ups cost CPU on every reply, issue #14); one reader at a
    time is the rule, but a second one is woken too.

    :meth:`read_event` hands what arrives to a parser instead, in the producer's call, and
    wakes its reader once, with what the parser made of the bytes.

    ``loop``: the event loop the producer runs on, when it is known for good (a TCP
    connection's); otherwise it is looked up at the first read, and again once it has closed.
    ``stamp``: keep :attr:`arrived_at` (a clock reading per chunk; only paced memory links
    need it).
    """

    __slots__ = (
        "_data",
        "_end_reason",
        "_link",
        "_loop",
        "_loop_fixed",
        "_parse",
        "_stamp",
        "_trace",
        "_waiter",
        "_waiters",
        "arrived_at",
    )

    def __init__(
        self, loop: asyncio.AbstractEventLoop | None = None, *, stamp: bool = True
    ) -> None:
        self._data = bytearray()
        self._waiters: list[asyncio.Future[None]] = []
        self._loop = loop
        self._loop_fixed = loop is not None
        self._end_reason: str | None = None
        # A read_event in progress: its future, its parser, its link (counts, trace) and
        # whether the link traces (looked up once per read: issue #14).
        self._waiter: asyncio.Future[Any] | None = None
        self._parse: Callable[[bytes], Any] = _no_parser
        self._link: Link | None = None
        self._trace = False
        self._stamp = stamp
        self.arrived_at = -math.inf
        """``time.monotonic()`` when the latest bytes arrived (the producer says, or when fed)."""

    def feed(self, data: bytes, arrived_at: float | None = None) -> None:
        """Append received bytes; ignored after the end of the stream. ``arrived_at`` is when
        they arrived if the producer knows better than now (a paced peer: when due on the line)."""
        if self._end_reason is None and data:
            if self._stamp:
                self.arrived_at = time.monotonic() if arrived_at is None else arrived_at
            waiter = self._waiter
            if waiter is not None:
                if not waiter.done():  # not cancelled: the parser takes the bytes
                    link: Link = self._link  # type: ignore[assignment]  # set with the waiter
                    link.bytes_read += len(data)  # as _parsed(), inline: every reply passes
                    if self._trace:
                        trace_transfer("<--", link.name, data)
                    event = self._parse(data)
                    if event is not NEED_DATA:
                        self._waiter = None
                        resolve(waiter, event)  # the reader runs now (last: it may read again)
                    return
                self._waiter = None
            self._data += data
            self._wake()

    def feed_end(self, reason: str) -> None:
        """Mark the end of the stream; the first reason given is the one readers see."""
        if self._end_reason is None:
            self._end_reason = reason
            waiter, self._waiter = self._waiter, None
            self._wake()
            if waiter is not None and not waiter.done():
                assert self._link is not None
                self._link._end_seen()
                fail(waiter, LinkClosedError(reason))

    def read_event(
        self, parse: Callable[[bytes], E | NeedData], link: Link, trace: bool | None = None
    ) -> asyncio.Future[E]:
        """What ``parse`` makes of the bytes buffered and then of those fed, once it is other
        than ``NEED_DATA`` (see :meth:`scopelink.links.Link.read_event`; ``link`` counts and
        traces the bytes, and is marked closed when the stream ends first). The future fails
        with LinkClosedError once the stream has ended without an event; cancelling it leaves
        later bytes buffered for the next read. Its reader wakes in the producer's call
        (:func:`scopelink.links.prompt.resolve`). ``trace``: whether the link traces
        (None: look it up)."""
        loop = self._loop
        if not self._loop_fixed and (loop is None or loop.is_closed()):
            loop = self._loop = asyncio.get_running_loop()
        waiter: asyncio.Future[E] = asyncio.Future(loop=loop)
        buffered = self._data
        if buffered:
            data = bytes(buffered)
            buffered.clear()
            event = _parsed(parse, link, data)
            if event is not NEED_DATA:
                waiter.set_result(event)  # not NEED_DATA: an E
                return waiter
        if self._end_reason is not None:
            link._end_seen()
            waiter.set_exception(LinkClosedError(self._end_reason))
            return waiter
        self._waiter, self._parse, self._link = waiter, parse, link
        self._trace = trace_logger.isEnabledFor(logging.DEBUG) if trace is None else trace
        return waiter

    async def read(self, max_bytes: int) -> bytes:
        """Wait for 1..max_bytes bytes; LinkClosedError once drained and ended."""
        while not self._data:
            if self._end_reason is not None:
                raise LinkClosedError(self._end_reason)
            loop = self._loop
            if loop is None or loop.is_closed():  # looked up once: each look-up is a system call
                loop = self._loop = asyncio.get_running_loop()
            waiter = loop.create_future()
            waiters = self._waiters
            waiters.append(waiter)
            try:
                await waiter
            finally:
                waiters.remove(waiter)
        buffered = self._data
        if len(buffered) <= max_bytes:  # the common case: take everything
            data = bytes(buffered)
            buffered.clear()
            return data
        data = bytes(buffered[:max_bytes])
        del buffered[:max_bytes]
        return data

    def _wake(self) -> None:
        for waiter in self._waiters:
            if not waiter.done():
                waiter.set_result(None)


def _no_parser(data: bytes) -> NeedData:  # pragma: no cover - never called: no waiter
    return NEED_DATA


def _parsed(parse: Callable[[bytes], E | NeedData], link: Link, data: bytes) -> E | NeedData:
    """``parse(data)``, the bytes counted and traced as :meth:`Link.read` does."""
    link.bytes_read += len(data)
    if trace_logger.isEnabledFor(logging.DEBUG):
        trace_transfer("<--", link.name, data)
    return parse(data)
