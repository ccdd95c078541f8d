"""What a trace is made of and what the annotator says about it."""

from __future__ import annotations

import enum
from dataclasses import dataclass

from scopelink.protocol.base import Message


class Protocol(enum.Enum):
    """Which conversation a trace holds."""

    SYNSCAN = "synscan"
    """PC <-> SynScan hand control."""
    SKYTRACKER = "skytracker"
    """PC <-> Sky Tracker, with the Sky Commander reached through the bus (``Q``/``A``/``q``)."""
    SKYCOMMANDER = "skycommander"
    """PC <-> Sky Commander on its own port."""


class Direction(enum.Enum):
    """Who sent a byte."""

    PC = "pc"
    """From the computer to the device."""
    DEVICE = "device"
    """From the device (hand control, Sky Tracker or Sky Commander) to the computer."""


class Peer(enum.Enum):
    """The device a message is for or from."""

    SYNSCAN = "SynScan hand control"
    SKY_TRACKER = "Sky Tracker"
    SKY_COMMANDER = "Sky Commander"


class Kind(enum.Enum):
    """What an annotation is."""

    COMMAND = "command"
    REPLY = "reply"
    NOTE = "note"
    """Worth knowing but not wrong: a stray ``#``, a reply absent from the trace."""
    ERROR = "error"


@dataclass(frozen=True, slots=True)
class Chunk:
    """Bytes as one line or argument of the input gave them.

    ``direction`` is None when the input did not say; the annotator then infers it (a reply follows
    its command). ``flushes_input`` marks a command written by a driver that discards unread
    input first (INDI's ``sendCommand``), so an earlier reply that was not read never comes.
    """

    data: bytes
    direction: Direction | None = None
    flushes_input: bool = False


@dataclass(frozen=True, slots=True)
class Annotation:
    """One message, note or error, and where its bytes sit in the trace.

    ``offset`` counts from the first byte of the trace (all chunks one after the other, in input
    order) and is where ``data`` begins. ``data`` may be empty for a note about something absent
    (a reply not in the trace). For an error, ``error_offset`` is the offending byte. A reply, a
    reply that does not fit or a note about a missing reply ``answers`` the command at that offset.
    """

    offset: int
    data: bytes
    direction: Direction
    peer: Peer
    kind: Kind
    meaning: str
    error_offset: int | None = None
    message: Message | None = None
    answers: int | None = None

    @property
    def is_error(self) -> bool:
        """Whether this annotation reports something wrong."""
        return self.kind is Kind.ERROR
