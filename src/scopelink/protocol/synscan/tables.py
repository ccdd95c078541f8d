"""The SynScan codec's dispatch tables, derived from the message classes, and the functions that
use them.

`AnyCommand` and `AnyReply` list the classes once (for exhaustive ``match``); everything else is
derived: `FRAME_LENGTHS` and the frame decoders from each command's `Command.frames` and
`Command.decode`. A test checks that every `Command` and `Reply` subclass is listed."""

from __future__ import annotations

from typing import Final, cast, get_args

from scopelink.protocol.base import NEED_DATA
from scopelink.protocol.synscan import commands, passthrough, replies
from scopelink.protocol.synscan.message import FieldError, Mismatch, ReplyShape, ScanResult

AnyCommand = (
    commands.GetRaDec
    | commands.GetAzAlt
    | commands.GotoRaDec
    | commands.GotoAzAlt
    | commands.SyncRaDec
    | commands.GetTrackingMode
    | commands.SetTrackingMode
    | passthrough.VariableRateSlew
    | passthrough.FixedRateSlew
    | passthrough.GetDeviceVersion
    | passthrough.SlowGoto
    | passthrough.SetAxisPosition
    | passthrough.Passthrough
    | commands.GetLocation
    | commands.SetLocation
    | commands.GetTime
    | commands.SetTime
    | commands.GetVersion
    | commands.GetModel
    | commands.Echo
    | commands.IsAligned
    | commands.IsGotoInProgress
    | commands.CancelGoto
    | commands.GetPointingState
)
"""The closed union of every SynScan command (for exhaustive ``match``)."""

AnyReply = (
    replies.Ack
    | replies.Position
    | replies.TrackingModeReply
    | replies.Location
    | replies.DateTime
    | replies.Version
    | replies.Model
    | replies.EchoReply
    | replies.Aligned
    | replies.GotoInProgress
    | replies.PointingState
    | replies.DeviceVersion
    | replies.PassthroughReply
    | replies.PassthroughFailed
)
"""The closed union of every SynScan reply."""

COMMANDS: Final[tuple[type[AnyCommand], ...]] = get_args(AnyCommand)
"""Every command class."""

REPLIES: Final[tuple[type[AnyReply], ...]] = get_args(AnyReply)
"""Every reply class."""


def _frame_lengths() -> dict[int, int]:
    lengths: dict[int, int] = {}
    for command in COMMANDS:
        for first, length in command.frames.items():
            if lengths.setdefault(first, length) != length:
                raise TypeError(f"{command.__name__} frames {chr(first)!r} at another length")
    return lengths


FRAME_LENGTHS: Final[dict[int, int]] = _frame_lengths()
"""Total length in bytes (letter included) of each command, by its first byte."""

_DECODERS: Final[dict[int, tuple[type[AnyCommand], ...]]] = {
    first: tuple(command for command in COMMANDS if first in command.frames)
    for first in FRAME_LENGTHS
}
"""The classes whose frames start with each byte (several only for ``P``)."""


def frame_length(first_byte: int) -> int | None:
    """Length of the command that starts with this byte, or None if no command does."""
    return FRAME_LENGTHS.get(first_byte)


def decode_command_frame(frame: bytes) -> AnyCommand | FieldError:
    """The command in one complete frame (length as `frame_length` says), or where it is
    malformed."""
    for command in _DECODERS.get(frame[0], ()):
        decoded = command.decode(frame)
        if decoded is not None:
            return decoded
    raise ValueError(f"no command starts with {frame[:1]!r}")


def encode_command(command: AnyCommand) -> bytes:
    """The exact bytes that send ``command`` (positions as uppercase hex, low byte 00 when
    rounded)."""
    return command.encode()


def encode_reply(reply: AnyReply) -> bytes:
    """The exact bytes the hand control sends for ``reply`` (uppercase hex, ``#`` last)."""
    return reply.encode()


def reply_shape(command: AnyCommand) -> ReplyShape:
    """The expected reply of ``command`` (for trace annotation and timeouts)."""
    return command.reply_shape()


def scan_reply(command: AnyCommand, buffer: bytes | bytearray) -> ScanResult:
    """Look for ``command``'s reply at the start of ``buffer``, as far as its bytes go."""
    return command.scan_reply(buffer)


class ReplyError(ValueError):
    """A whole buffer is not exactly the reply a command expects."""


def parse_reply(command: AnyCommand, data: bytes) -> AnyReply:
    """Parse one whole reply (``#`` included); raises `ReplyError` if ``data`` is not exactly it."""
    result = command.scan_reply(data)
    if result is NEED_DATA:
        raise ReplyError(f"reply {data!r} to {command.describe()!r} is incomplete")
    if isinstance(result, Mismatch):
        raise ReplyError(
            f"reply {data!r} to {command.describe()!r}: {result.reason} at byte {result.index}"
        )
    if result.length != len(data):
        raise ReplyError(
            f"reply to {command.describe()!r} is {result.length} bytes, {len(data) - result.length}"
            " bytes follow it"
        )
    return cast(AnyReply, result.reply)  # every Reply class is in AnyReply (tests check)


def reply_fits(command: AnyCommand, reply: AnyReply) -> bool:
    """Whether ``reply`` is something the hand control may answer to ``command``."""
    try:
        return parse_reply(command, reply.encode()) == reply
    except ReplyError:
        return False
