"""Reading the time a page sends (``POST /api/time``, ``POST /api/setup``)."""

from __future__ import annotations

from datetime import UTC, datetime

from scopelink.web.params import BadRequestError

__all__ = ["TIME_SKEW_LIMIT_YEARS", "parse_utc"]

TIME_SKEW_LIMIT_YEARS = 200
"""A time further than this from the PC's clock is a mistake, not a time to set."""


def parse_utc(text: str) -> datetime:
    """An ISO 8601 time with a zone (``...Z`` for UTC) as an aware UTC datetime."""
    try:
        utc = datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise BadRequestError(f"'utc' must be an ISO 8601 time with a zone, not {text!r}") from None
    if utc.tzinfo is None:
        raise BadRequestError("'utc' must carry a time zone (end it with Z for UTC)")
    if abs(utc.year - datetime.now(UTC).year) > TIME_SKEW_LIMIT_YEARS:
        raise BadRequestError(f"'utc' {text!r} is not a plausible time")
    return utc.astimezone(UTC)
