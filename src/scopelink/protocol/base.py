"""What the four codecs share (SynScan, Sky Tracker / Sky Commander, LX200, Stellarium).

Every codec is sans-IO in the style of h11: feed bytes with ``receive_data``, take events with
``next_event``, which returns `NEED_DATA` when it cannot say anything yet. Events say what they
mean in one line (`Event.describe`, also ``str()``); messages also know their exact bytes
(`Message.encode`). Calling a connection in a way the protocol forbids (a second command while one
is in flight, a reply with no command to answer) raises `LocalProtocolError`; bad bytes from the
peer never raise, they become error events."""

from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from typing import Final, Literal


class Wait(enum.Enum):
    """What ``next_event`` returns when it has no event to give."""

    NEED_DATA = "NEED_DATA"
    """More bytes are needed: call ``receive_data``."""
    PAUSED = "PAUSED"
    """The peer must decide something first (the Sky Tracker device answering a bus request)."""


NEED_DATA: Final = Wait.NEED_DATA
PAUSED: Final = Wait.PAUSED

NeedData = Literal[Wait.NEED_DATA]
"""The type of `NEED_DATA`."""


class LocalProtocolError(Exception):
    """Our own side asked for something the protocol does not allow in the current state."""


class Event(ABC):
    """Anything a codec hands out: a message, or an error event naming the byte and the reason."""

    __slots__ = ()

    @abstractmethod
    def describe(self) -> str:
        """One line saying what this event means, in plain units."""

    def __str__(self) -> str:
        return self.describe()


class Message(Event):
    """A unit on the wire that knows its exact bytes."""

    __slots__ = ()

    @abstractmethod
    def encode(self) -> bytes:
        """The exact bytes of this message on the wire."""
