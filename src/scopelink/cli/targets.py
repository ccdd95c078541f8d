"""What a TARGET on the command line means: a catalogue name, or coordinates.

Coordinates are two angles, given as two arguments or one quoted string: RA then Dec
(``"5.5 -5.4"``, ``"05:35:17 -05:23:28"``, ``"5h35m17s -5°23'28\""``,
``"5 35 17 -5 23 28"``), or with ``--altaz`` altitude then azimuth in degrees. Anything whose
words do not all look like angles is a catalogue name (``M31``, ``"HIP 91262"``, ``Vega``).
"""

from __future__ import annotations

import argparse
import re
from dataclasses import dataclass
from typing import Final

from scopelink.astro import parse_degrees, parse_hours
from scopelink.cli.errors import CommandError

__all__ = ["AltAz", "Named", "RaDec", "Target", "accept_negative_values", "parse_target"]

_ANGLE_WORD: Final = re.compile(r"^[+-]?[0-9][0-9.:hmsd°'\"′″]*$")
_NEGATIVE_VALUE: Final = re.compile(r"^-[0-9][0-9.:hmsdx°'\"′″ ]*$")


def accept_negative_values(parser: argparse.ArgumentParser) -> None:
    """Let ``parser`` take ``-05:23:28``, ``-5°23'`` or a rate ``-16x`` as a positional argument.

    argparse reads any word starting with ``-`` as an option unless it looks like a negative
    *number*; a sexagesimal declination does not, so ``goto 05:35:17 -05:23:28`` would fail with
    "unrecognized arguments". argparse has no public hook for this: widening its (private, but
    stable since Python 3.2) negative-number pattern is the smallest fix. None of our options
    starts with a digit, so nothing else changes.
    """
    parser._negative_number_matcher = _NEGATIVE_VALUE


@dataclass(frozen=True, slots=True)
class Named:
    """An object of the offline catalogue."""

    name: str


@dataclass(frozen=True, slots=True)
class RaDec:
    """J2000 right ascension (hours) and declination (degrees)."""

    ra_hours: float
    dec_deg: float


@dataclass(frozen=True, slots=True)
class AltAz:
    """Observed altitude and azimuth (degrees; North = 0, East = 90), given with ``--altaz``."""

    alt_deg: float
    az_deg: float


Target = Named | RaDec | AltAz


def parse_target(words: list[str], *, altaz: bool = False) -> Target:
    """Read TARGET from its command-line words (see the module docstring)."""
    text = " ".join(words).strip()
    if not text:
        raise CommandError("no target given", "give a name (M31, Vega) or 'RA DEC'")
    tokens = text.split()
    looks_like_angles = all(_ANGLE_WORD.match(token) for token in tokens)
    if altaz or looks_like_angles:
        if not looks_like_angles or len(tokens) < 2:
            raise _not_two_angles(text, altaz)
        return _split_angles(text, tokens, altaz)
    return Named(" ".join(tokens))


def _not_two_angles(text: str, altaz: bool, why: str = "") -> CommandError:
    what = "ALT AZ in degrees" if altaz else "RA DEC"
    example = "45 180" if altaz else "05:35:17 -05:23:28"
    return CommandError(
        f"cannot read {text!r} as two angles{why}", f"give {what}, e.g. '{example}'"
    )


def _split_angles(text: str, tokens: list[str], altaz: bool) -> RaDec | AltAz:
    """The one way to cut the words into two angles: where the second carries a sign, else in
    half, else the only cut that reads; several readable cuts and no sign are ambiguous."""
    first_parser = parse_degrees if altaz else parse_hours
    kind = AltAz if altaz else RaDec
    readings: dict[int, RaDec | AltAz] = {}
    for cut in range(1, len(tokens)):
        try:
            first = first_parser(" ".join(tokens[:cut]))
            second = parse_degrees(" ".join(tokens[cut:]))
        except ValueError:
            continue
        readings[cut] = kind(first, second)
    signed = [cut for cut in readings if tokens[cut][0] in "+-"]
    if len(signed) == 1:
        return readings[signed[0]]
    if len(tokens) % 2 == 0 and len(tokens) // 2 in readings:
        return readings[len(tokens) // 2]
    if len(readings) == 1:
        return next(iter(readings.values()))
    if readings:
        raise _not_two_angles(text, altaz, ": ambiguous (give the second a sign, or use colons)")
    raise _not_two_angles(text, altaz)
