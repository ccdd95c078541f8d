"""Reading a trace written as text: escaped bytes or hex, direction tags, INDI debug-log lines.

Each input line (or command-line argument) is one chunk. Literal line breaks only separate chunks;
bytes 0x0D and 0x0A are written ``\\r`` and ``\\n``. See ``docs/decode.md`` for the whole format.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import Final

from scopelink.decode.model import Chunk, Direction

_ESCAPES: Final[dict[int, int]] = {
    ord("r"): 0x0D,
    ord("n"): 0x0A,
    ord("t"): 0x09,
    ord("0"): 0x00,
    ord("\\"): 0x5C,
}
_ESCAPED: Final[dict[int, str]] = {value: "\\" + chr(letter) for letter, value in _ESCAPES.items()}
_HEX_DIGITS: Final = b"0123456789abcdefABCDEF"

_TAGS: Final[tuple[tuple[bytes, Direction], ...]] = (
    (b"->", Direction.PC),
    (b"<-", Direction.DEVICE),
    (b">", Direction.PC),
    (b"<", Direction.DEVICE),
    (b"TX:", Direction.PC),
    (b"RX:", Direction.DEVICE),
    (b"PC:", Direction.PC),
    (b"HC:", Direction.DEVICE),
    (b"ST:", Direction.DEVICE),
    (b"SC:", Direction.DEVICE),
)
"""Direction tags at the very start of a line, longest first where one begins another."""

# What INDI's drivers print at debug level (synscandriver.cpp, lx200 drivers: sendCommand;
# skycommander.cpp: ReadScopeStatus). Raw strings and hex dumps are told apart by their shape.
_INDI_BRACKETED: Final = re.compile(rb"\b(CMD|RES) <(.*)>")
_INDI_COMMANDER_CMD: Final = re.compile(rb"\bCMD: 0[Xx]([0-9A-Fa-f]{1,2})\b")
_INDI_COMMANDER_RES: Final = re.compile(rb"\bRES: (.*)")
_INDI_HEX_DUMP: Final = re.compile(rb"[0-9A-F]{2}(?: [0-9A-F]{2})*")
_LINE_BREAK: Final = re.compile(rb"\r\n|\r|\n")
_HEX_GROUP: Final = re.compile(rb"[^\s,:]+")


class TraceInputError(ValueError):
    """The input text is not a trace; ``line`` is the offending line (or argument), ``column``
    the offending character's index in it."""

    def __init__(self, reason: str, line: bytes, column: int) -> None:
        super().__init__(reason)
        self.reason = reason
        self.line = line
        self.column = column


def escape_bytes(data: bytes) -> str:
    """Bytes as escaped text that `unescape` reads back: printable ASCII as is, ``\\r \\n \\t
    \\0 \\\\``, anything else ``\\xNN``."""
    return "".join(
        _ESCAPED.get(byte) or (chr(byte) if 0x20 <= byte < 0x7F else f"\\x{byte:02x}")
        for byte in data
    )


def unescape(text: bytes) -> bytes:
    """Escaped text to bytes: ``\\r \\n \\t \\0 \\xNN \\\\``; every other byte stands for
    itself."""
    out = bytearray()
    index = 0
    while index < len(text):
        byte = text[index]
        if byte != ord("\\"):
            out.append(byte)
            index += 1
            continue
        letter = text[index + 1] if index + 1 < len(text) else None
        if letter in _ESCAPES:
            out.append(_ESCAPES[letter])
            index += 2
        elif letter == ord("x"):
            digits = text[index + 2 : index + 4]
            if len(digits) < 2 or any(digit not in _HEX_DIGITS for digit in digits):
                raise TraceInputError("\\x needs two hex digits", text, index)
            out.append(int(digits, 16))
            index += 4
        else:
            raise TraceInputError("unknown escape: use \\r \\n \\t \\0 \\xNN or \\\\", text, index)
    return bytes(out)


def parse_hex(text: bytes) -> bytes:
    """Hex bytes separated (or not) by whitespace, commas or colons, each group optionally
    ``0x``-prefixed: ``65 33``, ``0x65,0x33``, ``65:33``, ``6533``; ``0xD`` is one byte."""
    out = bytearray()
    for group in _HEX_GROUP.finditer(text):
        digits, first = group[0], group.start()
        prefixed = digits[:2] in (b"0x", b"0X")
        if prefixed:
            digits, first = digits[2:], first + 2
        for index, digit in enumerate(digits):
            if digit not in _HEX_DIGITS:
                raise TraceInputError("not a hex digit", text, first + index)
        if prefixed and len(digits) < 2:
            if not digits:
                raise TraceInputError("0x needs hex digits", text, first - 2)
            digits = b"0" + digits
        if len(digits) % 2:
            raise TraceInputError(
                "odd number of hex digits (write bytes as two digits)", text, first
            )
        out += bytes.fromhex(digits.decode("ascii"))
    return bytes(out)


def split_tag(line: bytes) -> tuple[Direction | None, bytes, int]:
    """The direction tag at the start of ``line`` (None if none), the rest, and where the rest
    starts. One space or tab after a tag separates it and is not data."""
    for tag, direction in _TAGS:
        if line.startswith(tag):
            start = len(tag)
            if line[start : start + 1] in (b" ", b"\t"):
                start += 1
            return direction, line[start:], start
    return None, line, 0


def indi_chunk(line: bytes) -> Chunk | None:
    """The traffic in one line of an INDI debug log, or None if the line shows none.

    ``CMD <...>`` / ``RES <...>`` hold a raw string or an uppercase hex dump (``50 02 11 24``);
    INDI flushes its input before each command, so a command chunk ``flushes_input``. The Sky
    Commander driver prints ``CMD: 0XD`` and ``RES: <reply up to its NUL>``: the NUL is put back.
    """
    if (match := _INDI_BRACKETED.search(line)) is not None:
        content = match[2]
        data = bytes.fromhex(content.decode()) if _INDI_HEX_DUMP.fullmatch(content) else content
        if match[1] == b"CMD":
            return Chunk(data, Direction.PC, flushes_input=True)
        return Chunk(data, Direction.DEVICE)
    if (match := _INDI_COMMANDER_CMD.search(line)) is not None:
        return Chunk(bytes((int(match[1], 16),)), Direction.PC, flushes_input=True)
    if (match := _INDI_COMMANDER_RES.search(line)) is not None:
        return Chunk(match[1] + b"\0", Direction.DEVICE)
    return None


def parse_trace(items: Iterable[bytes], *, hex_input: bool = False) -> list[Chunk]:
    """Chunks from lines or arguments (each may hold several lines).

    If any line is an INDI traffic line, the input is read as an INDI log: only those lines
    count. Otherwise each non-empty line is one chunk: an optional direction tag, then escaped
    text (or hex with ``hex_input``). Raises `TraceInputError` at the first line that does not
    read."""
    lines = [line for item in items for line in _LINE_BREAK.split(item) if line]
    indi = [chunk for chunk in map(indi_chunk, lines) if chunk is not None]
    if indi:
        return indi
    chunks = []
    for line in lines:
        direction, body, start = split_tag(line)
        try:
            data = parse_hex(body) if hex_input else unescape(body)
        except TraceInputError as error:
            raise TraceInputError(error.reason, line, start + error.column) from None
        chunks.append(Chunk(data, direction))
    return chunks
