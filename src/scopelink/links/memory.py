"""Two in-memory links joined back to back: what one writes, the other reads."""

from __future__ import annotations

from scopelink.links.base import Link, LinkClosedError
from scopelink.links.inbound import InboundBuffer


class MemoryLink(Link):
    """One end of a :func:`memory_pair`. Writes never block (the buffer is unbounded)."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self._inbound = InboundBuffer()
        self._peer: MemoryLink | None = None

    async def _read_some(self, max_bytes: int) -> bytes:
        return await self._inbound.read(max_bytes)

    async def _write_all(self, data: bytes) -> None:
        peer = self._peer
        if peer is None or peer.closed:
            raise LinkClosedError(f"{self.name}: the other end is closed")
        peer._inbound.feed(data)

    async def _close_transport(self) -> None:
        self._inbound.feed_end(f"{self.name} is closed")
        if self._peer is not None:
            self._peer._inbound.feed_end(f"{self._peer.name}: the other end closed")


def memory_pair(names: tuple[str, str] = ("memory a", "memory b")) -> tuple[MemoryLink, MemoryLink]:
    """Return two connected links; closing either one ends the stream for the other."""
    first, second = MemoryLink(names[0]), MemoryLink(names[1])
    first._peer, second._peer = second, first
    return first, second
