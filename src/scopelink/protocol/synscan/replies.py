"""SynScan replies on the wire: encoding (server side) and incremental parsing by shape (client
side).

A reply is read by its exact length and shape for the command that asked for it, never "until #":
binary payloads (``w``, ``h``, ``P``, ``K``) may contain 0x23. The shape is checked byte by byte as
the bytes arrive, so a wrong reply is noticed at its first wrong byte."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

from scopelink.protocol.synscan import angles
from scopelink.protocol.synscan.angles import HASH
from scopelink.protocol.synscan.commands import (
    FieldError,
    decode_date_time,
    decode_hex_pair,
    decode_location,
    encode_date_time,
    encode_location,
)
from scopelink.protocol.synscan.events import NEED_DATA, NeedData
from scopelink.protocol.synscan.messages import (
    Ack,
    Aligned,
    AnyCommand,
    AnyReply,
    CancelGoto,
    DateTime,
    DeviceVersion,
    Echo,
    EchoReply,
    FixedRateSlew,
    Frame,
    GetAzAlt,
    GetDeviceVersion,
    GetLocation,
    GetModel,
    GetPointingState,
    GetRaDec,
    GetTime,
    GetTrackingMode,
    GetVersion,
    GotoAzAlt,
    GotoInProgress,
    GotoRaDec,
    IsAligned,
    IsGotoInProgress,
    Location,
    Model,
    Passthrough,
    PassthroughCommand,
    PassthroughFailed,
    PassthroughReply,
    PointingSide,
    PointingState,
    Position,
    SetAxisPosition,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SlowGoto,
    SyncRaDec,
    TrackingMode,
    VariableRateSlew,
    Version,
    VersionDialect,
    passthrough_reply_length,
)

_TERMINATOR = bytes((HASH,))
_VERSION_HEX_DIGITS = 6
_NEXSTAR_VERSION_BYTES = 2
_BINARY_SYNSCAN_VERSION_BYTES = 3

# ---------------------------------------------------------------------------------------- encoding


def encode_reply(reply: AnyReply) -> bytes:
    """The exact bytes the hand control sends for ``reply`` (uppercase hex, ``#`` last)."""
    match reply:
        case Ack():
            body = b""
        case Position(_, first, second, precise):
            body = angles.format_hex_angle(first, precise) + b","
            body += angles.format_hex_angle(second, precise)
        case TrackingMode(mode):
            body = bytes((mode,))
        case Location():
            body = encode_location(reply)
        case DateTime():
            body = encode_date_time(reply)
        case Version(major, minor, patch, VersionDialect.SYNSCAN_HEX):
            body = b"%02X%02X%02X" % (major, minor, patch or 0)
        case Version(major, minor, None, VersionDialect.NEXSTAR_BINARY):
            body = bytes((major, minor))
        case Version(major, minor, patch, _):
            body = bytes((major, minor, patch or 0))
        case Model(code, swapped):
            return _TERMINATOR + bytes((code,)) if swapped else bytes((code, HASH))
        case EchoReply(value):
            body = bytes((value,))
        case Aligned(aligned):
            body = bytes((int(aligned),))
        case GotoInProgress(in_progress):
            body = b"1" if in_progress else b"0"
        case PointingState(side):
            body = side.value.encode()
        case DeviceVersion(major, minor):
            body = bytes((major, minor))
        case PassthroughReply(data):
            body = data
        case PassthroughFailed(data, extra):
            body = data + bytes((extra,))
    return body + _TERMINATOR


reply_bytes = encode_reply
"""Alias of `encode_reply`."""


# ------------------------------------------------------------------------------------------- shape


@dataclass(frozen=True, slots=True)
class ReplyShape:
    """What a command's reply looks like: its possible total lengths (``#`` included) and in
    words."""

    lengths: tuple[int, ...]
    description: str


def reply_shape(command: AnyCommand) -> ReplyShape:
    """The expected reply of ``command`` (for trace annotation and timeouts)."""
    match command:
        case GetRaDec(precise) | GetAzAlt(precise):
            width = angles.hex_width(precise)
            return ReplyShape((2 * width + 2,), f"{width} hex, ',', {width} hex, '#'")
        case GetTrackingMode():
            return ReplyShape((2,), "binary mode byte, '#'")
        case GetLocation() | GetTime():
            return ReplyShape((9,), "8 binary bytes, '#'")
        case GetVersion():
            return ReplyShape(
                (7, 3, 4),
                "6 hex digits + '#', or 2 (NexStar) or 3 (old SynScan) binary bytes + '#'",
            )
        case GetModel():
            return ReplyShape((2,), "binary model byte, '#' (or '#' first on some firmware)")
        case Echo():
            return ReplyShape((2,), "the echoed byte, '#'")
        case IsAligned():
            return ReplyShape((2,), "binary 0x00/0x01, '#'")
        case IsGotoInProgress():
            return ReplyShape((2,), "ASCII '0'/'1', '#'")
        case GetPointingState():
            return ReplyShape((2,), "ASCII 'E'/'W', '#'")
        case (
            VariableRateSlew()
            | FixedRateSlew()
            | GetDeviceVersion()
            | SlowGoto()
            | SetAxisPosition()
            | Passthrough()
        ):
            count = passthrough_reply_length(command)
            return ReplyShape(
                (count + 1, count + 2), f"{count} bytes, '#' (one extra byte before '#' on failure)"
            )
        case GotoRaDec() | SyncRaDec() | GotoAzAlt() | SetTrackingMode():
            return ReplyShape((1,), "'#'")
        case SetLocation() | SetTime() | CancelGoto():
            return ReplyShape((1,), "'#'")


# ----------------------------------------------------------------------------------------- parsing


@dataclass(frozen=True, slots=True)
class Complete:
    """A whole reply was found at the start of the buffer; it took ``length`` bytes."""

    reply: AnyReply
    length: int


@dataclass(frozen=True, slots=True)
class Mismatch:
    """The buffer does not start with the expected reply; ``index`` is the first wrong byte."""

    index: int
    reason: str


ScanResult = Complete | Mismatch | NeedData

_ByteCheck = Callable[[int, int], str | None]
"""Checks payload byte ``value`` at ``index``; returns why it is wrong, or None."""


def scan_reply(command: AnyCommand, buffer: bytes | bytearray) -> ScanResult:
    """Look for ``command``'s reply at the start of ``buffer``, as far as its bytes go."""
    match command:
        case GetRaDec(precise):
            return _scan_position(buffer, Frame.EQUATORIAL, precise)
        case GetAzAlt(precise):
            return _scan_position(buffer, Frame.HORIZONTAL, precise)
        case GetTrackingMode():
            return _scan_terminated(buffer, 1, None, lambda body: TrackingMode(body[0]))
        case GetLocation():
            return _scan_terminated(buffer, 8, _flag_check(3, 7), decode_location)
        case GetTime():
            return _scan_terminated(buffer, 8, _flag_check(7), decode_date_time)
        case GetVersion():
            return _scan_version(buffer)
        case GetModel():
            return _scan_model(buffer)
        case Echo(value):
            return _scan_terminated(
                buffer, 1, _allowed_bytes(bytes((value,))), lambda body: EchoReply(body[0])
            )
        case IsAligned():
            return _scan_terminated(
                buffer, 1, _allowed_bytes(b"\x00\x01"), lambda body: Aligned(body[0] == 1)
            )
        case IsGotoInProgress():
            return _scan_terminated(
                buffer, 1, _allowed_bytes(b"01"), lambda body: GotoInProgress(body == b"1")
            )
        case GetPointingState():
            return _scan_terminated(
                buffer,
                1,
                _allowed_bytes(b"EW"),
                lambda body: PointingState(PointingSide(body.decode())),
            )
        case (
            VariableRateSlew()
            | FixedRateSlew()
            | GetDeviceVersion()
            | SlowGoto()
            | SetAxisPosition()
            | Passthrough()
        ):
            return _scan_passthrough(buffer, command)
        case GotoRaDec() | SyncRaDec() | GotoAzAlt() | SetTrackingMode():
            return _scan_terminated(buffer, 0, None, lambda body: Ack())
        case SetLocation() | SetTime() | CancelGoto():
            return _scan_terminated(buffer, 0, None, lambda body: Ack())


class ReplyError(ValueError):
    """A whole buffer is not exactly the reply a command expects."""


def parse_reply(command: AnyCommand, data: bytes) -> AnyReply:
    """Parse one whole reply (``#`` included); raises `ReplyError` if ``data`` is not exactly it."""
    result = scan_reply(command, data)
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
    return result.reply


def reply_fits(command: AnyCommand, reply: AnyReply) -> bool:
    """Whether ``reply`` is something the hand control may answer to ``command``."""
    try:
        return parse_reply(command, encode_reply(reply)) == reply
    except ReplyError:
        return False


def _scan_terminated(
    buffer: bytes | bytearray,
    body_length: int,
    check: _ByteCheck | None,
    build: Callable[[bytes], AnyReply | FieldError],
) -> ScanResult:
    """A fixed-length body, each byte checked as it arrives, then ``#``."""
    for index, value in enumerate(buffer[: body_length + 1]):
        if index == body_length:
            if value != HASH:
                return Mismatch(index, f"expected '#', got 0x{value:02X}")
        elif check is not None and (reason := check(index, value)) is not None:
            return Mismatch(index, reason)
    if len(buffer) <= body_length:
        return NEED_DATA
    built = build(bytes(buffer[:body_length]))
    if isinstance(built, FieldError):
        return Mismatch(built.index, built.reason)
    return Complete(built, body_length + 1)


def _allowed_bytes(allowed: bytes) -> _ByteCheck:
    def check(index: int, value: int) -> str | None:
        return None if value in allowed else f"expected one of {allowed!r}, got 0x{value:02X}"

    return check


def _flag_check(*flag_indices: int) -> _ByteCheck:
    def check(index: int, value: int) -> str | None:
        if index in flag_indices and value > 1:
            return f"flag byte must be 0 or 1, got {value}"
        return None

    return check


_WHOLE_POSITION: Final = {
    precise: re.compile(rb"([0-9A-Fa-f]{%d}),([0-9A-Fa-f]{%d})#" % (width, width))
    for precise, width in ((True, angles.hex_width(True)), (False, angles.hex_width(False)))
}
"""A complete, well-formed position reply at the start of a buffer (what nearly every poll gets);
anything else is scanned byte by byte, for the exact mismatch or how much is still missing."""


def _scan_position(buffer: bytes | bytearray, frame: Frame, precise: bool) -> ScanResult:
    whole = _WHOLE_POSITION[precise].match(buffer)
    if whole is not None:
        first, second = whole.groups()
        return Complete(Position(frame, int(first, 16), int(second, 16), precise), whole.end())
    width = angles.hex_width(precise)

    def check(index: int, value: int) -> str | None:
        if index == width:
            return None if value == ord(",") else f"expected ',', got 0x{value:02X}"
        return None if angles.is_hex_digit(value) else f"expected a hex digit, got 0x{value:02X}"

    def build(body: bytes) -> Position | FieldError:
        pair = decode_hex_pair(body, precise)
        return pair if isinstance(pair, FieldError) else Position(frame, *pair, precise)

    return _scan_terminated(buffer, 2 * width + 1, check, build)


def _scan_version(buffer: bytes | bytearray) -> ScanResult:
    """Tell the dialect by the first byte: a hex digit means SynScan's 6 hex digits + '#'.

    Otherwise the reply is binary: '#' as third byte ends a 2-byte NexStar version, any other third
    byte is the patch of an old 3-byte SynScan version, which must then be followed by '#'."""
    if not buffer:
        return NEED_DATA
    if angles.is_hex_digit(buffer[0]):

        def hex_check(index: int, value: int) -> str | None:
            return (
                None if angles.is_hex_digit(value) else f"expected a hex digit, got 0x{value:02X}"
            )

        def hex_build(body: bytes) -> Version:
            major, minor, patch = (int(body[i : i + 2], 16) for i in (0, 2, 4))
            return Version(major, minor, patch, VersionDialect.SYNSCAN_HEX)

        return _scan_terminated(buffer, _VERSION_HEX_DIGITS, hex_check, hex_build)
    if len(buffer) < _NEXSTAR_VERSION_BYTES + 1:
        return NEED_DATA
    if buffer[_NEXSTAR_VERSION_BYTES] == HASH:
        return Complete(
            Version(buffer[0], buffer[1], None, VersionDialect.NEXSTAR_BINARY),
            _NEXSTAR_VERSION_BYTES + 1,
        )
    return _scan_terminated(
        buffer,
        _BINARY_SYNSCAN_VERSION_BYTES,
        None,
        lambda body: Version(body[0], body[1], body[2], VersionDialect.SYNSCAN_BINARY),
    )


def _scan_model(buffer: bytes | bytearray) -> ScanResult:
    """``code #``, or ``# code`` from firmware that swaps them (a code of 35 reads as unswapped)."""
    if len(buffer) < 2:
        return NEED_DATA
    first, second = buffer[0], buffer[1]
    if second == HASH:
        return Complete(Model(first), 2)
    if first == HASH:
        return Complete(Model(second, swapped=True), 2)
    return Mismatch(1, f"expected '#' before or after the model byte, got 0x{second:02X}")


def _scan_passthrough(buffer: bytes | bytearray, command: PassthroughCommand) -> ScanResult:
    """``count`` bytes then ``#``; on failure one extra byte comes before the ``#``."""
    count = passthrough_reply_length(command)
    if len(buffer) <= count:
        return NEED_DATA
    data = bytes(buffer[:count])
    if buffer[count] == HASH:
        return Complete(_passthrough_success(command, data), count + 1)
    if len(buffer) <= count + 1:
        return NEED_DATA
    if buffer[count + 1] != HASH:
        return Mismatch(
            count + 1, f"expected '#' after the failure byte, got 0x{buffer[count + 1]:02X}"
        )
    return Complete(PassthroughFailed(data, buffer[count]), count + 2)


def _passthrough_success(command: PassthroughCommand, data: bytes) -> AnyReply:
    match command:
        case GetDeviceVersion():
            return DeviceVersion(data[0], data[1])
        case Passthrough():
            return PassthroughReply(data)
        case _:
            return Ack()
