"""What an emulator received: every chunk its device read, with the simulated time it came.

:func:`record_reads` taps a served link where the device reads it, so the link stays exactly what
the device would have been given (a pty keeps its line settings, a TCP link its pacing): nothing
is wrapped, the link's own read hook is observed.
"""

from __future__ import annotations

import threading
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

from scopelink.links import Link
from scopelink.protocol.synscan import NEED_DATA, AnyCommand, CommandParser, ParsedCommand

__all__ = ["CommandLog", "Received", "record_reads"]


@dataclass(frozen=True, slots=True)
class Received:
    """One chunk the device read: ``elapsed_s`` simulated seconds after start, on ``link``."""

    elapsed_s: float
    link: str
    data: bytes


class CommandLog:
    """Every chunk an emulator read, in order; safe to read from any thread."""

    def __init__(self, elapsed: Callable[[], float]) -> None:
        self._elapsed = elapsed
        self._chunks: list[Received] = []
        self._lock = threading.Lock()

    def add(self, link: str, data: bytes) -> None:
        with self._lock:
            self._chunks.append(Received(self._elapsed(), link, data))

    @property
    def chunks(self) -> list[Received]:
        """A copy of what was read so far, chunk by chunk."""
        with self._lock:
            return list(self._chunks)

    @property
    def received(self) -> bytes:
        """Every byte read so far, from every client, in the order read."""
        return b"".join(chunk.data for chunk in self.chunks)

    def synscan_commands(self) -> list[AnyCommand]:
        """The SynScan commands in :attr:`received`, framed as the hand control frames them
        (each client's stream on its own; unknown bytes and malformed frames left out)."""
        streams: dict[str, CommandParser] = {}
        found: list[AnyCommand] = []
        for chunk in self.chunks:
            parser = streams.setdefault(chunk.link, CommandParser())
            parser.receive_data(chunk.data)
            while (frame := parser.next_frame()) is not NEED_DATA:
                if isinstance(frame, ParsedCommand):  # else an error event: skipped, read on
                    found.append(frame.command)
        return found

    def clear(self) -> None:
        with self._lock:
            self._chunks.clear()


def record_reads(link: Link, log: CommandLog) -> None:
    """Log every chunk read from ``link`` (by the device, through any wrapper) into ``log``."""
    read_some: Callable[[int], Awaitable[bytes]] = link._read_some

    async def recorded(max_bytes: int) -> bytes:
        data = await read_some(max_bytes)
        log.add(link.name, data)
        return data

    link._read_some = recorded  # type: ignore[method-assign]
