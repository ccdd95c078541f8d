"""Validating the JSON bodies of the dashboard's API: every refusal names the field and why."""

from __future__ import annotations

import enum
import json
import math
from typing import TypeVar

from aiohttp import web

__all__ = ["BadRequestError", "Body", "read_body"]

MAX_BODY_BYTES = 4096
"""Every command fits in a few hundred bytes; more is a mistake or an attack."""

E = TypeVar("E", bound=enum.Enum)


class BadRequestError(Exception):
    """The request cannot be acted on as sent (HTTP 400); the message says what to change."""


class Body:
    """A JSON object received from the browser, read field by field with checks."""

    def __init__(self, fields: dict[str, object]) -> None:
        self._fields = fields

    def has(self, key: str) -> bool:
        return self._fields.get(key) is not None

    def number(self, key: str, low: float, high: float, *, default: float | None = None) -> float:
        """A finite number in [``low``, ``high``]; ``default`` when absent (else required)."""
        value = self._fields.get(key)
        if value is None:
            if default is not None:
                return default
            raise BadRequestError(f"{key!r} is required")
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise BadRequestError(f"{key!r} must be a number, not {type(value).__name__}")
        try:
            number = float(value)
        except OverflowError:  # JSON integers have no size limit; 1e400 as an int gets here
            raise BadRequestError(f"{key!r} must lie in [{low:g}, {high:g}]") from None
        if not (math.isfinite(number) and low <= number <= high):
            raise BadRequestError(f"{key!r} must lie in [{low:g}, {high:g}], not {number:g}")
        return number

    def text(self, key: str, *, max_length: int = 100) -> str:
        """A non-empty string of at most ``max_length`` characters, stripped."""
        value = self._fields.get(key)
        if not isinstance(value, str):
            raise BadRequestError(f"{key!r} is required and must be a string")
        text = value.strip()
        if not text:
            raise BadRequestError(f"{key!r} must not be empty")
        if len(text) > max_length:
            raise BadRequestError(f"{key!r} must be at most {max_length} characters")
        return text

    def choice(self, key: str, kind: type[E]) -> E:
        """One of an enum's members, given by its string value or its name (any case)."""
        value = self._fields.get(key)
        spellings = {}
        for member in kind:
            spellings[member.name.lower()] = member
            if isinstance(member.value, str):
                spellings[member.value.lower()] = member
        if isinstance(value, str) and value.lower() in spellings:
            return spellings[value.lower()]
        allowed = ", ".join(
            member.value if isinstance(member.value, str) else member.name.lower()
            for member in kind
        )
        raise BadRequestError(f"{key!r} must be one of {allowed}, not {value!r}")


async def read_body(request: web.Request) -> Body:
    """The request's JSON object. Only ``application/json`` is accepted: a cross-site page can
    then not send commands without a CORS preflight, which this server never grants."""
    if request.content_type != "application/json":
        raise BadRequestError("send the command as JSON (Content-Type: application/json)")
    if request.content_length is not None and request.content_length > MAX_BODY_BYTES:
        raise BadRequestError(f"the request body must be at most {MAX_BODY_BYTES} bytes")
    # read() returns what has arrived, not the whole body: a body split across TCP segments
    # (found by the dashboard-http fuzz target) is read to its end, up to the limit.
    parts: list[bytes] = []
    size = 0
    while size <= MAX_BODY_BYTES and (part := await request.content.read(MAX_BODY_BYTES + 1)):
        parts.append(part)
        size += len(part)
    raw = b"".join(parts)
    if len(raw) > MAX_BODY_BYTES:
        raise BadRequestError(f"the request body must be at most {MAX_BODY_BYTES} bytes")
    if not raw.strip():
        return Body({})
    try:
        decoded = json.loads(raw)
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise BadRequestError(f"the request body is not valid JSON: {error}") from None
    except RecursionError:  # the C decoder recurses once per level: "[[[[..." in 4 KiB
        raise BadRequestError("the request body nests too deeply to be a command") from None
    if not isinstance(decoded, dict):
        raise BadRequestError("the request body must be a JSON object")
    return Body(decoded)
