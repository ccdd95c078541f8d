"""``scopelink info`` for people: the report of :func:`~scopelink.cli.info_command.describe` as
labelled lines ("max axis rate  3.34°/s"), the JSON keys kept for ``--json`` (docs/cli.md, "info").

Known keys get a label and a unit; a key this module does not know yet is still shown, its
underscores turned into spaces, so a driver's new detail is never hidden.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Final

__all__ = ["info_lines"]


def _yes_no(value: object) -> str:
    return "yes" if value else "no"


def _axes(value: object) -> str:
    if not isinstance(value, list | tuple) or len(value) != 2:
        return _plain(value)
    primary, secondary = bool(value[0]), bool(value[1])
    if primary and secondary:
        return "both axes"
    if primary or secondary:
        return "primary axis only" if primary else "secondary axis only"
    return "no"


def _rate(value: object) -> str:
    return f"{value:.2f}°/s" if isinstance(value, int | float) else _plain(value)


def _versions(value: object) -> str:
    """The motor controllers' ``[[3, 39], [3, 39]]`` as ``3.39, 3.39`` (``-`` for one silent)."""
    if not isinstance(value, list | tuple):
        return _plain(value)
    return ", ".join(
        f"{pair[0]}.{pair[1]:02d}" if isinstance(pair, list | tuple) and len(pair) == 2 else "-"
        for pair in value
    )


def _plain(value: object) -> str:
    if isinstance(value, bool):
        return _yes_no(value)
    if isinstance(value, list | tuple):
        return ", ".join(_plain(item) for item in value) or "-"
    if value is None or value == "":
        return "-"
    return str(value).replace("_", " ") if isinstance(value, str) else str(value)


_LABELS: Final[dict[str, tuple[str, Callable[[object], str]]]] = {
    "protocol": ("protocol", _plain),
    "model": ("model", _plain),
    "firmware": ("firmware", _plain),
    "link": ("link", _plain),
    "aligned": ("aligned", _yes_no),
    "alignment_mode": ("mount type", _plain),
    "can_goto": ("goto", _yes_no),
    "can_goto_altaz": ("goto to alt/az", _yes_no),
    "can_sync": ("sync", _yes_no),
    "can_park": ("park", _yes_no),
    "can_set_park": ("set the park position", _yes_no),
    "can_pulse_guide": ("pulse guiding", _yes_no),
    "can_move_axis": ("manual motion", _axes),
    "max_axis_rate_deg_s": ("max axis rate", _rate),
    "tracking_modes": ("tracking modes", _plain),
    "can_set_site": ("set the site", _yes_no),
    "can_set_time": ("set the clock", _yes_no),
    "can_report_pier_side": ("reports the pier side", _yes_no),
    "sky_tracker_version": ("Sky Tracker version", _plain),
    "sky_commander_present": ("Sky Commander fitted", _yes_no),
    "mode": ("mode", _plain),
    "motor_versions": ("motor controllers", _versions),
}
_SECTIONS: Final = {"capabilities": "can do", "details": "details"}


def info_lines(report: dict[str, Any]) -> list[tuple[str, str]]:
    """``(label, value)`` lines; a section (``capabilities``, ``details``) gets a heading line
    with an empty value and its entries indented under it."""
    lines: list[tuple[str, str]] = []
    sections: list[tuple[str, dict[str, Any]]] = []
    for key, value in report.items():
        if isinstance(value, dict):
            sections.append((key, value))
        else:
            lines.append(_line(key, value))
    for key, values in sections:
        lines.append((_SECTIONS.get(key, key.replace("_", " ")) + ":", ""))
        lines.extend(("  " + label, text) for label, text in _entries(values))
    return lines


_SHOWN_ABOVE: Final = frozenset({"version.major", "version.minor", "version.patch"})
"""SynScan's firmware version in parts: the ``firmware`` line already says it."""
_NESTED_LABELS: Final = {"version.dialect": "reply format"}


def _entries(values: dict[str, Any], prefix: str = "") -> list[tuple[str, str]]:
    lines: list[tuple[str, str]] = []
    for key, value in values.items():
        dotted = prefix + key
        if isinstance(value, dict):
            lines.extend(_entries(value, dotted + "."))
        elif dotted not in _SHOWN_ABOVE:
            label, text = _line(key, value)
            label = _NESTED_LABELS.get(dotted, prefix.replace(".", " ").replace("_", " ") + label)
            lines.append((label, text))
    return lines


def _line(key: str, value: object) -> tuple[str, str]:
    label, show = _LABELS.get(key, (key.replace("_", " "), _plain))
    return label, show(value)
