"""Two in-memory links joined back to back: what one writes, the other reads."""

from __future__ import annotations

from collections.abc import Awaitable, Callable

from scopelink.links.base import Link, LinkClosedError
from scopelink.links.inbound import E, InboundBuffer
from scopelink.protocol.base import NeedData


class MemoryLink(Link):
    """One end of a :func:`memory_pair`. Writes never block (the buffer is unbounded)."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self._inbound = InboundBuffer()
        self._peer: MemoryLink | None = None

    async def _read_some(self, max_bytes: int) -> bytes:
        return await self._inbound.read(max_bytes)

    def _read_event(self, parse: Callable[[bytes], E | NeedData]) -> Awaitable[E]:
        return self._inbound.read_event(parse, self)

    @property
    def arrived_at(self) -> float:
        """``time.monotonic()`` when the bytes last read arrived (see :meth:`hand_over`)."""
        return self._inbound.arrived_at

    async def _write_all(self, data: bytes) -> None:
        self.hand_over(data)

    def hand_over(self, data: bytes, arrived_at: float | None = None) -> None:
        """Give ``data`` to the other end now, saying it arrived at ``arrived_at`` (default now):
        a pacer hands bytes over when it gets to it and says when the line carried them."""
        peer = self._peer
        if peer is None or peer.closed:
            raise LinkClosedError(f"{self.name}: the other end is closed")
        peer._inbound.feed(data, arrived_at)

    async def _close_transport(self) -> None:
        self._inbound.feed_end(f"{self.name} is closed")
        if self._peer is not None:
            self._peer._inbound.feed_end(f"{self._peer.name}: the other end closed")


def memory_pair(names: tuple[str, str] = ("memory a", "memory b")) -> tuple[MemoryLink, MemoryLink]:
    """Return two connected links; closing either one ends the stream for the other."""
    first, second = MemoryLink(names[0]), MemoryLink(names[1])
    first._peer, second._peer = second, first
    return first, second
