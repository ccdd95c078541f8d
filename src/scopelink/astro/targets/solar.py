"""The Sun, the Moon and the planets as moving targets, from the shipped DE421 catalogue.

Positions are the catalogue's astrometric J2000 places, topocentric for the site (the Moon's
parallax is up to ~1°, Mars's ~20″ at its closest), with light time: exactly what a J2000 mount
points at (docs/catalog.md, "Positions").
"""

from __future__ import annotations

from scopelink.astro._arrays import FloatArray
from scopelink.astro.catalog import ObjectKind, PositionSource, UnknownObjectError, find
from scopelink.astro.site import Site
from scopelink.astro.targets.base import MovingTarget, TargetError, TargetKind

__all__ = ["SolarSystemTarget", "solar_system_target"]

_KINDS = {
    ObjectKind.SUN: TargetKind.SUN,
    ObjectKind.MOON: TargetKind.MOON,
    ObjectKind.PLANET: TargetKind.PLANET,
    ObjectKind.DWARF_PLANET: TargetKind.PLANET,
}


class SolarSystemTarget(MovingTarget):
    """A body of the catalogue's solar system (Sun, Moon, planets, Pluto)."""

    def __init__(
        self, name: str, kind: TargetKind, site: Site | None, source: PositionSource
    ) -> None:
        super().__init__(name, kind, site)
        self._source = source

    def positions(self, jd: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
        ra, dec, _ = self._source.astrometric(jd, self.site)
        return ra, dec


def solar_system_target(name: str, site: Site | None) -> SolarSystemTarget:
    """The Sun, the Moon or a planet by name (any spelling the catalogue takes)."""
    try:
        entry = find(name)
    except UnknownObjectError as error:
        raise TargetError(str(error)) from None
    kind = _KINDS.get(entry.kind)
    if kind is None:
        raise TargetError(
            f"{entry.name} is not a body of the solar system: it keeps its place among the stars, "
            "so sidereal tracking follows it (scopelink goto it)"
        )
    return SolarSystemTarget(entry.name, kind, site, entry.position)
