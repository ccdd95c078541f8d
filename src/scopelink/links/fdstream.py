"""Non-blocking reads and writes on a file descriptor (tty, pty master, socket) on the event loop.

Waits for readiness with ``loop.add_reader``/``add_writer`` and then does one non-blocking
``os.read``/``os.write``, so the event loop never blocks and a cancelled read loses nothing:
unread bytes stay in the kernel.
"""

from __future__ import annotations

import asyncio
import errno
import os
import select
from collections.abc import Callable

from scopelink.links.base import LinkClosedError

# errno values meaning the device or peer went away rather than "try again".
_GONE_ERRNOS = frozenset(
    {errno.EIO, errno.ENXIO, errno.ENODEV, errno.EPIPE, errno.ECONNRESET, errno.ENOTCONN}
)


class FdStream:
    """Async byte I/O on a descriptor that the caller owns and closes after ``close``."""

    def __init__(self, fd: int, name: str) -> None:
        os.set_blocking(fd, False)
        self._fd = fd
        # A tty in pyserial's raw mode (VMIN=0) answers "no data" with an empty read, not EAGAIN.
        self._empty_read_may_mean_no_data = os.isatty(fd)
        self._name = name
        self._loop = asyncio.get_running_loop()
        self._waiters: set[asyncio.Future[None]] = set()
        self._read_waiters: list[asyncio.Future[None]] = []
        self._watching = False
        """Registered with the loop for readability: kept from one read to the next."""
        self._closed = False

    async def read(self, max_bytes: int) -> bytes:
        """Wait for 1..max_bytes bytes; LinkClosedError on EOF, hang-up or close."""
        waited = False
        empty_reads = 0
        while True:
            self._raise_if_closed()
            try:
                data = os.read(self._fd, max_bytes)
            except BlockingIOError:
                data = None
            except OSError as exc:
                raise self._gone_error(exc) from exc
            if data:
                return data
            if data is None or (self._empty_read_may_mean_no_data and not waited):
                await self._wait_readable()
                waited = True
                continue
            empty_reads += 1
            if (
                self._empty_read_may_mean_no_data
                and empty_reads <= _EMPTY_READS_BEFORE_GONE
                and not _hung_up(self._fd)
            ):
                # A readiness report gone stale (the watch outlives each read, so a report
                # queued before the last read took its bytes can wake the next one), or bytes
                # that arrived just after the empty read: read again, waiting if need be.
                # Only the hang-up flag ends the stream: "readable" alone was once the reply
                # landing between the two calls, taken for a hang-up.
                await self._wait_readable()
                continue
            # Empty and hung up, readable and empty again and again (no tty does that with
            # data or without a hang-up: not worth spinning on), or not a tty.
            raise LinkClosedError(f"{self._name}: end of stream")

    async def write(self, data: bytes) -> None:
        """Write all of ``data``, waiting for buffer space as needed."""
        view = memoryview(data)
        while view:
            self._raise_if_closed()
            try:
                written = os.write(self._fd, view)
            except BlockingIOError:
                await self._wait_ready(self._loop.add_writer, self._loop.remove_writer)
                continue
            except OSError as exc:
                raise self._gone_error(exc) from exc
            view = view[written:]

    def close(self) -> None:
        """Stop using the descriptor; pending reads and writes raise LinkClosedError."""
        self._closed = True
        # Unregister now: the owner closes the fd next and its number may be reused at once.
        self._watching = False
        self._loop.remove_reader(self._fd)
        self._loop.remove_writer(self._fd)
        for waiter in self._waiters:
            if not waiter.done():
                waiter.set_exception(LinkClosedError(f"{self._name} is closed"))

    async def _wait_readable(self) -> None:
        """Wait until the descriptor is readable. The loop keeps watching it after the wait
        (a driver reads again right after its next command): registering and unregistering on
        every read cost two ``epoll_ctl`` calls and the selector's bookkeeping per reply
        (issue #14). Readable while nobody reads, it is unregistered (:meth:`_on_readable`)."""
        waiter: asyncio.Future[None] = self._loop.create_future()
        self._read_waiters.append(waiter)
        self._waiters.add(waiter)
        if not self._watching:
            self._loop.add_reader(self._fd, self._on_readable)
            self._watching = True
        try:
            await waiter
        finally:
            self._waiters.discard(waiter)
            if waiter in self._read_waiters:  # cancelled or closed before the fd was readable
                self._read_waiters.remove(waiter)

    def _on_readable(self) -> None:
        waiters = self._read_waiters
        if not waiters:
            # Nobody reads now: stop watching (level-triggered, it would fire every loop turn
            # until someone reads); the next read registers again.
            self._watching = False
            self._loop.remove_reader(self._fd)
            return
        self._read_waiters = []
        for waiter in waiters:
            if not waiter.done():
                waiter.set_result(None)

    async def _wait_ready(
        self,
        add: Callable[..., object],
        remove: Callable[[int], bool],
    ) -> None:
        waiter: asyncio.Future[None] = self._loop.create_future()
        add(self._fd, _resolve, waiter)
        self._waiters.add(waiter)
        try:
            await waiter
        finally:
            self._waiters.discard(waiter)
            if not self._closed:
                remove(self._fd)

    def _raise_if_closed(self) -> None:
        if self._closed:
            raise LinkClosedError(f"{self._name} is closed")

    def _gone_error(self, exc: OSError) -> LinkClosedError:
        if exc.errno in _GONE_ERRNOS:
            return LinkClosedError(f"{self._name}: device or peer gone ({exc.strerror})")
        return LinkClosedError(f"{self._name}: I/O error ({exc})")


_GONE_EVENTS = select.POLLHUP | select.POLLERR | select.POLLNVAL

_EMPTY_READS_BEFORE_GONE = 100
"""Empty reads of a tty that says it is readable, in a row within one read, before the stream
counts as ended although no hang-up is reported (a stale report or a reply racing the check
takes one or two)."""


def _hung_up(fd: int) -> bool:
    """Whether ``fd`` reports a hang-up or an error right now, without waiting (``poll``
    reports these whatever events are asked for)."""
    poller = select.poll()  # not select.select: any descriptor number, even above 1023
    poller.register(fd, select.POLLIN)
    return any(events & _GONE_EVENTS for _, events in poller.poll(0))


def _resolve(waiter: asyncio.Future[None]) -> None:
    if not waiter.done():
        waiter.set_result(None)
