"""Pseudo-terminals: a device emulator owns the master side; a client program opens ``path``.

We keep our own descriptor of the slave open, so a client closing the port (and opening it
again later) never ends our stream, and its line settings stay readable: an emulator can garble
input when the client set the wrong baud rate or framing, as a real device would.
"""

from __future__ import annotations

import contextlib
import os
import termios
import tty
from dataclasses import dataclass
from pathlib import Path

from scopelink.links.base import Link, LinkOpenError
from scopelink.links.fdstream import FdStream

_SPEED_CONSTANTS = {
    getattr(termios, name): int(name[1:])
    for name in dir(termios)
    if name.startswith("B") and name[1:].isdigit()
}
_DATA_BITS = {termios.CS5: 5, termios.CS6: 6, termios.CS7: 7, termios.CS8: 8}
_CFLAG = 2
_ISPEED, _OSPEED = 4, 5


@dataclass(frozen=True, slots=True)
class LineSettings:
    """Framing a client set on a tty: what a UART at the other end would need to match."""

    baudrate: int | None  # None for a non-standard rate set with BOTHER
    data_bits: int
    parity: str  # "N", "E" or "O"
    stop_bits: int

    @property
    def bits_per_byte(self) -> int:
        """Bits on the wire per byte: start bit, data, parity, stop bits (8N2 → 11)."""
        return 1 + self.data_bits + (self.parity != "N") + self.stop_bits

    def __str__(self) -> str:
        return f"{self.baudrate or '?'} {self.data_bits}{self.parity}{self.stop_bits}"


def read_line_settings(fd: int) -> LineSettings:
    """The line settings of the tty behind ``fd``."""
    attributes = termios.tcgetattr(fd)
    cflag = attributes[_CFLAG]
    parity = "N"
    if cflag & termios.PARENB:
        parity = "O" if cflag & termios.PARODD else "E"
    return LineSettings(
        baudrate=_SPEED_CONSTANTS.get(attributes[_OSPEED]),
        data_bits=_DATA_BITS[cflag & termios.CSIZE],
        parity=parity,
        stop_bits=2 if cflag & termios.CSTOPB else 1,
    )


def _set_raw_9600_8n1(fd: int) -> None:
    tty.setraw(fd)
    attributes = termios.tcgetattr(fd)
    attributes[_CFLAG] &= ~(termios.CSTOPB | termios.PARENB)
    attributes[_CFLAG] |= termios.CLOCAL | termios.CREAD
    attributes[_ISPEED] = attributes[_OSPEED] = termios.B9600
    termios.tcsetattr(fd, termios.TCSANOW, attributes)


class PtyLink(Link):
    """The master side of a pseudo-terminal; clients open :attr:`path` like a serial port."""

    def __init__(self, master_fd: int, slave_fd: int, symlink: Path | None) -> None:
        self.device_path = os.ttyname(slave_fd)
        self.symlink = symlink
        name = f"pty {symlink} -> {self.device_path}" if symlink else f"pty {self.device_path}"
        super().__init__(name)
        self._master_fd = master_fd
        self._slave_fd = slave_fd
        self._stream = FdStream(master_fd, name)

    @property
    def path(self) -> str:
        """What a client opens: the stable symlink if one was asked for, else the slave device."""
        return str(self.symlink) if self.symlink else self.device_path

    def line_settings(self) -> LineSettings:
        """The client's current line settings (raw 9600 8N1 until a client changes them)."""
        return read_line_settings(self._slave_fd)

    async def _read_some(self, max_bytes: int) -> bytes:
        return await self._stream.read(max_bytes)

    async def _write_all(self, data: bytes) -> None:
        await self._stream.write(data)

    async def _close_transport(self) -> None:
        if self._master_fd < 0:
            return
        self._stream.close()
        os.close(self._master_fd)
        os.close(self._slave_fd)
        self._master_fd = self._slave_fd = -1
        if self.symlink is not None and _points_to(self.symlink, self.device_path):
            with contextlib.suppress(FileNotFoundError):
                self.symlink.unlink()


async def open_pty(symlink: str | os.PathLike[str] | None = None) -> PtyLink:
    """Create a pseudo-terminal in raw 9600 8N1 mode and return its master side.

    With ``symlink``, also make that path point at the slave device (replacing a stale symlink,
    never a regular file) and remove it on close, so clients can be configured once.
    """
    master_fd, slave_fd = os.openpty()
    try:
        _set_raw_9600_8n1(slave_fd)
        link_path = None if symlink is None else Path(symlink)
        if link_path is not None:
            _make_symlink(link_path, os.ttyname(slave_fd))
    except BaseException:
        os.close(master_fd)
        os.close(slave_fd)
        raise
    return PtyLink(master_fd, slave_fd, link_path)


def _make_symlink(link_path: Path, target: str) -> None:
    if link_path.is_symlink():
        link_path.unlink()
    elif link_path.exists():
        hint = "choose another path; only a symlink left by an earlier run is replaced"
        raise LinkOpenError(f"pty {link_path}", "the path exists and is not a symlink", hint)
    try:
        link_path.symlink_to(target)
    except OSError as exc:
        raise LinkOpenError(f"pty {link_path}", exc.strerror or str(exc)) from exc


def _points_to(link_path: Path, target: str) -> bool:
    try:
        return os.readlink(link_path) == target
    except OSError:
        return False
