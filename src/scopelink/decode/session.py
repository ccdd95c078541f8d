"""What every protocol's annotating session shares: emitting annotations, stray device bytes."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence

from scopelink.decode.model import Annotation, Direction, Kind, Peer
from scopelink.protocol.base import Message


class Session(ABC):
    """Reads one trace byte by byte, in time order, and collects annotations.

    Subclasses parse the PC's bytes into commands and the device's bytes into the replies those
    commands await, oldest first. Every byte given ends up in exactly one annotation.
    """

    def __init__(self) -> None:
        self.annotations: list[Annotation] = []
        self._stray = bytearray()
        self._stray_positions: list[int] = []
        self._stray_peer = Peer.SYNSCAN

    @abstractmethod
    def awaiting_reply(self) -> bool:
        """Whether a command still awaits (more of) its reply: then untagged bytes are the
        device's."""

    @abstractmethod
    def from_pc(self, byte: int, offset: int) -> None:
        """One byte the computer sent; ``offset`` is its place in the trace."""

    @abstractmethod
    def from_device(self, byte: int, offset: int) -> None:
        """One byte the device sent; ``offset`` is its place in the trace."""

    def flush_input(self, offset: int) -> None:
        """The driver discarded unread input here: replies still awaited will never be read."""
        self._flush_stray()
        self._close_awaited(
            offset,
            "read: the driver discarded its input before the next command",
            "read, then the driver discarded its input before the next command",
        )

    @abstractmethod
    def _close_awaited(self, offset: int, why_absent: str, why_cut: str) -> None:
        """Report every awaited reply as absent (none of it read) or cut short, and stop waiting.

        ``why_absent`` and ``why_cut`` finish the sentences "no reply to X ..." and "incomplete
        reply to X: N bytes ...".
        """

    @abstractmethod
    def finish(self, offset: int) -> None:
        """The trace ends at ``offset``: report what is left incomplete or unanswered."""

    def _emit(
        self,
        positions: Sequence[int],
        data: bytes,
        kind: Kind,
        meaning: str,
        *,
        direction: Direction,
        peer: Peer,
        error_offset: int | None = None,
        message: Message | None = None,
        answers: int | None = None,
    ) -> None:
        self.annotations.append(
            Annotation(
                positions[0], data, direction, peer, kind, meaning, error_offset, message, answers
            )
        )

    def _note_absent(self, offset: int, peer: Peer, meaning: str, answers: int) -> None:
        """A note about a reply that is not in the trace (it covers no byte)."""
        self.annotations.append(
            Annotation(offset, b"", Direction.DEVICE, peer, Kind.NOTE, meaning, answers=answers)
        )

    def _stray_byte(self, byte: int, offset: int, peer: Peer) -> None:
        """A device byte while no reply is awaited; a run of them is reported as one error."""
        if self._stray and (
            peer is not self._stray_peer or offset != self._stray_positions[-1] + 1
        ):
            self._flush_stray()
        self._stray.append(byte)
        self._stray_positions.append(offset)
        self._stray_peer = peer

    def _flush_stray(self) -> None:
        if not self._stray:
            return
        count = len(self._stray)
        self._emit(
            self._stray_positions,
            bytes(self._stray),
            Kind.ERROR,
            f"{count} unexpected byte{'s' if count > 1 else ''} from the "
            f"{self._stray_peer.value}: no command awaits a reply",
            direction=Direction.DEVICE,
            peer=self._stray_peer,
            error_offset=self._stray_positions[0],
        )
        self._stray.clear()
        self._stray_positions.clear()


def describe_byte(value: int) -> str:
    """``0x47 ('G')`` for printable bytes, ``0x00`` otherwise."""
    printable = 0x20 <= value < 0x7F
    return f"0x{value:02X} ({chr(value)!r})" if printable else f"0x{value:02X}"
