"""The typed results of the catalogue: objects, search matches and the not-found error."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

__all__ = ["CatalogObject", "ObjectKind", "SearchMatch", "UnknownObjectError"]


class ObjectKind(StrEnum):
    """What sort of thing an object is; deep-sky objects say more in ``type_description``."""

    STAR = "star"
    DEEP_SKY = "deep-sky"
    SUN = "sun"
    MOON = "moon"
    PLANET = "planet"
    DWARF_PLANET = "dwarf planet"

    @property
    def is_solar_system(self) -> bool:
        """Whether the position moves with the ephemeris rather than the stars."""
        return self not in (ObjectKind.STAR, ObjectKind.DEEP_SKY)


@dataclass(frozen=True, slots=True)
class CatalogObject:
    """An object found by name, with its astrometric J2000 (ICRS) position at the asked time.

    ``ra_hours``/``dec_deg`` are where a J2000 mount should point: proper motion applied to the
    date for stars, light-time corrected ephemeris positions for solar-system bodies
    (topocentric when a site was given), no aberration, deflection or refraction (the frame
    conversions of :mod:`scopelink.astro` add those). ``distance_au`` is known for solar-system
    bodies only; ``magnitude`` is visual (V) where the catalogue has it.
    """

    name: str
    aliases: tuple[str, ...]
    kind: ObjectKind
    type_description: str
    ra_hours: float
    dec_deg: float
    magnitude: float | None = None
    distance_au: float | None = None
    constellation: str | None = None


@dataclass(frozen=True, slots=True)
class SearchMatch:
    """One search-as-you-type result: the object's name and the alias the prefix matched."""

    name: str
    matched: str
    kind: ObjectKind
    type_description: str
    magnitude: float | None


class UnknownObjectError(LookupError):
    """No object has the given name; ``suggestions`` holds the closest names, best first."""

    def __init__(self, name: str, suggestions: tuple[str, ...]) -> None:
        self.name = name
        self.suggestions = suggestions
        hint = (
            f"; did you mean {', '.join(repr(s) for s in suggestions)}?"
            if suggestions
            else "; try a Messier, NGC, IC or Caldwell number, a star name, 'HIP n' or a planet"
        )
        super().__init__(f"no object named {name!r} in the offline catalogue{hint}")
