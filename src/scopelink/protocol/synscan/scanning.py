"""Reading SynScan fields byte by byte: the incremental reply reader and the hex angle pairs.

A reply is read by its exact length and shape for the command that asked for it, never "until #":
binary payloads (``w``, ``h``, ``P``, ``K``) may contain 0x23. The shape is checked byte by byte as
the bytes arrive, so a wrong reply is noticed at its first wrong byte."""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Final

from scopelink.protocol.base import NEED_DATA
from scopelink.protocol.synscan import angles
from scopelink.protocol.synscan.angles import HASH
from scopelink.protocol.synscan.message import Complete, FieldError, Mismatch, Reply, ScanResult

ByteCheck = Callable[[int, int], str | None]
"""Checks payload byte ``value`` at ``index``; returns why it is wrong, or None."""


def scan_terminated(
    buffer: bytes | bytearray,
    body_length: int,
    check: ByteCheck | None,
    build: Callable[[bytes], Reply | FieldError],
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


def allowed_bytes(allowed: bytes) -> ByteCheck:
    """A check that accepts only the given byte values."""

    def check(index: int, value: int) -> str | None:
        return None if value in allowed else f"expected one of {allowed!r}, got 0x{value:02X}"

    return check


def flag_check(*flag_indices: int) -> ByteCheck:
    """A check that the bytes at ``flag_indices`` are 0 or 1."""

    def check(index: int, value: int) -> str | None:
        if index in flag_indices and value > 1:
            return f"flag byte must be 0 or 1, got {value}"
        return None

    return check


def hex_check(index: int, value: int) -> str | None:
    """A check that every byte is a hex digit."""
    return None if angles.is_hex_digit(value) else f"expected a hex digit, got 0x{value:02X}"


def encode_hex_pair(first: int, second: int, precise: bool) -> bytes:
    """Two angles as uppercase hex, comma-separated (``34AB,12CE``)."""
    return angles.format_hex_angle(first, precise) + b"," + angles.format_hex_angle(second, precise)


_HEX_PAIR: Final = {
    precise: re.compile(rb"[0-9A-Fa-f]{%d},[0-9A-Fa-f]{%d}" % (width, width))
    for precise, width in ((True, angles.hex_width(True)), (False, angles.hex_width(False)))
}
"""A well-formed pair of each width; anything else goes through the byte-by-byte check."""


def decode_hex_pair(text: bytes, precise: bool) -> tuple[int, int] | FieldError:
    """Two comma-separated hex angles (either case), e.g. ``34AB,12CE`` or ``34AB0500,12CE0500``."""
    width = angles.hex_width(precise)
    if _HEX_PAIR[precise].fullmatch(text):  # the usual case, at C speed
        return int(text[:width], 16), int(text[width + 1 :], 16)
    for index, byte in enumerate(text):
        if index == width:
            if byte != ord(","):
                return FieldError(index, f"expected ',' got {bytes((byte,))!r}")
        elif not angles.is_hex_digit(byte):
            return FieldError(index, f"expected a hex digit, got {bytes((byte,))!r}")
    return int(text[:width], 16), int(text[width + 1 :], 16)
