"""The name index: exact lookup, search as you type, and suggestions for near misses."""

from __future__ import annotations

import bisect
import difflib
import re
from collections.abc import Callable, Iterable
from functools import cache

import numpy as np
import numpy.typing as npt

from scopelink.astro.catalog.deepsky import load_deep_sky
from scopelink.astro.catalog.entries import CatalogEntry, Prominence
from scopelink.astro.catalog.names import confusable_variants, name_key
from scopelink.astro.catalog.objects import CatalogObject, SearchMatch, UnknownObjectError
from scopelink.astro.catalog.solar_system import load_solar_system
from scopelink.astro.catalog.stars import hipparcos_star, load_named_stars
from scopelink.astro.site import Site
from scopelink.astro.timescales import ScalarTime

__all__ = ["Catalogue", "default_catalogue"]

_UNKNOWN_MAGNITUDE = 30.0
_SUGGESTION_CUTOFF = 0.6
_SUGGESTION_LENGTH_SLACK = 2
_HIP_KEY = re.compile(r"^HIP(\d{1,7})$")

Resolver = Callable[[str], CatalogEntry | None]
"""Finds an entry the index does not hold, from its name key (e.g. any ``HIP n``)."""


class Catalogue:
    """Objects by name: every alias of every entry is a key (see :func:`name_key`).

    Where two entries claim one key, the more prominent (then brighter) entry keeps it.
    """

    def __init__(self, entries: Iterable[CatalogEntry], resolver: Resolver | None = None) -> None:
        ordered = sorted(
            entries,
            key=lambda e: (e.prominence, _magnitude_or_faint(e.magnitude)),
        )
        self._resolver = resolver
        self._by_key: dict[str, tuple[CatalogEntry, str]] = {}
        for entry in ordered:
            for text in (entry.name, *entry.aliases):
                key = name_key(text)
                if key:
                    self._by_key.setdefault(key, (entry, text))
        self._keys = sorted(self._by_key)
        entry_rank = {id(entry): rank for rank, entry in enumerate(ordered)}
        self._ranks = np.array(
            [entry_rank[id(self._by_key[key][0])] for key in self._keys], dtype=np.int64
        )
        self._well_known_keys = [
            key for key in self._keys if self._by_key[key][0].prominence <= Prominence.CALDWELL
        ]

    def __len__(self) -> int:
        return len({id(entry) for entry, _ in self._by_key.values()})

    def find(self, name: str) -> CatalogEntry:
        """The entry called ``name``, or :class:`UnknownObjectError` with suggestions."""
        key = name_key(name)
        found = self._by_key.get(key)
        if found is not None:
            return found[0]
        resolved = self._resolver(key) if self._resolver is not None and key else None
        if resolved is not None:
            return resolved
        raise UnknownObjectError(name, self.suggestions(name))

    def lookup(self, name: str, t: ScalarTime, site: Site | None = None) -> CatalogObject:
        """The object called ``name`` with its astrometric J2000 position at ``t``.

        ``site`` makes solar-system positions topocentric (the Moon moves by up to ~1°).
        """
        entry = self.find(name)
        ra, dec, distance = entry.position.astrometric(t, site)
        distance_au = float(distance)
        return CatalogObject(
            name=entry.name,
            aliases=entry.aliases,
            kind=entry.kind,
            type_description=entry.type_description,
            ra_hours=float(ra),
            dec_deg=float(dec),
            magnitude=entry.magnitude,
            distance_au=None if np.isnan(distance_au) else distance_au,
            constellation=entry.constellation,
        )

    def search(self, prefix: str, limit: int = 10) -> list[SearchMatch]:
        """Up to ``limit`` objects with a name starting with ``prefix``, best first.

        An exact name comes first; then the Sun, Moon and planets, named stars and objects,
        Caldwell, NGC/IC, the rest; brighter first within each tier. Each object appears once.
        """
        key = name_key(prefix)
        if not key or limit <= 0:
            return []
        low = bisect.bisect_left(self._keys, key)
        high = bisect.bisect_left(self._keys, key + "~", lo=low)
        # Rank, then key order: a unique score, so partial selection is deterministic.
        scores = self._ranks[low:high] * len(self._keys) + np.arange(high - low)
        exact = [low] if low < high and self._keys[low] == key else []
        wanted = limit * 4  # objects have several keys: take more, then fewer after dedup
        while True:
            matches = self._distinct_matches(exact + _smallest(scores, wanted, low), limit)
            if len(matches) == limit or wanted >= len(scores):
                return matches
            wanted *= 4

    def _distinct_matches(self, positions: list[int], limit: int) -> list[SearchMatch]:
        matches: list[SearchMatch] = []
        seen: set[int] = set()
        for position in positions:
            entry, text = self._by_key[self._keys[position]]
            if id(entry) in seen:
                continue
            seen.add(id(entry))
            matches.append(
                SearchMatch(
                    name=entry.name,
                    matched=text,
                    kind=entry.kind,
                    type_description=entry.type_description,
                    magnitude=entry.magnitude,
                )
            )
            if len(matches) == limit:
                break
        return matches

    def suggestions(self, name: str, limit: int = 5) -> tuple[str, ...]:
        """Names close to ``name``: digit look-alikes first ("M 3l" -> "M 31"), then difflib."""
        key = name_key(name)
        if not key:
            return ()
        found = [v for v in confusable_variants(name) if v in self._by_key]
        candidates = {
            k
            for k in self._keys
            if k[0] == key[0] and abs(len(k) - len(key)) <= _SUGGESTION_LENGTH_SLACK
        }
        candidates.update(self._well_known_keys)
        found += difflib.get_close_matches(key, candidates, n=limit * 2, cutoff=_SUGGESTION_CUTOFF)
        texts = [self._by_key[k][1] for k in found]
        return tuple(dict.fromkeys(texts))[:limit]


def _smallest(scores: npt.NDArray[np.int64], count: int, offset: int) -> list[int]:
    """Indices (plus ``offset``) of the ``count`` smallest scores, smallest first."""
    if count < len(scores):
        chosen = np.argpartition(scores, count - 1)[:count]
        ordered = chosen[np.argsort(scores[chosen])]
    else:
        ordered = np.argsort(scores)
    return [offset + int(i) for i in ordered]


def _magnitude_or_faint(magnitude: float | None) -> float:
    return _UNKNOWN_MAGNITUDE if magnitude is None else magnitude


def _resolve_hipparcos(key: str) -> CatalogEntry | None:
    match = _HIP_KEY.match(key)
    return hipparcos_star(int(match.group(1))) if match else None


@cache
def default_catalogue() -> Catalogue:
    """The offline catalogue: solar system, named stars, any HIP number, OpenNGC. Built once."""
    return Catalogue(
        [*load_solar_system(), *load_named_stars(), *load_deep_sky()],
        resolver=_resolve_hipparcos,
    )
