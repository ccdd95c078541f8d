"""The offline object catalogue: goto by name with no network.

Deep-sky objects from OpenNGC (Messier, NGC, IC, Caldwell, common names), named bright stars and
every Hipparcos star (``HIP n``) with proper motion, and the Sun, Moon and planets from JPL DE421.
Names are case-, space- and zero-padding-insensitive; unknown names raise
:class:`UnknownObjectError` with suggestions. Positions are astrometric J2000 (ICRS) at the asked
time: feed them to :func:`scopelink.astro.j2000_to_apparent` / ``j2000_to_observed``. The data
loads on first use (under a second) and is cached. See ``docs/catalog.md``.
"""

from scopelink.astro.catalog.entries import CatalogEntry, PositionSource
from scopelink.astro.catalog.index import Catalogue, default_catalogue
from scopelink.astro.catalog.names import name_key
from scopelink.astro.catalog.objects import (
    CatalogObject,
    ObjectKind,
    SearchMatch,
    UnknownObjectError,
)
from scopelink.astro.catalog.riseset import (
    STANDARD_HORIZON_DEG,
    SUN_MOON_HORIZON_DEG,
    RiseTransitSet,
    Target,
    is_up,
    rise_transit_set,
)
from scopelink.astro.catalog.solar_system import EphemerisRangeError
from scopelink.astro.site import Site
from scopelink.astro.timescales import ScalarTime

__all__ = [
    "STANDARD_HORIZON_DEG",
    "SUN_MOON_HORIZON_DEG",
    "CatalogEntry",
    "CatalogObject",
    "Catalogue",
    "EphemerisRangeError",
    "ObjectKind",
    "PositionSource",
    "RiseTransitSet",
    "SearchMatch",
    "Target",
    "UnknownObjectError",
    "default_catalogue",
    "find",
    "is_up",
    "lookup",
    "name_key",
    "rise_transit_set",
    "search",
]


def find(name: str) -> CatalogEntry:
    """The catalogue entry called ``name`` (its position source works on arrays of times)."""
    return default_catalogue().find(name)


def lookup(name: str, t: ScalarTime, site: Site | None = None) -> CatalogObject:
    """The object called ``name`` with its astrometric J2000 position at ``t``.

    ``site`` makes solar-system positions topocentric. Raises :class:`UnknownObjectError`
    (with suggestions) for unknown names and :class:`EphemerisRangeError` for solar-system
    bodies outside DE421 (1899-12-04 to 2200-02-01).
    """
    return default_catalogue().lookup(name, t, site)


def search(prefix: str, limit: int = 10) -> list[SearchMatch]:
    """Up to ``limit`` objects whose name or alias starts with ``prefix``, best first."""
    return default_catalogue().search(prefix, limit)
