"""What every Sky Tracker / Sky Commander codec shares: message bases, error events, sentinels."""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import ClassVar, Self

from scopelink.protocol.base import Event, Message


class Reply(Message):
    """A fixed-length answer; clients read replies by length, never by content."""

    __slots__ = ()
    size: ClassVar[int]

    @classmethod
    @abstractmethod
    def decode(cls, data: bytes) -> Self:
        """Parse exactly :attr:`size` bytes; raise ``ValueError`` saying what is wrong."""


class Command(Message):
    """A request from the PC; :attr:`reply` is the reply class it gets, or None for none."""

    __slots__ = ()
    reply: ClassVar[type[Reply] | None]


@dataclass(frozen=True, slots=True)
class Acknowledge(Reply):
    """``A``: the Sky Tracker accepted calibration (``S``); the Sky Commander loaded an object."""

    size: ClassVar[int] = 1

    @classmethod
    def decode(cls, data: bytes) -> Self:
        if data != b"A":
            raise ValueError(f"expected acknowledge 'A', got {data!r}")
        return cls()

    def encode(self) -> bytes:
        return b"A"

    def describe(self) -> str:
        return "A: acknowledged"


@dataclass(frozen=True, slots=True)
class ErrorEvent(Event):
    """Bytes that could not be understood. The codec has consumed them and carries on.

    ``offset`` is the stream position of ``data[0]`` (counted from the first byte ever given to
    ``receive_data``), so a trace decoder can point at the fault.
    """

    offset: int
    data: bytes
    reason: str

    def describe(self) -> str:
        return f"error at byte {self.offset}: {self.reason} [{self.data.hex(' ')}]"


@dataclass(frozen=True, slots=True)
class UnknownCommand(ErrorEvent):
    """A byte that starts no command the device knows."""


@dataclass(frozen=True, slots=True)
class MalformedCommand(ErrorEvent):
    """A complete command whose payload does not parse or is out of range."""


@dataclass(frozen=True, slots=True)
class LineTooLong(ErrorEvent):
    """A Sky Commander ``L`` line with no carriage return within the length bound (or its tail)."""


@dataclass(frozen=True, slots=True)
class IncompleteFrame(ErrorEvent):
    """The start of a command whose remaining bytes never came (dropped on request)."""


@dataclass(frozen=True, slots=True)
class BadReply(ErrorEvent):
    """A reply of the right length with contents that do not fit the command it answers."""


@dataclass(frozen=True, slots=True)
class StrayByte(ErrorEvent):
    """A byte from the device while no reply was expected."""
