"""Serial ports through pyserial: device paths (``/dev/ttyUSB0``, ``COM3``) and pyserial URLs
(``socket://``, ``rfc2217://``, ``loop://``).

A port with a real file descriptor whose bytes are the line's bytes (a POSIX tty, ``socket://``)
is driven from the event loop; any other (``rfc2217://``, ``loop://``, Windows ports) gets a
reader thread. Either way the event loop never blocks.
"""

from __future__ import annotations

import asyncio
import errno
import io
import threading
from collections.abc import Awaitable, Callable
from typing import TypeVar

import serial

from scopelink.links.base import (
    DEFAULT_BAUDRATE,
    Link,
    LinkClosedError,
    LinkOpenError,
    LinkSpecError,
)
from scopelink.links.fdstream import FdStream
from scopelink.links.inbound import E, InboundBuffer
from scopelink.protocol.base import NeedData

# How often a reader thread looks up from a blocking read to see whether it should stop.
_THREAD_POLL_SECONDS = 0.05

_T = TypeVar("_T")

_LIST_PORTS_HINT = "is it plugged in? List ports with: python -m serial.tools.list_ports"
_DIALOUT_HINT = (
    "add yourself to the dialout group (sudo usermod -aG dialout $USER), then log in again"
)
_BUSY_HINT = "another program has it open (another scopelink? ModemManager? gpsd?)"

NO_SUCH_DEVICE = "no such device"
"""The ``reason`` of a :class:`LinkOpenError` for a port that does not exist (ENOENT)."""
PERMISSION_DENIED = "permission denied"
"""... for a port this user may not open (EACCES, EPERM)."""
PORT_BUSY = "port busy"
"""... for a port another program holds (EBUSY, or its exclusive lock)."""


class SerialLink(Link):
    """An open pyserial port. ``port`` gives the pyserial object (line settings, DTR/RTS)."""

    def __init__(self, port: serial.Serial, name: str) -> None:
        super().__init__(name)
        self.port = port


class _DescriptorSerialLink(SerialLink):
    def __init__(self, port: serial.Serial, name: str, fd: int) -> None:
        super().__init__(port, name)
        self._stream = FdStream(fd, name)

    async def _read_some(self, max_bytes: int) -> bytes:
        return await self._stream.read(max_bytes)

    async def _write_all(self, data: bytes) -> None:
        await self._stream.write(data)

    async def _close_transport(self) -> None:
        self._stream.close()
        # Off the loop: pyserial's socket:// close sleeps 0.3 s "to give the server some time".
        await asyncio.to_thread(self.port.close)


class _ThreadedSerialLink(SerialLink):
    def __init__(self, port: serial.Serial, name: str) -> None:
        super().__init__(port, name)
        self._loop = asyncio.get_running_loop()
        self._inbound = InboundBuffer()
        self._write_lock = asyncio.Lock()
        self._stopping = threading.Event()
        self._reader = threading.Thread(target=self._pump, name=f"read {name}", daemon=True)
        self._reader.start()

    def _pump(self) -> None:
        """Reader thread: move bytes from the port to the inbound buffer until stopped."""
        try:
            while not self._stopping.is_set():
                data = self.port.read(max(1, self.port.in_waiting))
                if data:
                    self._post(self._inbound.feed, data)
        except (serial.SerialException, OSError) as exc:
            if not self._stopping.is_set():
                self._post(self._inbound.feed_end, f"{self.name}: {exc}")

    def _post(self, callback: Callable[[_T], None], argument: _T) -> None:
        try:
            self._loop.call_soon_threadsafe(callback, argument)
        except RuntimeError:  # the event loop is closed: nobody will ever read again
            self._stopping.set()

    async def _read_some(self, max_bytes: int) -> bytes:
        return await self._inbound.read(max_bytes)

    def _read_event(self, parse: Callable[[bytes], E | NeedData]) -> Awaitable[E]:
        return self._inbound.read_event(parse, self)

    async def _write_all(self, data: bytes) -> None:
        async with self._write_lock:
            try:
                await asyncio.to_thread(self.port.write, data)
            except (serial.SerialException, OSError) as exc:
                raise LinkClosedError(f"{self.name}: {exc}") from exc

    async def _close_transport(self) -> None:
        self._inbound.feed_end(f"{self.name} is closed")
        if self._stopping.is_set():
            return
        self._stopping.set()
        await asyncio.to_thread(self._reader.join)
        await asyncio.to_thread(self.port.close)


async def open_serial(
    url_or_path: str,
    baudrate: int = DEFAULT_BAUDRATE,
    *,
    bytesize: int = 8,
    parity: str = "N",
    stopbits: float = 1,
    exclusive: bool = True,
) -> SerialLink:
    """Open a serial port or pyserial URL, raw, with the given line settings (default 9600 8N1).

    ``exclusive`` takes an advisory lock on local devices so two programs cannot share a port.
    Raises LinkOpenError (naming the port, with a hint) or LinkSpecError for bad arguments.
    """
    try:
        port = serial.serial_for_url(
            url_or_path,
            baudrate=baudrate,
            bytesize=bytesize,
            parity=parity,
            stopbits=stopbits,
            timeout=_THREAD_POLL_SECONDS,
            do_not_open=True,
        )
        if "://" not in url_or_path:
            port.exclusive = exclusive
    except ValueError as exc:
        raise LinkSpecError(f"bad serial port settings for {url_or_path!r}: {exc}") from exc
    try:
        await asyncio.to_thread(port.open)
    except (serial.SerialException, OSError) as exc:
        raise _open_error(url_or_path, exc) from exc
    except ValueError as exc:  # pyserial checks some URL parameters only when opening
        raise LinkSpecError(f"bad serial port URL {url_or_path!r}: {exc}") from exc
    try:
        fd = port.fileno()
    except (AttributeError, OSError, io.UnsupportedOperation):
        return _ThreadedSerialLink(port, url_or_path)
    return _DescriptorSerialLink(port, url_or_path, fd)


def _open_error(port: str, exc: BaseException) -> LinkOpenError:
    code = _errno_of(exc)
    if code == errno.ENOENT:
        return LinkOpenError(port, NO_SUCH_DEVICE, _LIST_PORTS_HINT)
    if code in (errno.EACCES, errno.EPERM):
        return LinkOpenError(port, PERMISSION_DENIED, _DIALOUT_HINT)
    if code in (errno.EBUSY, errno.EAGAIN) or "exclusively lock" in str(exc):
        return LinkOpenError(port, PORT_BUSY, _BUSY_HINT)
    if code == errno.ECONNREFUSED:
        return LinkOpenError(port, "connection refused", "is the serial-to-network bridge running?")
    return LinkOpenError(port, str(exc))


def _errno_of(exc: BaseException | None) -> int | None:
    """pyserial wraps OSErrors, sometimes keeping the errno, sometimes only as the cause."""
    while exc is not None:
        if isinstance(exc, OSError) and exc.errno is not None:
            return exc.errno
        exc = exc.__cause__ or exc.__context__
    return None
