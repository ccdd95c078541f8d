"""Catalogue records before a time is chosen: names, kind, and how to find the position."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from scopelink.astro._arrays import FloatArray
from scopelink.astro.catalog.objects import ObjectKind
from scopelink.astro.site import Site
from scopelink.astro.timescales import TimeLike, tt_pair

__all__ = ["CatalogEntry", "FixedPosition", "PositionSource", "Prominence", "pretty_designation"]


class Prominence:
    """Ranking tiers for search results: lower comes first."""

    SOLAR_SYSTEM = 0
    NAMED = 1  # named stars, Messier objects, deep-sky common names
    CALDWELL = 2
    NGC_IC = 3
    OTHER = 4


class PositionSource(Protocol):
    """Astrometric J2000 RA (h), Dec (deg) and distance (au, NaN if unknown) at times ``t``."""

    def astrometric(
        self, t: TimeLike, site: Site | None
    ) -> tuple[FloatArray, FloatArray, FloatArray]: ...


@dataclass(frozen=True, slots=True)
class FixedPosition:
    """A position that does not change over the years that matter here (deep-sky objects)."""

    ra_hours: float
    dec_deg: float

    def astrometric(
        self, t: TimeLike, site: Site | None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The fixed position, broadcast to the shape of ``t``."""
        shape = tt_pair(t)[0].shape
        return (
            np.full(shape, self.ra_hours),
            np.full(shape, self.dec_deg),
            np.full(shape, np.nan),
        )


@dataclass(frozen=True, slots=True)
class CatalogEntry:
    """One object of the catalogue; ``aliases`` never repeats ``name``."""

    name: str
    aliases: tuple[str, ...]
    kind: ObjectKind
    type_description: str
    magnitude: float | None
    constellation: str | None
    position: PositionSource
    prominence: int


_DESIGNATION = re.compile(r"^([A-Za-z]+)0*(\d+)(.*)$")


def pretty_designation(compact: str) -> str:
    """``"NGC0224"`` -> ``"NGC 224"``, ``"M031"`` -> ``"M 31"``; other text is returned as is."""
    match = _DESIGNATION.match(compact)
    if match is None:
        return compact
    prefix, number, rest = match.groups()
    return f"{prefix} {number}{rest}"
