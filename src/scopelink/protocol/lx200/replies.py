"""The handset's replies as bytes. Which command gets which shape is in
:func:`~scopelink.protocol.lx200.commands.reply_kind`."""

from __future__ import annotations

import enum
from typing import Final

from scopelink.protocol.lx200.angles import MEADE_DEGREE_SIGN

__all__ = [
    "DATE_SET_REPLY",
    "MAX_REASON_LENGTH",
    "SlewRefusal",
    "boolean_reply",
    "slew_reply",
    "text_reply",
]

DATE_SET_REPLY: Final = b"1Updating Planetary Data#" + b" " * 30 + b"#"
"""``:SC#`` accepted: ``1``, then two ``#``-terminated strings, as Meade's handsets send them
(INDI reads both, so nothing is left over to desynchronise the next reply)."""

MAX_REASON_LENGTH: Final = 40
"""Longest reason text after a refused ``:MS#`` (clients read it into small buffers)."""


class SlewRefusal(enum.Enum):
    """The first byte of a refused ``:MS#``: ``1`` below the horizon, ``2`` any other limit or
    reason (Meade: "below higher", i.e. the elevation limit)."""

    BELOW_HORIZON = "1"
    OTHER = "2"


_KEPT: Final = frozenset({"\x7f", MEADE_DEGREE_SIGN})


def boolean_reply(ok: bool) -> bytes:
    """``1`` (valid, done) or ``0`` (invalid) without a terminator."""
    return b"1" if ok else b"0"


def _clean(text: str, limit: int | None = None) -> str:
    """Printable ASCII without ``#``; the terminator must end the reply, nothing else."""
    cleaned = "".join(c if " " <= c <= "~" and c != "#" else " " for c in text)
    return cleaned if limit is None else cleaned[:limit]


def text_reply(text: str) -> bytes:
    """``text`` + ``#`` (a ``#`` or unprintable character inside becomes a space; 0x7F, the
    distance-bar character, and 0xDF, Meade's degree sign, are kept)."""
    cleaned = "".join(c if c in _KEPT else _clean(c) for c in text)
    return cleaned.encode("latin-1") + b"#"


def slew_reply(refusal: SlewRefusal | None, reason: str = "") -> bytes:
    """``0`` for a slew under way, else the refusal digit, the reason and ``#``."""
    if refusal is None:
        return b"0"
    return (refusal.value + _clean(reason, MAX_REASON_LENGTH)).encode("ascii") + b"#"
