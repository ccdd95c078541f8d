"""Alpaca request parameters: names, transaction ids and typed values.

The Alpaca spec makes GET query parameter *names* case-insensitive and PUT form parameter names
case-sensitive. A value that cannot be parsed at all (``Rate=fast``) is a malformed request
(HTTP 400, :class:`BadRequest`); a well-formed number outside its range, or NaN, is ASCOM's
InvalidValue (0x401, :class:`AlpacaError`), which the client reports as a driver error.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from scopelink.servers.alpaca.errors import AlpacaError, BadRequest, ErrorNumber

__all__ = ["UINT32_MAX", "Params", "parse_transaction_id"]

UINT32_MAX = 2**32 - 1

# ASCII decimals as clients send them (Python's float() would also take "1_0" and other digits).
_DECIMAL = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_INTEGER = re.compile(r"[+-]?\d+", re.ASCII)
_NON_FINITE = frozenset({"nan", "inf", "infinity"})
_TRUE = "true"
_FALSE = "false"


def parse_transaction_id(name: str, text: str | None) -> int:
    """``ClientID`` or ``ClientTransactionID``: absent means 0; otherwise a uint32 or HTTP 400."""
    if text is None:
        return 0
    # ASCII digits only: str.isdigit() also accepts superscripts, which int() refuses.
    digits_ok = text.isascii() and text.isdigit() and len(text) <= 10
    if not digits_ok or int(text) > UINT32_MAX:
        raise BadRequest(f"{name} must be an unsigned 32-bit integer, got {text!r}")
    return int(text)


@dataclass(frozen=True, slots=True)
class Params:
    """One request's parameters. ``exact`` is True for PUT (names case-sensitive); for GET the
    names are kept lower-cased, so a lookup folds only the name asked for."""

    values: Mapping[str, str]
    exact: bool

    @classmethod
    def from_pairs(cls, pairs: Iterable[tuple[str, str]], *, exact: bool) -> Params:
        values: dict[str, str] = {}
        for name, value in pairs:
            values.setdefault(name if exact else name.lower(), value)
        return cls(values, exact)

    def optional(self, name: str) -> str | None:
        """The raw value of ``name``, or None when absent (spelt another way, for PUT)."""
        return self.values.get(name if self.exact else name.lower())

    def text(self, name: str) -> str:
        value = self.optional(name)
        if value is not None:
            return value
        folded = name.lower()
        spelt = next((key for key in self.values if key.lower() == folded), None)
        if spelt is not None:
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
        stripped = text.strip()
        if _DECIMAL.fullmatch(stripped):
            value = float(stripped)
        elif stripped.lower().lstrip("+-") in _NON_FINITE:
            value = math.nan  # well formed, but no coordinate or rate: InvalidValue below
        else:
            raise BadRequest(f"{name} must be a decimal number, got {text!r}")
        if not math.isfinite(value):
            raise AlpacaError(
                ErrorNumber.INVALID_VALUE, f"{name} {stripped[:24]} must be a finite number"
            )
        if not low <= value <= high:
            limits = f"[{low:g}, {high:g}]"
            raise AlpacaError(
                ErrorNumber.INVALID_VALUE, f"{name} {stripped[:24]} must lie within {limits}"
            )
        return value

    def integer(self, name: str, low: int, high: int) -> int:
        text = self.text(name)
        stripped = text.strip()
        if not _INTEGER.fullmatch(stripped):
            raise BadRequest(f"{name} must be an integer, got {text!r}")
        # Length first: Python refuses to convert more than 4300 digits.
        if len(stripped) > 20 or not low <= int(stripped) <= high:
            raise AlpacaError(
                ErrorNumber.INVALID_VALUE, f"{name} {stripped[:24]} must lie in {low}..{high}"
            )
        return int(stripped)
