"""The shape of every SynScan message, and what reading a reply can find.

A `Command` carries everything about one command: the first bytes it may start with and the
length of its frame (`Command.frames`), its encoding (`Command.encode`), its decoding from a frame
(`Command.decode`), the shape of its reply (`Command.reply_shape`) and how that reply is read
(`Command.scan_reply`), and which method of a `CommandHandler` answers it
(`Command.handler_name`). A `Reply` knows its bytes (`Reply.encode`). The dispatch tables of the
codec (`scopelink.protocol.synscan.tables`) are derived from these classes."""

from __future__ import annotations

import re
from abc import abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Self

from scopelink.protocol.base import Message, NeedData
from scopelink.protocol.synscan.angles import HASH

TERMINATOR: bytes = bytes((HASH,))
"""The ``#`` that ends every reply, as bytes."""


@dataclass(frozen=True, slots=True)
class ReplyShape:
    """What a command's reply looks like: its possible total lengths (``#`` included) and in
    words."""

    lengths: tuple[int, ...]
    description: str


@dataclass(frozen=True, slots=True)
class FieldError:
    """Where and why a payload does not parse; ``index`` counts from the start of the bytes
    given."""

    index: int
    reason: str

    def shifted(self, by: int) -> FieldError:
        """The same error re-indexed ``by`` bytes later (a payload error within its frame)."""
        return FieldError(self.index + by, self.reason)


@dataclass(frozen=True, slots=True)
class Complete:
    """A whole reply was found at the start of the buffer; it took ``length`` bytes."""

    reply: Reply
    length: int


@dataclass(frozen=True, slots=True)
class Mismatch:
    """The buffer does not start with the expected reply; ``index`` is the first wrong byte."""

    index: int
    reason: str


ScanResult = Complete | Mismatch | NeedData
"""What looking for a reply at the start of a buffer finds."""


class Command(Message):
    """A message from the PC to the hand control; each subclass is one command."""

    __slots__ = ()

    frames: ClassVar[Mapping[int, int]]
    """Total frame length (letter included) by each first byte this command may start with."""

    changes_mount: ClassVar[bool] = False
    """Whether it moves the mount or changes a setting (a read-only server refuses it)."""

    repeats_reply: ClassVar[bool] = False
    """A poll whose reply has one length and means the same whenever its bytes are the same: a
    client may reuse the reply it parsed last time from the same bytes (a tracking mount's
    ``e`` repeats for seconds; see `SynScanClientConnection`)."""

    handler_name: ClassVar[str]
    """The method of a `CommandHandler` that answers it: the class name in snake case
    (`GetRaDec` -> ``get_ra_dec``)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.handler_name = re.sub(r"(?<!^)(?=[A-Z])", "_", cls.__name__.lstrip("_")).lower()

    @classmethod
    @abstractmethod
    def decode(cls, frame: bytes) -> Self | FieldError | None:
        """The command in a whole frame that starts with one of its `frames`, where that frame is
        malformed, or None when the frame is another command's (passthrough payloads)."""

    @abstractmethod
    def reply_shape(self) -> ReplyShape:
        """The expected reply (for trace annotation and timeouts)."""

    @abstractmethod
    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        """Look for this command's reply at the start of ``buffer``, as far as its bytes go."""


class Reply(Message):
    """A message from the hand control to the PC."""

    __slots__ = ()

    @abstractmethod
    def body(self) -> bytes:
        """The bytes before the closing ``#``."""

    def encode(self) -> bytes:
        """The exact bytes the hand control sends (uppercase hex, ``#`` last)."""
        return self.body() + TERMINATOR


def letter_frames(letters: bytes, length: int) -> dict[int, int]:
    """`Command.frames` for commands whose every letter starts a frame of ``length`` bytes."""
    return dict.fromkeys(letters, length)
