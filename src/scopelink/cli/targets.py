"""What a TARGET on the command line means: a catalogue name, or coordinates.

Coordinates are two angles, given as two arguments or one quoted string: RA then Dec
(``"5.5 -5.4"``, ``"05:35:17 -05:23:28"``, ``"5h35m17s -5°23'28\""``,
``"5 35 17 -5 23 28"``), or with ``--altaz`` altitude then azimuth in degrees. Anything whose
words do not all look like angles is a catalogue name (``M31``, ``"HIP 91262"``, ``Vega``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Final

from scopelink.astro import parse_degrees, parse_hours
from scopelink.cli.errors import CommandError

__all__ = ["Coordinates", "Named", "Target", "parse_target"]

_ANGLE_WORD: Final = re.compile(r"^[+-]?[0-9][0-9.:hmsd°'\"′″]*$")


@dataclass(frozen=True, slots=True)
class Named:
    """An object of the offline catalogue."""

    name: str


@dataclass(frozen=True, slots=True)
class Coordinates:
    """Two angles: J2000 RA (hours) and Dec (degrees), or observed Alt and Az (degrees)."""

    first: float
    second: float
    altaz: bool = False


Target = Named | Coordinates


def parse_target(words: list[str], *, altaz: bool = False) -> Target:
    """Read TARGET from its command-line words (see the module docstring)."""
    text = " ".join(words).strip()
    if not text:
        raise CommandError("no target given", "give a name (M31, Vega) or 'RA DEC'")
    tokens = text.split()
    looks_like_angles = all(_ANGLE_WORD.match(token) for token in tokens)
    if altaz or looks_like_angles:
        if not (looks_like_angles and len(tokens) in (2, 4, 6)):
            what = "ALT AZ in degrees" if altaz else "RA DEC"
            raise CommandError(
                f"cannot read {text!r} as two angles",
                f"give {what}, e.g. '{'45 180' if altaz else '05:35:17 -05:23:28'}'",
            )
        half = len(tokens) // 2
        first_text, second_text = " ".join(tokens[:half]), " ".join(tokens[half:])
        try:
            if altaz:
                return Coordinates(parse_degrees(first_text), parse_degrees(second_text), True)
            return Coordinates(parse_hours(first_text), parse_degrees(second_text))
        except ValueError as error:
            raise CommandError(f"cannot read {text!r}: {error}") from None
    return Named(text)
