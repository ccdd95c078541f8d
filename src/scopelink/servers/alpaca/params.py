"""Alpaca request parameters: names, transaction ids and typed values.

The Alpaca spec makes GET query parameter *names* case-insensitive and PUT form parameter names
case-sensitive. A value that cannot be parsed at all (``Rate=fast``) is a malformed request
(HTTP 400, :class:`BadRequest`); a well-formed number outside its range, or NaN, is ASCOM's
InvalidValue (0x401, :class:`AlpacaError`), which the client reports as a driver error.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from scopelink.servers.alpaca.errors import AlpacaError, BadRequest, ErrorNumber

__all__ = ["UINT32_MAX", "Params", "parse_transaction_id"]

UINT32_MAX = 2**32 - 1

_TRUE = "true"
_FALSE = "false"


def parse_transaction_id(name: str, text: str | None) -> int:
    """``ClientID`` or ``ClientTransactionID``: absent means 0; otherwise a uint32 or HTTP 400."""
    if text is None:
        return 0
    stripped = text.strip()
    if not stripped.isdigit() or stripped != text or int(stripped) > UINT32_MAX:
        raise BadRequest(f"{name} must be an unsigned 32-bit integer, got {text!r}")
    return int(stripped)


@dataclass(frozen=True, slots=True)
class Params:
    """One request's parameters. ``exact`` is True for PUT (names case-sensitive)."""

    values: Mapping[str, str]
    folded: Mapping[str, str]
    exact: bool

    @classmethod
    def from_pairs(cls, pairs: Iterable[tuple[str, str]], *, exact: bool) -> Params:
        values: dict[str, str] = {}
        folded: dict[str, str] = {}
        for name, value in pairs:
            values.setdefault(name, value)
            folded.setdefault(name.lower(), value)
        return cls(values, folded, exact)

    def optional(self, name: str) -> str | None:
        """The raw value of ``name``, or None when absent (spelt another way, for PUT)."""
        return self.values.get(name) if self.exact else self.folded.get(name.lower())

    def text(self, name: str) -> str:
        value = self.optional(name)
        if value is not None:
            return value
        if self.exact and name.lower() in self.folded:
            spelt = next(key for key in self.values if key.lower() == name.lower())
            raise BadRequest(
                f"form parameter {spelt!r} must be spelt {name!r}: PUT parameter names are "
                "case-sensitive"
            )
        raise BadRequest(f"missing parameter {name!r}")

    def boolean(self, name: str) -> bool:
        text = self.text(name)
        lowered = text.strip().lower()
        if lowered == _TRUE:
            return True
        if lowered == _FALSE:
            return False
        raise BadRequest(f"{name} must be True or False, got {text!r}")

    def number(self, name: str, low: float = -math.inf, high: float = math.inf) -> float:
        """A finite float within [low, high]; NaN or outside the range is InvalidValue."""
        text = self.text(name)
        try:
            value = float(text)
        except ValueError:
            raise BadRequest(f"{name} must be a number, got {text!r}") from None
        if not (math.isfinite(value) and low <= value <= high):
            raise AlpacaError(
                ErrorNumber.INVALID_VALUE, f"{name} {text} must lie within [{low:g}, {high:g}]"
            )
        return value

    def integer(self, name: str, low: int, high: int) -> int:
        text = self.text(name)
        try:
            value = int(text.strip())
        except ValueError:
            raise BadRequest(f"{name} must be an integer, got {text!r}") from None
        if not low <= value <= high:
            raise AlpacaError(
                ErrorNumber.INVALID_VALUE, f"{name} {value} must lie in {low}..{high}"
            )
        return value
