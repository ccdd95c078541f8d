"""What ``config set`` and ``config unset`` changed, as lines for people:
``site.latitude: 40.4 -> 41.0`` (docs/cli.md, "config")."""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["change_lines", "read_settings", "toml_value"]

_MISSING = object()


def read_settings(path: Path) -> dict[str, Any]:
    """The file's settings as written (not the defaults filled in); empty when there is none
    or it does not parse (the edit that follows reports that)."""
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return {}


def _at(settings: dict[str, Any], key: str) -> object:
    value: object = settings
    for part in key.split("."):
        if not isinstance(value, dict) or part not in value:
            return _MISSING
        value = value[part]
    return value


def toml_value(value: object) -> str:
    """``value`` as TOML writes it (None, a server turned off, as ``false``)."""
    if value is None:
        return "false"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return repr(value)


def _shown(value: object) -> str:
    return "(default)" if value is _MISSING else toml_value(value)


def change_lines(keys: Sequence[str], before: dict[str, Any], after: dict[str, Any]) -> list[str]:
    """One line per key: ``KEY: OLD -> NEW``, or ``KEY: VALUE (unchanged)``."""
    lines = []
    for key in keys:
        old, new = _at(before, key), _at(after, key)
        if old == new:
            lines.append(f"{key}: {_shown(new)} (unchanged)")
        else:
            lines.append(f"{key}: {_shown(old)} -> {_shown(new)}")
    return lines
