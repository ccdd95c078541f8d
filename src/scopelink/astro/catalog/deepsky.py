"""Deep-sky objects from OpenNGC (NGC, IC, Messier, Caldwell and addenda) via ``pyongc``.

``pyongc`` ships OpenNGC as an SQLite file; reading it directly (read-only) builds every record in
one query instead of one ``pyongc.Dso`` per object. Positions are J2000 (ICRS) in radians.
"""

from __future__ import annotations

import math
import re
import sqlite3
from collections import defaultdict
from typing import Any

import pyongc

from scopelink.astro.catalog.entries import (
    CatalogEntry,
    FixedPosition,
    Prominence,
    pretty_designation,
)
from scopelink.astro.catalog.objects import ObjectKind

__all__ = ["load_deep_sky", "load_deep_sky_shapes"]

# Identifiers that name a position rather than an object ("2MASX J00424433+4116074") or that
# nobody types at a telescope; they would only crowd the search.
_UNTYPED_IDENTIFIER = re.compile(r"\bJ ?\d|^IRAS\b|^2MAS|^SDSS\b|^WDS\b")
_MAIN_CATALOGUES = ("NGC", "IC", "C0")
_CALDWELL = re.compile(r"^C 0*(\d+)$")

_QUERY = """
SELECT objects.name, objects.type, objTypes.typedesc, ra, dec, const, vmag, bmag,
       messier, ngc, ic, identifiers, commonnames
FROM objects JOIN objTypes ON objects.type = objTypes.type
"""


_SHAPE_QUERY = "SELECT name, majax, minax, pa FROM objects WHERE majax IS NOT NULL"


def _rows(query: str) -> list[tuple[Any, ...]]:
    connection = sqlite3.connect(f"file:{pyongc.DBPATH}?mode=ro", uri=True)
    try:
        return connection.execute(query).fetchall()
    finally:
        connection.close()


def _split(field: str | None) -> list[str]:
    return [item.strip() for item in (field or "").split(",") if item.strip()]


def _cross_ids(ngc: str | None, ic: str | None) -> list[str]:
    return [f"NGC{n}" for n in _split(ngc)] + [f"IC{n}" for n in _split(ic)]


def load_deep_sky() -> list[CatalogEntry]:
    """Every OpenNGC object with a position, duplicates folded into their main record."""
    rows = _rows(_QUERY)
    duplicate_names: defaultdict[str, list[str]] = defaultdict(list)
    messier_owner: dict[str, str] = {}
    for name, kind, _, _, _, _, _, _, messier, ngc, ic, *_ in rows:
        if kind == "Dup":
            targets = _cross_ids(ngc, ic) or ([f"M{messier}"] if messier else [])
            for target in targets:
                duplicate_names[target].append(name)
        elif messier:
            messier_owner[f"M{messier}"] = name
    for target in [t for t in duplicate_names if t in messier_owner]:
        duplicate_names[messier_owner[target]].extend(duplicate_names.pop(target))

    entries = []
    for (
        name,
        kind,
        description,
        ra,
        dec,
        constellation,
        vmag,
        bmag,
        messier,
        ngc,
        ic,
        identifiers,
        common_names,
    ) in rows:
        if kind in ("Dup", "NonEx") or ra is None or dec is None:
            continue
        designation = pretty_designation(name)
        others = [pretty_designation(n) for n in (*_cross_ids(ngc, ic), *duplicate_names[name])]
        caldwell = []
        extra = []
        for identifier in _split(identifiers):
            match = _CALDWELL.match(identifier)
            if match:
                caldwell.append(f"C {match.group(1)}")
            elif not _UNTYPED_IDENTIFIER.search(identifier):
                extra.append(identifier)
        common = _split(common_names)
        # Outside Messier, NGC, IC and Caldwell a common name beats "ESO 56-115" or "B 33".
        by_common_name = bool(common) and not messier and not name.startswith(_MAIN_CATALOGUES)
        names = [
            *([f"M {int(messier)}"] if messier else []),
            *(common[:1] if by_common_name else []),
            designation,
            *caldwell,
            *common,
            *others,
            *extra,
        ]
        unique = list(dict.fromkeys(names))
        if messier or common_names:
            prominence = Prominence.NAMED
        elif caldwell or name.startswith("C0"):
            prominence = Prominence.CALDWELL
        elif name.startswith(("NGC", "IC")):
            prominence = Prominence.NGC_IC
        else:
            prominence = Prominence.OTHER
        magnitude = vmag if vmag is not None else bmag
        entries.append(
            CatalogEntry(
                name=unique[0],
                aliases=tuple(unique[1:]),
                kind=ObjectKind.DEEP_SKY,
                type_description=description,
                magnitude=magnitude,
                constellation=constellation or None,
                position=FixedPosition(math.degrees(ra) / 15.0, math.degrees(dec)),
                prominence=prominence,
            )
        )
    return entries


def load_deep_sky_shapes() -> dict[str, tuple[float, float | None, float | None]]:
    """The apparent size of every OpenNGC object that has one, by designation (``"NGC 224"``,
    as an alias of :func:`load_deep_sky`'s entries): major and minor axis in arcminutes and the
    position angle of the major axis in degrees east of north (None where unknown)."""
    return {
        pretty_designation(name): (float(major), _float(minor), _float(angle))
        for name, major, minor, angle in _rows(_SHAPE_QUERY)
    }


def _float(value: float | None) -> float | None:
    return None if value is None else float(value)
