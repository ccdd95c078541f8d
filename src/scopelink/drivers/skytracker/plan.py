"""A night's list for the Sky Commander's memory: objects by name or J2000 RA/Dec, one a line.

Format (``docs/drivers-skytracker.md``, "Plan files")::

    # comments and blank lines are ignored
    M 31                               a catalogue name: next slot
    @12 NGC 7000                       '@NN' puts it in slot NN (00-58); the next line takes 13
    05:35:17 -05:23:28 = C/2023 A3 21h a J2000 RA (hours) and Dec (degrees), named after '='
    Vega = the first of the night      a name may be relabelled too

Lines without a slot take the slot after the previous line's (the first: ``--from``, default
00). Every line is checked before anything is sent: an unknown name, an unreadable position, a
slot outside 00-58 or used twice is a :class:`PlanError` naming the line, and nothing is written.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from datetime import datetime

from scopelink.astro import Site, parse_degrees, parse_hours
from scopelink.astro.catalog import EphemerisRangeError, UnknownObjectError, lookup
from scopelink.mount import SunAvoidanceError

from .memory import SLOT_COUNT, SlotEntry, check_away_from_sun

__all__ = ["PlanError", "PlanItem", "entries_for", "parse_plan", "resolve_words"]

_SLOT = re.compile(r"^@(\d{1,2})\s+(.*)$")


class PlanError(ValueError):
    """A plan line (or argument) that cannot be stored; the message names it."""


@dataclass(frozen=True, slots=True)
class PlanItem:
    """One line of a plan: a catalogue name or coordinates, an optional slot and label."""

    where: str
    """``line 3`` or ``argument 2``: what error messages name."""
    slot: int | None
    name: str | None
    ra_j2000_hours: float | None = None
    dec_j2000_deg: float | None = None
    label: str = ""


def _coordinates(text: str) -> tuple[float, float] | None:
    tokens = text.split()
    if len(tokens) != 2 or not all(re.match(r"^[+-]?[0-9]", token) for token in tokens):
        return None
    try:
        ra, dec = parse_hours(tokens[0]), parse_degrees(tokens[1])
    except ValueError:
        return None
    if not (0.0 <= ra < 24.0 and -90.0 <= dec <= 90.0):
        return None
    return ra, dec


def parse_line(text: str, where: str) -> PlanItem | None:
    """One plan line (None for a blank or comment line)."""
    text = text.split("#", 1)[0].strip()
    if not text:
        return None
    slot = None
    match = _SLOT.match(text)
    if match is not None:
        slot = int(match.group(1))
        text = match.group(2).strip()
    elif text.startswith("@"):
        raise PlanError(f"{where}: a slot is '@NN' then the object, e.g. '@12 M 31'")
    what, _, label = text.partition("=")
    what, label = what.strip(), label.strip()
    if not what:
        raise PlanError(f"{where}: no object before '='")
    if re.match(r"^[+-]?[0-9]", what):
        coordinates = _coordinates(what)
        if coordinates is None:
            raise PlanError(
                f"{where}: cannot read {what!r} as J2000 'RA DEC' (e.g. '05:35:17 -05:23:28' "
                "or '5.588 -5.391')"
            )
        return PlanItem(where, slot, None, *coordinates, label=label or what)
    return PlanItem(where, slot, what, label=label)


def parse_plan(text: str) -> list[PlanItem]:
    """Every object line of a plan file; :class:`PlanError` names the first bad line."""
    items = []
    for number, line in enumerate(text.splitlines(), start=1):
        item = parse_line(line, f"line {number}")
        if item is not None:
            items.append(item)
    if not items:
        raise PlanError("the plan holds no object")
    return items


def resolve_words(words: Sequence[str], when: datetime, site: Site) -> list[PlanItem]:
    """Command-line objects: ``M 31 "NGC 7000" Vega``. Each catalogue name is the longest run of
    words (up to 4) that the catalogue knows, so ``M 31`` and ``M31`` both work; a quoted
    ``"RA DEC"`` is coordinates."""
    items: list[PlanItem] = []
    index = 0
    while index < len(words):
        where = f"argument {index + 1} ({words[index]!r})"
        item = parse_line(words[index], where)
        if item is None or item.name is None:
            if item is not None:
                items.append(item)
            index += 1
            continue
        for end in range(min(len(words), index + 4), index, -1):
            name = " ".join(words[index:end])
            try:
                lookup(name, when, site)
            except UnknownObjectError:
                continue
            items.append(PlanItem(where, item.slot, name, label=item.label))
            index = end
            break
        else:
            items.append(item)  # unknown: entries_for() reports it with suggestions
            index += 1
    return items


def entries_for(
    items: Iterable[PlanItem],
    *,
    start: int,
    when: datetime,
    site: Site,
    sun_avoidance_deg: float,
) -> list[SlotEntry]:
    """Slots and J2000 positions (names looked up for ``when``) for every item, checked whole."""
    if not 0 <= start < SLOT_COUNT:
        raise PlanError(f"--from {start}: the slots are 00-{SLOT_COUNT - 1:02d}")
    entries: list[SlotEntry] = []
    used: dict[int, str] = {}
    following = start
    for item in items:
        slot = following if item.slot is None else item.slot
        if not 0 <= slot < SLOT_COUNT:
            raise PlanError(
                f"{item.where}: slot {slot} is past the last one (58): the Sky Commander holds "
                f"{SLOT_COUNT} objects"
            )
        if slot in used:
            raise PlanError(f"{item.where}: slot {slot:02d} is already taken by {used[slot]}")
        used[slot] = item.where
        following = slot + 1
        if item.name is not None:
            try:
                found = lookup(item.name, when, site)
            except (UnknownObjectError, EphemerisRangeError) as error:
                raise PlanError(f"{item.where}: {error}") from None
            ra, dec, label = found.ra_hours, found.dec_deg, item.label or found.name
        else:
            assert item.ra_j2000_hours is not None
            assert item.dec_j2000_deg is not None
            ra, dec, label = item.ra_j2000_hours, item.dec_j2000_deg, item.label
        try:
            check_away_from_sun(label, ra, dec, when, sun_avoidance_deg)
        except SunAvoidanceError as error:
            raise PlanError(f"{item.where}: {error}") from None
        entries.append(SlotEntry(slot, label, ra % 24.0, dec))
    return entries
